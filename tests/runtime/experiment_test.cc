// tools/experiment.py: the paper's three experiments, each in its --quick
// size, write their CSV, summary.json, plots and videos, and a second call
// reuses what the first wrote.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunCommand;

bool HaveMatplotlib() {
  return RunCommand("/usr/bin/python3 -c 'import matplotlib'").exit_code == 0;
}

std::string Experiment(const std::string& args) {
  return "/usr/bin/python3 " + testing::SourcePath("tools/experiment.py") +
         " " + args + " --aia '" + AIA_BINARY + "'";
}

TEST(ExperimentTest, QuickExperimentsWriteResultsPlotsAndVideos) {
  if (!HaveMatplotlib()) GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_experiment_");
  const auto s = RunCommand(Experiment(
      "scalability --quick --policies greedy,random --threads 2 --out " + dir +
      "/s"));
  ASSERT_EQ(s.exit_code, 0) << s.out << s.err;
  for (const char* f : {"scalability.csv", "summary.json", "scalability.png",
                        "eval/runs.csv", "eval/summary.csv"})
    EXPECT_TRUE(fs::exists(dir + "/s/" + f)) << f;
  const std::string table = ReadFile(dir + "/s/scalability.csv");
  EXPECT_EQ(table.rfind("size,policy,instances,success_rate,success_se,", 0),
            0u);
  // The random walker never localizes within 3 F*: its row is exact.
  EXPECT_NE(table.find("10x10,random,3,0,0,2,0,"), std::string::npos) << table;

  const auto t = RunCommand(Experiment("tracking --quick --out " + dir + "/t"));
  ASSERT_EQ(t.exit_code, 0) << t.out << t.err;
  for (const char* m : {"localization", "tracking"})
    for (const char* f : {"summary.json", "trace.csv", "estimate.csv",
                          "uncertainty.png", "estimate.png"})
      EXPECT_TRUE(fs::exists(dir + "/t/" + m + "/" + f)) << m << "/" << f;
  EXPECT_TRUE(fs::exists(dir + "/t/tracking/tracking.mp4"));
  EXPECT_NE(ReadFile(dir + "/t/summary.json").find("\"mean_nees\""),
            std::string::npos);
  // Again: the missions and videos already there are not run again.
  const auto again =
      RunCommand(Experiment("tracking --quick --out " + dir + "/t"));
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.out.find("+ "), std::string::npos) << again.out;

  const auto r = RunCommand(Experiment(
      "robustness --quick --policy greedy --jobs 2 --out " + dir + "/r"));
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  for (const char* f :
       {"robustness.csv", "summary.json", "robustness.png", "robustness.mp4"})
    EXPECT_TRUE(fs::exists(dir + "/r/" + f)) << f;
  const std::string rows = ReadFile(dir + "/r/robustness.csv");
  EXPECT_EQ(std::count(rows.begin(), rows.end(), '\n'), 1 + 2 * 5);
  EXPECT_NE(ReadFile(dir + "/r/summary.json").find("\"mission_time_increase\""),
            std::string::npos);
  fs::remove_all(dir);
}

TEST(ExperimentTest, BadArgumentsExitWith2) {
  if (!HaveMatplotlib()) GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_experiment_");
  EXPECT_EQ(
      RunCommand(Experiment("robustness --seeds 0 --out " + dir)).exit_code, 2);
  EXPECT_EQ(RunCommand(Experiment("bogus --out " + dir)).exit_code, 2);
  const auto bad = RunCommand(Experiment(
      "robustness --quick --no-video --set robots.count=-1 --out " + dir));
  EXPECT_EQ(bad.exit_code, 2) << bad.out << bad.err;
  EXPECT_NE(bad.err.find("error: "), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
