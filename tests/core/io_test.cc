// Output files: an atomic write never replaces what is not a regular file.
#include "aia/core/io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

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
                "cannot write '" + path + "': it is " +
                    (name == "folder" ? std::string("a folder")
                                      : std::string("a named pipe (FIFO)")) +
                    ", not a regular file; give a file's path");
    }
    EXPECT_TRUE(name == "folder" ? fs::is_directory(path) : fs::is_fifo(path));
  }
  // Nothing else was left behind (no temporary file).
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 3);
  fs::remove_all(dir);
}

// Issue 37: a FIFO where aia reads or writes blocked the open for ever (one
// Ctrl-C did not end it). Readers and writers open without blocking and
// name what the path is; lines are read with a cap, so a file of gigabytes
// of NULs is an error, not gigabytes of memory.
TEST(IoTest, NothingBlocksOnAFifoAndLinesAreCapped) {
  const std::string dir = testing::MakeTempDir("aia_io_");
  const std::string pipe = dir + "/pipe";
  ASSERT_EQ(::mkfifo(pipe.c_str(), 0644), 0);
  EXPECT_EQ(NonRegularKind(pipe), "a named pipe (FIFO)");
  EXPECT_EQ(NonRegularKind(dir), "a folder");
  EXPECT_EQ(NonRegularKind("/dev/null"), "a character device");
  EXPECT_EQ(NonRegularKind(dir + "/none"), "");
  for (const std::string& path : {pipe, dir, std::string("/dev/zero")}) {
    try {
      ReadFile(path, 100);
      ADD_FAILURE() << path << " was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("not a regular file"),
                std::string::npos)
          << e.what();
    }
    EXPECT_THROW(LineReader(path, 100), std::runtime_error) << path;
  }
  EXPECT_EQ(OutputFileProblem(pipe, "written into the output folder"),
            "cannot write '" + pipe +
                "' (written into the output folder): it is a named pipe "
                "(FIFO), not a regular file; remove it or give another path");
  EXPECT_EQ(OutputFileProblem(dir + "/new.txt"), "");
  // A FIFO at an atomic writer's temporary name: refused, not waited on.
  const std::string out = dir + "/out.txt";
  ASSERT_EQ(::mkfifo(TemporaryPath(out).c_str(), 0644), 0);
  EXPECT_THROW(WriteFileAtomic(out, "x"), std::runtime_error);
  EXPECT_FALSE(fs::exists(out));

  // Lines: the last may lack its newline; none may pass the cap.
  {
    LineReader none(dir + "/none", 10);
    std::string line;
    EXPECT_FALSE(none.exists());
    EXPECT_FALSE(none.Next(&line));
  }
  WriteFileAtomic(dir + "/lines", "a\nbb\n\nccc");
  LineReader lines(dir + "/lines", 3);
  std::vector<std::string> read;
  for (std::string line; lines.Next(&line);) read.push_back(line);
  EXPECT_EQ(read, (std::vector<std::string>{"a", "bb", "", "ccc"}));
  WriteFileAtomic(dir + "/nuls", "ok\n" + std::string(1 << 20, '\0'));
  LineReader nuls(dir + "/nuls", 1000);
  std::string line;
  ASSERT_TRUE(nuls.Next(&line));
  EXPECT_EQ(line, "ok");
  try {
    nuls.Next(&line);
    ADD_FAILURE() << "a line of a MiB was read";
  } catch (const LineTooLong& e) {
    EXPECT_EQ(std::string(e.what()), "line 2 is longer than 1000 bytes");
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
