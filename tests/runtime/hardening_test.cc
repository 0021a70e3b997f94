// Long jobs and odd files (issue 11): kill-safety, locks on output folders,
// validated rows on resume, Ctrl-C, files that are not files, unwritable
// folders.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunAia;
using testing::RunCommand;
using testing::SourcePath;

std::string Quoted(const std::vector<std::string>& args) {
  std::string line = std::string("'") + AIA_BINARY + "'";
  for (const auto& a : args) line += " '" + a + "'";
  return line;
}

std::string WithoutWall(const std::string& csv) {
  return std::regex_replace(csv, std::regex(",[0-9.]+\n"), ",X\n");
}

// Files that AtomicFile writers leave when killed: NAME.tmp.PID.
std::vector<std::string> Temporaries(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp.") != std::string::npos)
      out.push_back(e.path().string());
  return out;
}

void ExpectOneErrorLine(const testing::CommandResult& r,
                        const std::string& part) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(part), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST(HardeningTest, ScenarioThatIsADeviceOrAPipeIsRefusedAtOnce) {
  const std::string dir = testing::MakeTempDir("aia_fifo_");
  ExpectOneErrorLine(RunAia({"run", "/dev/zero", "--out", dir, "--quiet"}),
                     "not a regular file");
  ASSERT_EQ(RunCommand("mkfifo '" + dir + "/pipe.yaml'").exit_code, 0);
  // Opening a FIFO for reading would block until a writer comes.
  const auto r = RunCommand("timeout 60 " + Quoted({"run", dir + "/pipe.yaml",
                                                    "--out", dir, "--quiet"}));
  ExpectOneErrorLine(r, "not a regular file");
  fs::remove_all(dir);
}

TEST(HardeningTest, UnwritableOutputFolderIsBadInput) {
  // /proc exists but takes no new files, even for root.
  const auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--out",
                         "/proc", "--quiet", "--max-steps", "1"});
  ExpectOneErrorLine(r, "--out: ");
}

