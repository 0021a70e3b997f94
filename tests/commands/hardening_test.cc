// Long jobs and odd files (issue 11): kill-safety, locks on output folders,
// validated rows on resume, Ctrl-C, files that are not files, unwritable
// folders.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "support/test_support.h"

// The sanitizer tree (AddressSanitizer reserves terabytes of address space).
#if defined(__SANITIZE_ADDRESS__)
#define AIA_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define AIA_TEST_ASAN 1
#endif
#endif

namespace aia {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunAia;
using testing::RunCommand;
using testing::SmallDisk;
using testing::SourcePath;
using testing::Temporaries;

std::string Quoted(const std::vector<std::string>& args) {
  std::string line = std::string("'") + AIA_BINARY + "'";
  for (const auto& a : args) line += " '" + a + "'";
  return line;
}

std::string WithoutWall(const std::string& csv) {
  return std::regex_replace(csv, std::regex(",[0-9.]+\n"), ",X\n");
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

TEST(HardeningTest, AnOutputFilePathThatNamesAFolderIsRefusedBeforeWork) {
  // `--out DIR/` of a command that writes one file: plan and world solved
  // and built, then failed with exit code 1, leaving DIR made.
  const std::string dir = testing::MakeTempDir("aia_outdir_");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  for (const std::string& out : {dir + "/p/", dir + "/p/.", dir + "/p/.."}) {
    ExpectOneErrorLine(RunAia({"plan", scenario, "--out", out}),
                       "it names a folder, not a file");
    ExpectOneErrorLine(RunAia({"world", scenario, "--out", out}),
                       "it names a folder, not a file");
  }
  EXPECT_FALSE(fs::exists(dir + "/p"));
  fs::remove_all(dir);
}

TEST(HardeningTest, UnwritableOutputFolderIsBadInput) {
  // /proc exists but takes no new files, even for root.
  const auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--out",
                         "/proc", "--quiet", "--max-steps", "1"});
  ExpectOneErrorLine(r, "--out: ");
}

