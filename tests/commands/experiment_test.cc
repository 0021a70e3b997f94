// tools/experiment.py: the paper's three experiments and the generalization
// suite, each in its --quick size, write their CSV, summary.json, plots and
// videos, and a second call reuses what the first wrote.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

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

// The generalization suite, cut to one generated condition and the two
// small hand-made worlds: its table has a row per condition and policy, the
// random walker's success is exactly 0 on generated worlds, and an --only
// that matches nothing is bad input.
TEST(ExperimentTest, GeneralizationSuiteWritesItsTable) {
  if (!HaveMatplotlib()) GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_experiment_");
  const auto g = RunCommand(Experiment(
      "generalization --quick --only 'team 2x2,hand-made' --policies "
      "greedy,random --seeds 2 --file-seeds 1 --threads 2 --jobs 2 --out " +
      dir + "/g"));
  ASSERT_EQ(g.exit_code, 0) << g.out << g.err;
  for (const char* f :
       {"generalization.csv", "generalization.md", "generalization.png",
        "summary.json", "eval/team_2x2/runs.csv"})
    EXPECT_TRUE(fs::exists(dir + "/g/" + f)) << f;
  const std::string table = ReadFile(dir + "/g/generalization.csv");
  EXPECT_EQ(table.rfind("condition,group,policy,n,success,success_se,", 0), 0u)
      << table;
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 1 + 2 * 2) << table;
  EXPECT_NE(table.find("team 2x2,team size,random,2,0,0,"), std::string::npos)
      << table;
  EXPECT_NE(
      table.find("scenarios/long (hand-made worlds),structured,greedy,2,"),
      std::string::npos)
      << table;
  const auto none = RunCommand(
      Experiment("generalization --quick --only nothing --out " + dir + "/n"));
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("error: --only: 'nothing' matches no condition"),
            std::string::npos)
      << none.err;
  fs::remove_all(dir);
}

// Point against wheeled robots on the same worlds: a row per condition,
// policy and model; a wheeled robot's decision step takes several times a
// point robot's simulated time, only wheeled robots turn in place, and the
// shares of the robots' time add up to one.
TEST(ExperimentTest, MotionComparesPointAndWheeledRobots) {
  if (!HaveMatplotlib()) GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_experiment_");
  const auto m = RunCommand(Experiment(
      "motion --quick --policies greedy --seeds 1 --max-steps 12 --jobs 2 "
      "--out " +
      dir + "/m"));
  ASSERT_EQ(m.exit_code, 0) << m.out << m.err;
  for (const char* f : {"motion.csv", "motion.md", "summary.json"})
    EXPECT_TRUE(fs::exists(dir + "/m/" + f)) << f;
  std::istringstream table(ReadFile(dir + "/m/motion.csv"));
  std::string line;
  std::getline(table, line);
  ASSERT_EQ(line.rfind("condition,model,policy,n,success,success_se,steps,", 0),
            0u)
      << line;
  std::vector<std::string> header;
  for (std::istringstream h(line); std::getline(h, line, ',');)
    header.push_back(line);
  auto column = [&](const std::vector<std::string>& row, const char* name) {
    const auto at = std::find(header.begin(), header.end(), name);
    return std::stod(row.at(at - header.begin()));
  };
  int rows = 0;
  while (std::getline(table, line)) {
    std::vector<std::string> row;
    for (std::istringstream r(line); std::getline(r, line, ',');)
      row.push_back(line);
    ++rows;
    const bool wheeled = row.at(1) == "diff_drive";
    const double per_step = column(row, "seconds_per_step");
    EXPECT_GT(per_step, wheeled ? 0.7 : 0.0) << line;
    if (!wheeled) EXPECT_LT(per_step, 0.5) << line;
    EXPECT_EQ(column(row, "share_turning") > 0.0, wheeled) << line;
    EXPECT_NEAR(
        column(row, "share_driving") + column(row, "share_turning") +
            column(row, "share_blocked") + column(row, "share_arrived") +
            column(row, "share_yielding") + column(row, "share_staying"),
        1.0, 1e-5);  // the CSV's six digits
  }
  EXPECT_EQ(rows, 2 * 2);

  // Wheeled robots in both decision modes: deciding on arrival, nobody
  // waits for the others.
  const auto a = RunCommand(Experiment(
      "motion --quick --policies greedy --seeds 1 --max-steps 12 --jobs 2 "
      "--models diff_drive --decisions lockstep,async --out " +
      dir + "/a"));
  ASSERT_EQ(a.exit_code, 0) << a.out << a.err;
  std::istringstream modes(ReadFile(dir + "/a/motion.csv"));
  std::getline(modes, line);
  rows = 0;
  while (std::getline(modes, line)) {
    std::vector<std::string> row;
    for (std::istringstream r(line); std::getline(r, line, ',');)
      row.push_back(line);
    ++rows;
    if (row.at(1) == "diff_drive async") {
      EXPECT_EQ(column(row, "share_arrived"), 0.0) << line;
    } else {
      EXPECT_EQ(row.at(1), "diff_drive");
      EXPECT_GT(column(row, "share_arrived"), 0.0) << line;
    }
  }
  EXPECT_EQ(rows, 2 * 2);
  fs::remove_all(dir);
}