TEST(HardeningTest, TemporaryFilesOfKilledJobsAreRemoved) {
  const std::string dir = testing::MakeTempDir("aia_tmp_");
  // PIDs above the kernel's default pid_max (4194304) never exist.
  const std::string stale = dir + "/trace.csv.tmp.999999999";
  { std::ofstream(stale) << "half a trace"; }
  const auto r =
      RunAia({"run", SourcePath("scenarios/default.yaml"), "--policy", "greedy",
              "--max-steps", "2", "--out", dir, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(Temporaries(dir).empty());
  fs::remove_all(dir);
}

// A second eval on a folder in use is refused (a lock), and Ctrl-C on the
// first writes the rows done and the summary of them, then exits 130.
TEST(HardeningTest, SecondJobOnAFolderIsRefusedAndCtrlCWritesWhatIsDone) {
  const std::string dir = testing::MakeTempDir("aia_lock_");
  const std::vector<std::string> eval = {
      "eval",   "--sizes", "2x2", "--seeds",   "2000", "--policies",
      "greedy", "--out",   dir,   "--threads", "1",    "--quiet"};
  const std::string script =
      Quoted(eval) + " >" + dir + "/first.out 2>" + dir +
      "/first.err & pid=$!\n"
      // Wait for a few rows (the lock is taken before any row).
      "for i in $(seq 600); do\n"
      "  [ $(wc -l < " +
      dir +
      "/runs.csv 2>/dev/null || echo 0) -gt 5 ] "
      "&& break; sleep 0.05; done\n" +
      Quoted(eval) + " >" + dir + "/second.out 2>" + dir +
      "/second.err; echo second=$?\n"
      "kill -INT $pid; wait $pid; echo first=$?\n";
  const auto r = RunCommand(
      "bash -c '" + std::regex_replace(script, std::regex("'"), "'\\''") + "'");
  EXPECT_NE(r.out.find("second=2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("first=130"), std::string::npos) << r.out;
  const std::string second = ReadFile(dir + "/second.err");
  EXPECT_NE(second.find("is in use by another aia job"), std::string::npos)
      << second;
  EXPECT_NE(ReadFile(dir + "/first.err").find("interrupted"),
            std::string::npos);
  // What was done is there, whole: every row parses, the summary counts it.
  const std::string runs = ReadFile(dir + "/runs.csv");
  const long rows = std::count(runs.begin(), runs.end(), '\n') - 1;
  EXPECT_GT(rows, 5);
  EXPECT_LT(rows, 2000);
  const std::string summary = ReadFile(dir + "/summary.csv");
  EXPECT_NE(summary.find("2x2,greedy," + std::to_string(rows) + ","),
            std::string::npos)
      << summary;
  EXPECT_TRUE(Temporaries(dir).empty());
  fs::remove_all(dir);
}

TEST(HardeningTest, ResumedEvalReportsAndRerunsBadRows) {
  const std::string a = testing::MakeTempDir("aia_rows_"),
                    b = testing::MakeTempDir("aia_rows_");
  const auto eval = [](const std::string& dir) {
    return RunAia({"eval", "--sizes", "2x2", "--seeds", "4", "--policies",
                   "greedy", "--out", dir, "--threads", "1", "--quiet"});
  };
  ASSERT_EQ(eval(a).exit_code, 0);
  ASSERT_EQ(eval(b).exit_code, 0);
  const std::string clean = ReadFile(a + "/runs.csv");
  // A duplicated row (both copies go), an impossible one (flowtime -500 for
  // seed 2, which replaces its row) and garbage.
  std::string lines = clean;
  const std::size_t row1 = lines.find('\n') + 1;
  const std::string first_row =
      lines.substr(row1, lines.find('\n', row1) + 1 - row1);
  std::string edited =
      std::regex_replace(lines, std::regex("\n2x2,2,greedy,[^\n]*\n"),
                         "\n2x2,2,greedy,1,-500,10,5,0.1\n");
  edited += first_row + "hello,world\n2x2,3,greedy,1,4,4,4,0.1abc\n";
  { std::ofstream(a + "/runs.csv") << edited; }
  const auto r = eval(a);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("dropped 5 rows that will run again"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("impossible flowtime -500"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("duplicate run 2x2 seed 0 greedy"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("not a row"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("2 rows already done, 2 to run"), std::string::npos)
      << r.out;
  EXPECT_EQ(WithoutWall(ReadFile(a + "/runs.csv")),
            WithoutWall(ReadFile(b + "/runs.csv")));
  EXPECT_EQ(ReadFile(a + "/summary.csv"), ReadFile(b + "/summary.csv"));
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST(HardeningTest, SigkilledEvalResumesToTheRowsOfOneRun) {
  const std::string dir = testing::MakeTempDir("aia_kill_");
  const auto args = [&](const std::string& out) {
    return std::vector<std::string>{
        "eval",         "--sizes", "2x2,3x3", "--seeds",   "6", "--policies",
        "greedy,decsb", "--out",   out,       "--threads", "2", "--quiet"};
  };
  ASSERT_EQ(RunAia(args(dir + "/whole")).exit_code, 0);
  // Killed at three moments (whatever is in flight then), then resumed.
  for (const char* after : {"1.3", "1.9", "2.6"})
    RunCommand(std::string("timeout -s KILL ") + after + " " +
               Quoted(args(dir + "/killed")));
  const auto r = RunAia(args(dir + "/killed"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(WithoutWall(ReadFile(dir + "/whole/runs.csv")),
            WithoutWall(ReadFile(dir + "/killed/runs.csv")));
  EXPECT_EQ(ReadFile(dir + "/whole/summary.csv"),
            ReadFile(dir + "/killed/summary.csv"));
  EXPECT_TRUE(Temporaries(dir).empty());
  fs::remove_all(dir);
}

TEST(HardeningTest, SigkilledTrainingResumesToTheSameModel) {
  const std::string dir = testing::MakeTempDir("aia_ktrain_");
  ASSERT_EQ(
      RunAia({"dataset", "--episodes", "30", "--size", "4x4", "--keep", "4",
              "--first-seed", "500", "--out", dir + "/data", "--quiet"})
          .exit_code,
      0);
  const auto args = [&](const std::string& out) {
    return std::vector<std::string>{
        "train",    "--data",    dir + "/data", "--out",    out,
        "--epochs", "30",        "--width",     "8",        "--window",
        "16",       "--threads", "1",           "--resume", "--quiet"};
  };
  // The same file name in two folders: a model's archive is named after it.
  fs::create_directories(dir + "/a");
  fs::create_directories(dir + "/b");
  const auto whole = RunAia(args(dir + "/a/model.pt"));
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  for (const char* after : {"1.5", "2.2", "2.9", "3.6"})
    RunCommand(std::string("timeout -s KILL ") + after + " " +
               Quoted(args(dir + "/b/model.pt")));
  const auto r = RunAia(args(dir + "/b/model.pt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The same epochs with the same losses (seconds aside), the same weights.
  const auto losses = [](const std::string& csv) {
    return std::regex_replace(csv, std::regex(",[0-9.e+-]+\n"), ",X\n");
  };
  EXPECT_EQ(losses(ReadFile(dir + "/a/model.train.csv")),
            losses(ReadFile(dir + "/b/model.train.csv")));
  EXPECT_TRUE(ReadFile(dir + "/a/model.pt") == ReadFile(dir + "/b/model.pt"));
  EXPECT_TRUE(Temporaries(dir).empty());
  fs::remove_all(dir);
}

// `aia run` stopped by Ctrl-C writes its files for the steps done.
TEST(HardeningTest, CtrlCEndsAMissionWithItsFilesWritten) {
  const std::string dir = testing::MakeTempDir("aia_int_");
  const std::string run =
      Quoted({"run", SourcePath("scenarios/default.yaml"), "--policy", "random",
              "--max-steps", "1000000", "--set",
              "mission.stop_at_success=false", "--out", dir, "--quiet"});
  const auto r = RunCommand("bash -c '" + run +
                            " & pid=$!; sleep 4; kill -INT $pid; wait $pid; "
                            "echo rc=$?'");
  EXPECT_NE(r.out.find("rc=130"), std::string::npos) << r.out << r.err;
  const std::string summary = ReadFile(dir + "/summary.json");
  EXPECT_NE(summary.find("\"interrupted\": true"), std::string::npos)
      << summary;
  EXPECT_TRUE(fs::exists(dir + "/trace.csv"));
  EXPECT_TRUE(Temporaries(dir).empty());
  fs::remove_all(dir);
}

// A full disk: one clear line naming the file, no crash. Needs a small
// tmpfs (root in a container that allows mounts); skipped elsewhere.
TEST(HardeningTest, FullDiskGivesOneClearError) {
  const std::string dir = testing::MakeTempDir("aia_full_");
  if (RunCommand("mount -t tmpfs -o size=64k tmpfs '" + dir + "'").exit_code !=
      0) {
    fs::remove_all(dir);
    GTEST_SKIP() << "cannot mount a tmpfs here";
  }
  const auto r =
      RunAia({"run", SourcePath("scenarios/default.yaml"), "--policy", "greedy",
              "--out", dir + "/out", "--quiet"});
  RunCommand("umount '" + dir + "'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("error: cannot write '" + dir + "/out/", 0), 0u)
      << r.err;
  EXPECT_NE(r.err.find("No space left on device"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