TEST(HardeningTest, EveryCommandRefusesAnUnwritableFolderBeforeItWorks) {
  // Each command's --out inside /proc: one error line, exit code 2, and
  // nothing done first (train used to train its epochs, then fail to save
  // with exit code 1).
  const std::string dir = testing::MakeTempDir("aia_proc_");
  ASSERT_EQ(RunAia({"dataset", "--out", dir + "/data", "--size", "2x2",
                    "--episodes", "2", "--keep", "2", "--quiet"})
                .exit_code,
            0);
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::vector<std::vector<std::string>> commands = {
      {"train", "--data", dir + "/data", "--epochs", "1", "--out",
       "/proc/model.pt", "--quiet"},
      {"dataset", "--episodes", "1", "--out", "/proc/data", "--quiet"},
      {"eval", "--sizes", "2x2", "--seeds", "1", "--out", "/proc/eval",
       "--quiet"},
      {"world", scenario, "--out", "/proc/world.xml"},
      {"plan", scenario, "--out", "/proc/plan.json"},
      {"render", scenario, "--max-steps", "1", "--out", "/proc/video.mp4",
       "--quiet"}};
  for (const std::vector<std::string>& args : commands) {
    const auto r = RunAia(args);
    ExpectOneErrorLine(r, "--out: ");
    EXPECT_EQ(r.out, "") << args[0];
  }
  fs::remove_all(dir);
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
      // Wait for a few rows, six and the header (the lock is taken before
      // any row; the second job now starts and ends in a tenth of a second,
      // so the rows counted below are the ones waited for).
      "for i in $(seq 600); do\n"
      "  [ $(wc -l < " +
      dir +
      "/runs.csv 2>/dev/null || echo 0) -gt 6 ] "
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

// One Ctrl-C delivered twice (coreutils' `timeout -s INT` signals the
// process and its process group, microseconds apart; here 1 ms) is one
// request: the job writes what is done and says so (it ended silently in 5
// of 12 runs, 143 for TERM); a second signal a moment later still ends it
// at once.
TEST(HardeningTest, ASignalDeliveredTwiceIsOneInterrupt) {
  const std::string dir = testing::MakeTempDir("aia_twice_");
  const std::vector<std::string> eval = {
      "eval",   "--sizes", "2x2", "--seeds",   "100000", "--policies",
      "greedy", "--out",   dir,   "--threads", "1",      "--quiet"};
  const auto run = [&](const std::string& signals) {
    return RunCommand("bash -c '" + Quoted(eval) + " 2>&1 & pid=$!; sleep 1; " +
                      signals + " wait $pid; echo rc=$?'");
  };
  for (int attempt = 0; attempt < 6; ++attempt) {
    const std::string sig = attempt % 2 ? "TERM" : "INT";
    // 1 ms apart: mostly delivered one after the other, not merged.
    const auto r =
        run("/usr/bin/python3 -c \"import os, signal, time; p = $pid; "
            "os.kill(p, signal.SIG" +
            sig + "); time.sleep(0.001); os.kill(p, signal.SIG" + sig + ")\";");
    EXPECT_NE(r.out.find("aia eval: interrupted"), std::string::npos)
        << sig << ": " << r.out;
    EXPECT_NE(r.out.find("rc=130"), std::string::npos) << sig << ": " << r.out;
  }
  const auto later = run("kill -INT $pid; sleep 0.3; kill -INT $pid;");
  EXPECT_NE(later.out.find("rc=130"), std::string::npos) << later.out;
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
                         "\n2x2,2,greedy,1,-500,10,5,0.0000,0,1.000,0,0,0.1\n");
  edited += first_row +
            "hello,world\n2x2,3,greedy,1,4,4,4,0.0000,0,1.000,0,0,0.1abc\n";
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
  // The same file name in two folders, so that the bytes compare whatever
  // the archive's folder is named after.
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

// The one line of an I/O failure: exit 1, the file under `dir` named.
void ExpectNoSpaceError(const testing::CommandResult& r,
                        const std::string& dir) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("error: cannot write '" + dir + "/", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("': No space left on device"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

// A full disk: one clear line naming the file, no crash. Needs a small
// tmpfs (root in a container that allows mounts); skipped elsewhere.
TEST(HardeningTest, FullDiskGivesOneClearError) {
  const SmallDisk disk;
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here";
  const auto r =
      RunAia({"run", SourcePath("scenarios/default.yaml"), "--policy", "greedy",
              "--out", disk.dir() + "/out", "--quiet"});
  ExpectNoSpaceError(r, disk.dir() + "/out");
  EXPECT_TRUE(Temporaries(disk.dir()).empty());
}

// Issue 19: `aia train` aborted with libtorch's backtrace when the model
// did not fit; `aia dataset` printed SQLite's "database or disk is full".
TEST(HardeningTest, FullDiskOnTrainAndDatasetGivesOneClearError) {
  const SmallDisk disk("8k");
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here";
  const std::string dir = testing::MakeTempDir("aia_fulltrain_");
  ASSERT_EQ(
      RunAia({"dataset", "--episodes", "6", "--size", "3x3", "--keep", "3",
              "--first-seed", "500", "--out", dir + "/data", "--quiet"})
          .exit_code,
      0);
  const auto train =
      RunAia({"train", "--data", dir + "/data", "--out",
              disk.dir() + "/m/model.pt", "--epochs", "1", "--width", "8",
              "--window", "16", "--threads", "1", "--quiet"});
  ExpectNoSpaceError(train, disk.dir() + "/m");
  EXPECT_TRUE(Temporaries(disk.dir()).empty());
  EXPECT_FALSE(fs::exists(disk.dir() + "/m/model.pt"));

  // The disk fills as the database is made (8k), or in an episode's
  // transaction (40k).
  const SmallDisk larger("40k");
  for (const std::string& d : {disk.dir() + "/d", larger.dir() + "/d"}) {
    const auto data = RunAia({"dataset", "--episodes", "40", "--size", "6x6",
                              "--keep", "10", "--out", d, "--quiet"});
    ExpectNoSpaceError(data, d);
    EXPECT_NE(data.err.find("/d/shard-0-of-1.sqlite'"), std::string::npos)
        << data.err;
    for (const auto& e : fs::directory_iterator(d))  // no journal left
      EXPECT_EQ(e.path().filename(), "shard-0-of-1.sqlite");
  }
  fs::remove_all(dir);
}

// Issue 19: an output that is an input would silently replace it. Refused
// before any work, through links and other spellings too; the input is
// left as it was.
TEST(HardeningTest, OutputThatIsAnInputIsRefused) {
  const std::string dir = testing::MakeTempDir("aia_inout_");
  const std::string yaml = dir + "/x.yaml";
  fs::copy_file(SourcePath("scenarios/default.yaml"), yaml);
  const std::string text = ReadFile(yaml);
  fs::create_symlink(yaml, dir + "/link.yaml");
  const auto refused = [&](const std::vector<std::string>& args,
                           const std::string& message) {
    const auto r = RunAia(args);
    ExpectOneErrorLine(r, message);
    EXPECT_EQ(r.err.rfind("error: command line: --out: '", 0), 0u) << r.err;
    EXPECT_EQ(ReadFile(yaml), text) << args[0];
  };
  const std::string input = "' is the input scenario; choose another path";
  refused({"plan", yaml, "--out", yaml}, input);
  refused({"plan", yaml, "--out", dir + "/link.yaml"}, input);
  refused({"world", yaml, "--out", dir + "/./x.yaml"}, input);
  refused({"world", dir + "/link.yaml", "--out", yaml}, input);
  // Files written next to the output: plan's FILE.effective.yaml, render's
  // FILE.effective.yaml and the files of `aia run` in its folder.
  fs::copy_file(yaml, dir + "/p.effective.yaml");
  refused({"plan", dir + "/p.effective.yaml", "--out", dir + "/p.json"},
          "p.effective.yaml' (written next to the plan) is the input scenario");
  refused(
      {"render", dir + "/p.effective.yaml", "--out", dir + "/p.mp4", "--quiet"},
      "p.effective.yaml' (written next to the video) is the input "
      "scenario");
  fs::create_directories(dir + "/run");
  fs::copy_file(yaml, dir + "/run/effective.yaml");
  refused(
      {"run", dir + "/run/effective.yaml", "--out", dir + "/run", "--quiet"},
      "effective.yaml' (written into the output folder) is the input "
      "scenario");
  EXPECT_FALSE(fs::exists(dir + "/run/summary.json"));
  EXPECT_FALSE(fs::exists(dir + "/p.json"));

  // Training: a dataset file, a new *.sqlite in a data folder, --init.
  ASSERT_EQ(
      RunAia({"dataset", "--episodes", "6", "--size", "3x3", "--keep", "3",
              "--first-seed", "500", "--out", dir + "/data", "--quiet"})
          .exit_code,
      0);
  const std::string shard = dir + "/data/shard-0-of-1.sqlite";
  const std::string data = ReadFile(shard);
  const std::vector<std::string> tiny = {"--epochs",  "1",        "--width",
                                         "8",         "--window", "16",
                                         "--threads", "1",        "--quiet"};
  const auto train = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "train");
    args.insert(args.end(), tiny.begin(), tiny.end());
    return RunAia(args);
  };
  auto r = train({"--data", dir + "/data", "--out", shard});
  ExpectOneErrorLine(r, "' is a dataset file of --data; choose another path");
  r = train(
      {"--data", shard, "--out", dir + "/data/../data/shard-0-of-1.sqlite"});
  ExpectOneErrorLine(r, "is a dataset file of --data");
  r = train({"--data", dir + "/data", "--out", dir + "/data/model.sqlite"});
  ExpectOneErrorLine(r, "would be read as a dataset file of --data");
  EXPECT_TRUE(ReadFile(shard) == data);
  ASSERT_EQ(train({"--data", dir + "/data", "--out", dir + "/m.pt"}).exit_code,
            0);
  const std::string model = ReadFile(dir + "/m.pt");
  // The --init model brings its network: no network flags beside it.
  r = RunAia({"train", "--data", dir + "/data", "--init", dir + "/m.pt",
              "--out", dir + "/m.pt", "--epochs", "1", "--quiet"});
  ExpectOneErrorLine(r, "'" + dir +
                            "/m.pt' is the model to start from (--init); "
                            "choose another path");
  EXPECT_TRUE(ReadFile(dir + "/m.pt") == model);
  fs::remove_all(dir);
}

// Issue 19: datasets read twice or mixed shard sets counted samples twice.
TEST(HardeningTest, DatasetsReadTwiceOrMixedShardSetsAreRefused) {
  const std::string dir = testing::MakeTempDir("aia_dup_");
  const auto dataset = [&](const std::string& out, const std::string& shard) {
    return RunAia({"dataset", "--episodes", "6", "--size", "3x3", "--keep", "3",
                   "--first-seed", "500", "--shard", shard, "--out", out,
                   "--quiet"});
  };
  ASSERT_EQ(dataset(dir + "/d", "0/1").exit_code, 0);
  const std::string shard = dir + "/d/shard-0-of-1.sqlite";
  const auto train = [&](const std::vector<std::string>& data) {
    std::vector<std::string> args = {"train"};
    for (const std::string& d : data) args.insert(args.end(), {"--data", d});
    args.insert(args.end(), {"--out", dir + "/m.pt", "--epochs", "1", "--width",
                             "8", "--window", "16", "--quiet"});
    return RunAia(args);
  };
  ExpectOneErrorLine(train({dir + "/d", dir + "/d"}),
                     "is read twice (as '" + dir + "/d' and as '" + dir +
                         "/d'): its samples would count twice");
  ExpectOneErrorLine(train({dir + "/d", shard}), "is read twice");
  ExpectOneErrorLine(train({shard, dir + "/d/../d/shard-0-of-1.sqlite"}),
                     "is read twice");
  // A copy of the same shard elsewhere holds the same episodes.
  fs::create_directories(dir + "/copy");
  fs::copy_file(shard, dir + "/copy/shard-0-of-1.sqlite");
  ExpectOneErrorLine(train({dir + "/d", dir + "/copy"}),
                     "is also in '" + shard + "' (the same recipe)");
  // `aia dataset` refuses a second shard count in a folder...
  ExpectOneErrorLine(dataset(dir + "/d", "0/2"),
                     "--shard: " + dir + "/d holds shards of a set of 1");
  // ... and `aia train` a folder that got one anyway.
  ASSERT_EQ(dataset(dir + "/two", "1/2").exit_code, 0);
  fs::copy_file(dir + "/two/shard-1-of-2.sqlite",
                dir + "/d/shard-1-of-2.sqlite");
  ExpectOneErrorLine(train({dir + "/d"}),
                     "mixes shard sets: '" + shard + "' is one of 1 shards, '" +
                         dir + "/d/shard-1-of-2.sqlite' one of 2");
  // Shards of one set written with other options (a resubmitted array task
  // with changed flags): `aia dataset` refuses to add one...
  const auto sized = [&](const std::string& out, const std::string& size,
                         const std::string& shard_of) {
    return RunAia({"dataset", "--episodes", "4", "--size", size, "--keep", "3",
                   "--first-seed", "500", "--shard", shard_of, "--out", out,
                   "--quiet"});
  };
  ASSERT_EQ(sized(dir + "/mix", "3x3", "0/2").exit_code, 0);
  ExpectOneErrorLine(sized(dir + "/mix", "4x3", "1/2"),
                     "--out: " + dir + "/mix holds '" + dir +
                         "/mix/shard-0-of-2.sqlite', written with other "
                         "options (size=3x3 ");
  ASSERT_EQ(sized(dir + "/mix", "3x3", "1/2").exit_code, 0);  // the same
  // ... and `aia train` a folder that got one anyway.
  ASSERT_EQ(sized(dir + "/other", "4x3", "1/2").exit_code, 0);
  fs::copy_file(dir + "/other/shard-1-of-2.sqlite",
                dir + "/mix/shard-1-of-2.sqlite",
                fs::copy_options::overwrite_existing);
  ExpectOneErrorLine(train({dir + "/mix"}),
                     "mixes shards written with other options: '" + dir +
                         "/mix/shard-0-of-2.sqlite' (size=3x3 ");
  fs::remove_all(dir);
}

// A shard changed outside aia (an episode's world record deleted, its
// samples left) is refused on resume at its path, not with SQLite's raw
// "UNIQUE constraint failed" and exit 1 when the episode ran again.
// Edits a dataset shard as a change made outside aia: `statements` are
// Python run with `c` a sqlite3 connection to it (struct imported), then
// committed. Whether that worked.
bool EditShard(const std::string& shard, const std::string& statements) {
  return RunCommand(
             "/usr/bin/python3 -c \"import sqlite3, struct; c = "
             "sqlite3.connect('" +
             shard + "'); " + statements + "; c.commit()\"")
             .exit_code == 0;
}

TEST(HardeningTest, AShardWithSamplesOfNoWorldIsRefusedOnResume) {
  const std::string dir = testing::MakeTempDir("aia_orphan_");
  const std::vector<std::string> args = {"dataset", "--episodes", "4", "--size",
                                         "3x3",     "--keep",     "2", "--out",
                                         dir,       "--quiet"};
  ASSERT_EQ(RunAia(args).exit_code, 0);
  const std::string shard = dir + "/shard-0-of-1.sqlite";
  ASSERT_TRUE(
      EditShard(shard, "c.execute('DELETE FROM worlds WHERE episode = 1')"));
  ExpectOneErrorLine(RunAia(args),
                     shard +
                         ": --out: holds samples of an episode without "
                         "its world record (the shard was changed outside "
                         "aia)");
  fs::remove_all(dir);
}

// A sample whose belief covariance is no covariance (edited outside aia)
// is refused at its shard, not read into a heat stamp that aborted (rc 134)
// or took a NaN window (a segfault).
TEST(HardeningTest, ASampleWithoutACovarianceIsRefused) {
  const std::string dir = testing::MakeTempDir("aia_cov_");
  ASSERT_EQ(RunAia({"dataset", "--episodes", "2", "--size", "3x3", "--keep",
                    "2", "--out", dir + "/d", "--quiet"})
                .exit_code,
            0);
  const std::string shard = dir + "/d/shard-0-of-1.sqlite";
  // Every sample's first target: the covariance -I.
  ASSERT_TRUE(EditShard(
      shard,
      "rows = c.execute('SELECT rowid, targets FROM samples').fetchall(); "
      "[c.execute('UPDATE samples SET targets = ? WHERE rowid = ?', (b[:16] "
      "+ struct.pack('<3d', -1, 0, -1) + b[40:], r)) for r, b in rows]"));
  ExpectOneErrorLine(
      RunAia({"train", "--data", dir + "/d", "--out", dir + "/m.pt", "--epochs",
              "1", "--width", "8", "--window", "16", "--quiet"}),
      "target 0's belief covariance is not one (-1, 0, -1)");
  fs::remove_all(dir);
}

// A shard that a stopped aia dataset left mid-episode (its hot journal
// beside it, which a reader cannot roll back): the error says so and what
// to do, not "not an aia dataset shard"; the dataset command then resumes.
TEST(HardeningTest, AShardLeftMidEpisodeSaysToRunTheDatasetAgain) {
  const std::string dir = testing::MakeTempDir("aia_journal_");
  const std::vector<std::string> args = {
      "dataset", "--episodes", "3",     "--size",   "3x3",
      "--keep",  "2",          "--out", dir + "/d", "--quiet"};
  ASSERT_EQ(RunAia(args).exit_code, 0);
  const std::string shard = dir + "/d/shard-0-of-1.sqlite";
  // A writer that dies inside its transaction (as SIGKILL would).
  ASSERT_EQ(
      RunCommand(
          "/usr/bin/python3 -c \"import sqlite3, os; c = "
          "sqlite3.connect('" +
          shard +
          "'); c.execute('PRAGMA cache_size = 1'); c.execute('DELETE FROM "
          "samples'); c.execute('DELETE FROM worlds'); os._exit(0)\"")
          .exit_code,
      0);
  ASSERT_TRUE(fs::exists(shard + "-journal"));
  ExpectOneErrorLine(RunAia({"train", "--data", dir + "/d", "--out",
                             dir + "/m.pt", "--epochs", "1", "--quiet"}),
                     shard + ": --data: holds an unfinished episode (" + shard +
                         "-journal): an aia dataset that was stopped left "
                         "it (run that command again");
  EXPECT_EQ(RunAia(args).exit_code, 0);
  EXPECT_FALSE(fs::exists(shard + "-journal"));
  fs::remove_all(dir);
}

// Issue 19: a policy or size listed twice wrote duplicate rows, which every
// resume dropped and ran again.
TEST(HardeningTest, EvalRefusesAPolicyOrASizeListedTwice) {
  const std::string dir = testing::MakeTempDir("aia_evaldup_");
  const auto eval = [&](const std::string& sizes, const std::string& policies) {
    return RunAia({"eval", "--sizes", sizes, "--seeds", "1", "--policies",
                   policies, "--out", dir + "/e", "--quiet"});
  };
  ExpectOneErrorLine(eval("2x2", "random,greedy,random"),
                     "error: command line: --policies: 'random' is listed "
                     "twice");
  ExpectOneErrorLine(eval("2x2,3x3,2x2", "random"),
                     "error: command line: --sizes: '2x2' is listed twice");
  // Sizes are read as counts: 02x2 is 2x2.
  ExpectOneErrorLine(eval("2x2,02x2", "random"),
                     "error: command line: --sizes: '2x2' is listed twice");
  EXPECT_FALSE(fs::exists(dir + "/e/runs.csv"));
  fs::remove_all(dir);
}

// Issue 19: training without held-out worlds printed "val acc 0.000".
TEST(HardeningTest, TrainingWithoutValidationSaysSo) {
  const std::string dir = testing::MakeTempDir("aia_noval_");
  ASSERT_EQ(
      RunAia({"dataset", "--episodes", "6", "--size", "3x3", "--keep", "3",
              "--first-seed", "500", "--out", dir + "/data", "--quiet"})
          .exit_code,
      0);
  const auto train = [&]() {
    return RunAia({"train", "--data", dir + "/data", "--out", dir + "/m.pt",
                   "--val-share", "0", "--epochs", "2", "--width", "8",
                   "--window", "16", "--threads", "1", "--resume"});
  };
  auto r = train();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("| val: none |"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("2 epochs, val: none,"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("val acc"), std::string::npos) << r.out;
  // A resume of the finished run reads the log back from the checkpoint.
  r = train();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 epochs, val: none,"), std::string::npos) << r.out;
  // The log's validation fields are empty.
  const std::string log = ReadFile(dir + "/m.train.csv");
  EXPECT_TRUE(std::regex_search(
      log, std::regex("\n1,[^,]+,[^,]+,[^,]+,,,,[0-9]+,[0-9.]+\n2,[^,]+,"
                      "[^,]+,[^,]+,,,,[0-9]+,[0-9.]+\n$")))
      << log;
  r = RunAia({"train", "--data", dir + "/data", "--validate", dir + "/m.pt",
              "--val-share", "0"});
  ExpectOneErrorLine(r, "--val-share: holds out none of the 6 worlds");
  fs::remove_all(dir);
}

// --- Issue 37 ---------------------------------------------------------

// A command under a hard time limit: what blocks is killed (exit 137), and
// the test says so instead of hanging.
testing::CommandResult RunWithin(const std::vector<std::string>& args,
                                 int seconds = 60) {
  return RunCommand("timeout -s KILL " + std::to_string(seconds) + " " +
                    Quoted(args));
}

// The regular files under `dir` (what a command wrote).
std::vector<std::string> RegularFiles(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end;
       it.increment(ec))
    if (it->is_regular_file()) files.push_back(it->path().string());
  return files;
}

// Every file every command writes, made a FIFO in turn: `mkfifo F/runs.csv`
// made `aia eval` block in open() for ever (SIGTERM did not end it), and
// run, render, plan and train wrote their work and then failed with exit 1.
// Each is now refused before any work, exit 2, one line naming the file.
TEST(HardeningTest, EveryOutputThatIsAFifoIsRefusedBeforeAnyWork) {
  const std::string root = testing::MakeTempDir("aia_fifos_");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  ASSERT_EQ(
      RunAia({"dataset", "--episodes", "4", "--size", "3x3", "--keep", "2",
              "--first-seed", "500", "--out", root + "/data", "--quiet"})
          .exit_code,
      0);
  struct Case {
    std::string dir, file, flag;
    std::vector<std::string> args;
  };
  std::vector<Case> cases;
  int n = 0;
  const auto add = [&](const std::string& file, const std::string& flag,
                       const auto& args_of) {
    const std::string dir = root + "/" + std::to_string(n++);
    cases.push_back({dir, dir + "/" + file, flag, args_of(dir)});
  };
  for (const char* f : {"summary.json", "trace.csv", "estimate.csv",
                        "effective.yaml", "diagnostics.json"})
    add(f, "--out", [&](const std::string& d) {
      return std::vector<std::string>{"run",   scenario, "--max-steps", "2",
                                      "--out", d,        "--quiet"};
    });
  for (const std::string f :
       {"v.mp4", "v.summary.json", "v.trace.csv", "v.estimate.csv",
        "v.effective.yaml", "v.diagnostics.json", "frames/frame_000000.png"})
    add(f, f.rfind("frames/", 0) == 0 ? "--frames" : "--out",
        [&](const std::string& d) {
          return std::vector<std::string>{
              "render",   scenario,      "--max-steps", "1",     "--width",
              "64",       "--height",    "48",          "--out", d + "/v.mp4",
              "--frames", d + "/frames", "--quiet"};
        });
  for (const char* f : {"p.json", "p.effective.yaml"})
    add(f, "--out", [&](const std::string& d) {
      return std::vector<std::string>{"plan", scenario, "--out", d + "/p.json"};
    });
  add("w.xml", "--out", [&](const std::string& d) {
    return std::vector<std::string>{"world", scenario, "--out", d + "/w.xml"};
  });
  for (const char* f : {"runs.csv", "summary.csv", "effective.yaml"})
    add(f, "--out", [&](const std::string& d) {
      return std::vector<std::string>{"eval", "--sizes", "2x2", "--seeds",
                                      "1",    "--out",   d,     "--quiet"};
    });
  for (const char* f : {"shard-0-of-1.sqlite", "shard-0-of-1.sqlite-journal"})
    add(f, "--out", [&](const std::string& d) {
      return std::vector<std::string>{"dataset", "--episodes", "2", "--size",
                                      "2x2",     "--out",      d,   "--quiet"};
    });
  for (const char* f : {"m.pt", "m.pt.ckpt", "m.train.csv"})
    add(f, "--out", [&](const std::string& d) {
      return std::vector<std::string>{"train",    "--data",    root + "/data",
                                      "--out",    d + "/m.pt", "--epochs",
                                      "1",        "--width",   "8",
                                      "--window", "16",        "--threads",
                                      "1",        "--resume",  "--quiet"};
    });
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args[0] + " with a FIFO at " + c.file);
    fs::create_directories(fs::path(c.file).parent_path());
    ASSERT_EQ(::mkfifo(c.file.c_str(), 0644), 0);
    const auto r = RunWithin(c.args);
    ExpectOneErrorLine(r, "'" + c.file);
    EXPECT_EQ(r.err.rfind("error: command line: " + c.flag + ": ", 0), 0u)
        << r.err;
    EXPECT_NE(r.err.find("a named pipe (FIFO), not a regular file"),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(fs::is_fifo(c.file)) << "the FIFO was replaced";
    EXPECT_EQ(RegularFiles(c.dir), std::vector<std::string>{})
        << "work was written before the refusal";
  }
  fs::remove_all(root);
}

