// The training log's row is declared once (EpochLog::Columns): the CSV log
// and the checkpoint's exact log are the same list of columns.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "aia/learning/trainer.h"

namespace aia {
namespace {

EpochLog Example() {
  EpochLog e;
  e.epoch = 3;
  e.lr = 1.0 / 30000.0;
  e.train_loss = 0.5123456789;
  e.train_acc = 0.75;
  e.val_loss = std::numeric_limits<double>::quiet_NaN();
  e.val_acc = 0.1;
  e.val_acc_useful = std::numeric_limits<double>::quiet_NaN();
  e.samples = 1234;
  e.seconds = 12.345;
  return e;
}

TEST(TrainLogTest, TheCsvLogAndTheCheckpointLogShareOneDeclaration) {
  EXPECT_EQ(CsvHeader<EpochLog>(),
            "epoch,lr,train_loss,train_acc,val_loss,val_acc,val_acc_useful,"
            "samples,seconds");
  const EpochLog e = Example();
  // What plot_training.py reads: 6 significant digits for lr, 6 decimals,
  // no validation figure as an empty cell.
  EXPECT_EQ(CsvLine(e),
            "3,3.33333e-05,0.512346,0.750000,,0.100000,,1234,12.35\n");
  // The checkpoint's log reads back exactly, NaN included.
  const std::string exact = ExactLine(e);
  EpochLog back;
  ASSERT_TRUE(ParseExactLine(exact.substr(0, exact.size() - 1), &back));
  EXPECT_EQ(back.epoch, 3);
  EXPECT_EQ(back.lr, e.lr);
  EXPECT_EQ(back.train_loss, e.train_loss);
  EXPECT_TRUE(std::isnan(back.val_loss));
  EXPECT_EQ(back.val_acc, 0.1);
  EXPECT_TRUE(std::isnan(back.val_acc_useful));
  EXPECT_EQ(back.samples, 1234);
  EXPECT_EQ(back.seconds, 12.345);
  // An older build's checkpoint log (17 digits, space-separated) reads too.
  ASSERT_TRUE(
      ParseExactLine("3 3.3333333333333335e-05 0.51234567890000002 0.75 nan "
                     "0.10000000000000001 "
                     "-nan 1234 12.345000000000001",
                     &back));
  EXPECT_EQ(back.lr, e.lr);
  EXPECT_EQ(back.train_loss, e.train_loss);
  EXPECT_TRUE(std::isnan(back.val_acc_useful));
  EXPECT_EQ(back.seconds, 12.345);
}

}  // namespace
}  // namespace aia
