// Output files: an atomic write never replaces what is not a regular file.
#include "aia/core/io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>

#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

TEST(IoTest, AtomicWritesReplaceOnlyRegularFiles) {
  const std::string dir = testing::MakeTempDir("aia_io_");
  // A new path and an existing file are written (and replaced).
  EXPECT_NO_THROW(CheckReplaceableFile(dir + "/new.txt"));
  WriteFileAtomic(dir + "/new.txt", "one");
  WriteFileAtomic(dir + "/new.txt", "two");
  EXPECT_EQ(testing::ReadFile(dir + "/new.txt"), "two");
  // A folder and a pipe are refused, and stay what they were.
  fs::create_directory(dir + "/folder");
  ASSERT_EQ(::mkfifo((dir + "/pipe").c_str(), 0644), 0);
  for (const std::string name : {"folder", "pipe"}) {
    const std::string path = dir + "/" + name;
    try {
      WriteFileAtomic(path, "x");
      ADD_FAILURE() << name << " was written";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()),
                "cannot write '" + path +
                    "': it exists and is not a regular file (a folder, "
                    "device or pipe); give a file's path");
    }
    EXPECT_TRUE(name == "folder" ? fs::is_directory(path) : fs::is_fifo(path));
  }
  // Nothing else was left behind (no temporary file).
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 3);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