// Inputs that are FIFOs, devices or folders never block a reader either.
TEST(HardeningTest, InputsThatAreFifosAreRefusedWithoutBlocking) {
  const std::string dir = testing::MakeTempDir("aia_infifo_");
  const std::string fifo = dir + "/pipe.pt";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", scenario, "--set", "policy.name=igbnet", "--set",
        "policy.model=" + fifo, "--out", dir + "/r", "--quiet"},
       "is a named pipe (FIFO), not a model file"},
      {{"run", scenario, "--set", "policy.name=igbnet", "--set",
        "policy.model=" + dir, "--out", dir + "/r", "--quiet"},
       "is a folder, not a model file"},
      {{"train", "--data", dir, "--init", fifo, "--out", dir + "/m.pt",
        "--quiet"},
       "is a named pipe (FIFO), not a model file"},
      {{"train", "--data", fifo, "--validate", SourcePath("models/igbnet.pt")},
       "is a named pipe (FIFO), not a dataset file"},
      {{"dataset", "--episodes", "1", "--size", "2x2", "--policy", "igbnet",
        "--model", fifo, "--out", dir + "/d", "--quiet"},
       "is a named pipe (FIFO), not a model file"},
  };
  for (const auto& [args, message] : cases) {
    SCOPED_TRACE(args[0]);
    ExpectOneErrorLine(RunWithin(args), message);
  }
  fs::remove_all(dir);
}