TEST(ExperimentTest, BadArgumentsExitWith2) {
  if (!HaveMatplotlib()) GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_experiment_");
  EXPECT_EQ(
      RunCommand(Experiment("robustness --seeds 0 --out " + dir)).exit_code, 2);
  EXPECT_EQ(RunCommand(Experiment("bogus --out " + dir)).exit_code, 2);
  EXPECT_EQ(
      RunCommand(Experiment("motion --max-steps 0 --out " + dir)).exit_code, 2);
  EXPECT_EQ(RunCommand(Experiment("motion --decisions sometimes --out " + dir))
                .exit_code,
            2);
  const auto bad = RunCommand(Experiment(
      "robustness --quick --no-video --set robots.count=-1 --out " + dir));
  EXPECT_EQ(bad.exit_code, 2) << bad.out << bad.err;
  EXPECT_NE(bad.err.find("error: "), std::string::npos) << bad.err;
  // aia eval's own error line, and no second line of the experiment's.
  const auto policy = RunCommand(
      Experiment("scalability --quick --policies nosuch --out " + dir + "/p"));
  EXPECT_EQ(policy.exit_code, 2);
  EXPECT_EQ(policy.err,
            "error: command line: --policies: unknown policy 'nosuch' "
            "(valid: random, greedy, expert, decsb, igbnet)\n");
  for (const char* flag : {"--seed-base -1", "--sizes ,3x3"}) {
    const auto r = RunCommand(Experiment(std::string("scalability --quick ") +
                                         flag + " --out " + dir + "/s"));
    EXPECT_EQ(r.exit_code, 2) << flag << r.err;
  }
  fs::remove_all(dir);
}

// A run that Ctrl-C cut short (its summary says "interrupted") is run again
// on the next call, not kept as done; a folder made with other settings
// (another --set, --policy) is refused rather than mixed.
TEST(ExperimentTest, ResumeRunsInterruptedRunsAgainAndKeepsItsSettings) {
  if (!HaveMatplotlib()) GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_experiment_resume_");
  const std::string cmd = Experiment(
      "robustness --quick --no-video --seeds 1 --jobs 1 --out " + dir);
  ASSERT_EQ(RunCommand(cmd).exit_code, 0);
  const std::string run = dir + "/runs/faults-0/summary.json";
  const std::string done = ReadFile(run);
  std::ofstream(run) << "{\"interrupted\": true, \"success\": false, "
                        "\"flowtime\": null, \"steps\": 0, \"max_steps\": "
                        "400}\n";
  const auto again = RunCommand(cmd);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  // Run again, the same result (but the wall clock).
  const auto no_wall = [](const std::string& text) {
    return std::regex_replace(text, std::regex("\"wall_s\": [0-9.e-]+"), "");
  };
  EXPECT_EQ(no_wall(ReadFile(run)), no_wall(done));
  const auto other = RunCommand(cmd + " --set sensor.range=1.5");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("this folder was made with other settings (set: "
                           "[] -> ['sensor.range=1.5'])"),
            std::string::npos)
      << other.err;
  EXPECT_EQ(RunCommand(cmd + " --policy greedy").exit_code, 2);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
