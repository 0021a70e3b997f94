#include "aia/core/progress.h"

#include <gtest/gtest.h>
#include <unistd.h>

namespace aia {
namespace {

// Under ctest stderr is a file or a pipe, never a terminal: the redrawn
// line is left out and the lines that stay are written whole.
TEST(ProgressLineTest, OffATerminalOnlyTheLinesThatStayAreWritten) {
  ASSERT_FALSE(::isatty(STDERR_FILENO));
  testing::internal::CaptureStderr();
  ProgressLine line(true);
  line.Update("[train] epoch 1/2  batch 1/9");
  line.Print("[train] epoch 1/2: loss 0.5");
  line.Update("[train] epoch 2/2  batch 1/9");
  line.Finish();
  line.Print("done");
  EXPECT_EQ(testing::internal::GetCapturedStderr(),
            "[train] epoch 1/2: loss 0.5\ndone\n");
}

}  // namespace
}  // namespace aia