// A runs.csv cut by a crash may end in gigabytes of NULs: a 3 GB tail took
// 12 GB of memory to resume. Lines are read one at a time up to 64 KiB.
TEST(HardeningTest, AResumeStopsAtALineLongerThanAnyRow) {
  const std::string dir = testing::MakeTempDir("aia_nuls_");
  const std::vector<std::string> eval = {
      "eval",       "--sizes", "2x2",   "--seeds", "2",
      "--policies", "random",  "--out", dir,       "--quiet"};
  ASSERT_EQ(RunAia(eval).exit_code, 0);
  {
    std::ofstream out(dir + "/runs.csv", std::ios::app | std::ios::binary);
    out << std::string(4 << 20, '\0');
  }
  ExpectOneErrorLine(RunWithin(eval),
                     "--out: cannot resume from '" + dir +
                         "/runs.csv': line 4 is longer than 65536 bytes, "
                         "which no row of aia eval is (a file cut by a crash "
                         "may end in NULs)");
  fs::remove_all(dir);
}

// A model whose largest tensor entry was emptied (a valid zip, its CRC
// fixed) crashed `aia run`, `aia train --init` and `--validate`; one 4
// bytes short loaded and read past the entry. Every reader now names the
// tensor and the entry.
TEST(HardeningTest, ATensorEntryShorterThanItsShapeIsRefusedByEveryReader) {
  const std::string dir = testing::MakeTempDir("aia_tensor_");
  ASSERT_EQ(
      RunAia({"dataset", "--episodes", "4", "--size", "3x3", "--keep", "2",
              "--first-seed", "500", "--out", dir + "/data", "--quiet"})
          .exit_code,
      0);
  for (const char* file : {"empty_tensor_model.pt", "short_tensor_model.pt"}) {
    const std::string model =
        SourcePath(std::string("tests/data/bad_world/") + file);
    const std::string named =
        "tensor 'fc1.weight' (float32, 128 x 16) needs 8192 bytes (2048 x "
        "float32), but its entry 'tiny.pt.tmp/data/42' holds ";
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"run", SourcePath("scenarios/default.yaml"),
                                   "--set", "policy.name=igbnet", "--set",
                                   "policy.model=" + model, "--out", dir + "/r",
                                   "--quiet"},
          std::vector<std::string>{"train", "--data", dir + "/data", "--init",
                                   model, "--out", dir + "/m.pt", "--epochs",
                                   "1", "--quiet"},
          std::vector<std::string>{"train", "--data", dir + "/data",
                                   "--validate", model}}) {
      SCOPED_TRACE(args[0] + " " + file);
      ExpectOneErrorLine(RunWithin(args), named);
    }
  }
  EXPECT_FALSE(fs::exists(dir + "/m.pt"));
  fs::remove_all(dir);
}

