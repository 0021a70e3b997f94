#include "aia/runtime/eval.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "support/test_support.h"

namespace aia {
namespace {

using testing::ReadFile;
using testing::RunAia;

std::string WithoutWall(const std::string& csv) {
  return std::regex_replace(csv, std::regex(",[0-9.]+\n"), ",X\n");
}

TEST(EvalTest, SummaryCountsFailuresAsThreeFStar) {
  // Two instances with F* = 4: one success in 6 steps, one failure.
  std::vector<EvalRow> rows = {{"2x2", 0, "greedy", true, 6, 4, 0.1},
                               {"2x2", 1, "greedy", false, -1, 4, 0.1},
                               {"2x2", 2, "greedy", false, -1, -1, 0.0}};
  const std::string csv = SummaryCsv(rows, {"2x2"}, {"greedy"});
  // success 1/2; increase mean((6-4)/4, (12-4)/4) = 1.25; one instance without
  // a plan.
  EXPECT_NE(csv.find("2x2,greedy,2,0.5000,1.2500,9.000,4.000,1"),
            std::string::npos)
      << csv;
}

TEST(EvalTest, RunsResumeAndDoNotDependOnThreads) {
  const std::string a = testing::MakeTempDir("aia_eval_"),
                    b = testing::MakeTempDir("aia_eval_");
  auto eval = [](const std::string& dir, const std::string& seeds,
                 const std::string& threads) {
    return RunAia({"eval", "--sizes", "2x2,3x2", "--seeds", seeds,
                   "--seed-base", "5", "--policies", "greedy,random", "--out",
                   dir, "--threads", threads, "--quiet"});
  };
  ASSERT_EQ(eval(a, "3", "2").exit_code, 0);
  // Interrupted mid-line: the partial row is dropped and its run redone.
  { std::ofstream(a + "/runs.csv", std::ios::app) << "3x2,7,greedy,1,"; }
  const auto resumed = eval(a, "4", "2");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("12 rows already done, 4 to run"),
            std::string::npos)
      << resumed.out;
  ASSERT_EQ(eval(b, "4", "1").exit_code, 0);
  EXPECT_EQ(WithoutWall(ReadFile(a + "/runs.csv")),
            WithoutWall(ReadFile(b + "/runs.csv")));
  EXPECT_EQ(ReadFile(a + "/summary.csv"), ReadFile(b + "/summary.csv"));
  const auto rows = ReadRuns(a + "/runs.csv");
  EXPECT_EQ(rows.size(), 16u);
  for (const auto& r : rows) {
    EXPECT_GE(r.fstar, 0);
    if (r.success) EXPECT_LE(r.flowtime, 3 * std::max(r.fstar, 1));
  }
  // The eval plot reads the summary (skipped without Debian's matplotlib).
  if (testing::RunCommand("/usr/bin/python3 -c 'import matplotlib'")
          .exit_code == 0) {
    const auto plot = testing::RunCommand(
        "/usr/bin/python3 " + testing::SourcePath("tools/plot_eval.py") + " " +
        a + "/summary.csv --out " + a + "/eval.png");
    EXPECT_EQ(plot.exit_code, 0) << plot.err;
    EXPECT_TRUE(std::filesystem::exists(a + "/eval.png"));
  }
  std::filesystem::remove_all(a);
  std::filesystem::remove_all(b);
}

TEST(EvalTest, BadFlagsExitWith2) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  auto r = RunAia({"eval", "--sizes", "10x", "--out", dir});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: command line: --sizes: '10x' is not a size"),
            std::string::npos)
      << r.err;
  r = RunAia({"eval", "--policies", "greedy,nope", "--out", dir});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown policy 'nope'"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace aia