// A name that XML gives a meaning (a quote ended MuJoCo's attribute: exit 1,
// "XML parse error 7") runs; one with a NUL is refused at its key, exit 2.
TEST(HardeningTest, NamesWithQuotesRunAndNamesWithNulsAreRefused) {
  const std::string dir = testing::MakeTempDir("aia_name_");
  const std::string yaml = dir + "/s.yaml";
  {
    std::ofstream(yaml) << "name: \"a\\\"b & <c>\"\nrobots: {count: 2}\n"
                           "targets: {count: 2}\nmission: {max_steps: 2}\n";
  }
  const auto r = RunAia({"run", yaml, "--out", dir + "/r", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      ReadFile(dir + "/r/summary.json").find("\"scenario\": \"a\\\"b & <c>\""),
      std::string::npos);
  {
    std::ofstream(yaml) << "name: \"a\\0b\"\nrobots: {count: 2}\n"
                           "targets: {count: 2}\n";
  }
  ExpectOneErrorLine(RunAia({"run", yaml, "--out", dir + "/n", "--quiet"}),
                     "s.yaml:1: name: holds a NUL character");
  fs::remove_all(dir);
}

// An 8192 x 8192 render of a one-step mission, which the schema allows,
// took 12 to 15 GB. What a size needs is stated and checked against the
// budget before any work.
TEST(HardeningTest, RenderSizesBeyondTheMemoryBudgetAreRefusedAtOnce) {
  const std::string dir = testing::MakeTempDir("aia_budget_");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  auto r = RunWithin({"render", scenario, "--width", "8192", "--height", "8192",
                      "--out", dir + "/v.mp4", "--quiet"});
  ExpectOneErrorLine(r,
                     "--width: 8192 x 8192 pixels need about 16.50 GiB (512 "
                     "MiB + 256 bytes per pixel), more than the render's "
                     "memory budget of 8 GiB (--memory-budget)");
  // The budget is the user's to give: 640 x 480 needs 0.6 GiB.
  r = RunWithin({"render", scenario, "--memory-budget", "0.5", "--out",
                 dir + "/v.mp4", "--quiet"});
  ExpectOneErrorLine(r, "640 x 480 pixels need about 0.57 GiB");
  // A process limit is a budget too (under ulimit -v the encoder failed
  // midway with OpenCV's raw line). AddressSanitizer reserves terabytes of
  // address space, so its tree cannot run under such a limit.
#ifndef AIA_TEST_ASAN
  const std::string limited =
      "ulimit -v 3000000; " +
      Quoted({"render", scenario, "--width", "4096", "--height", "4096",
              "--out", dir + "/v.mp4", "--quiet"});
  r = RunCommand("bash -c '" +
                 std::regex_replace(limited, std::regex("'"), "'\\''") + "'");
  ExpectOneErrorLine(r,
                     "4096 x 4096 pixels need about 4.50 GiB (512 MiB + 256 "
                     "bytes per pixel), more than this process may take "
                     "(2.86 GiB, ulimit -v)");
#endif
  EXPECT_TRUE(RegularFiles(dir).empty());
  fs::remove_all(dir);
}

// A target walled in where no robot can measure it: `aia plan` said found,
// F* = 6 (planned from its prior mean outside the walls), and the mission
// ran its horizon. Both refuse it now, naming it.
TEST(HardeningTest, ATargetNoRobotCanMeasureIsRefusedByPlanAndRun) {
  const std::string file =
      SourcePath("tests/data/bad_world/target_walled_in.yaml");
  const std::string dir = testing::MakeTempDir("aia_walled_");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"plan", file, "--out", dir + "/p.json"},
        std::vector<std::string>{"run", file, "--out", dir + "/r",
                                 "--quiet"}}) {
    const auto r = RunWithin(args);
    ExpectOneErrorLine(r, file +
                              ":8: targets.list[1].position: target [10, "
                              "10] can never be measured");
    EXPECT_EQ(r.out.find("found"), std::string::npos) << r.out;
  }
  EXPECT_TRUE(RegularFiles(dir).empty());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
