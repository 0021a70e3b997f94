#include "aia/commands/eval.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include "aia/commands/eval_folder.h"
#include "aia/commands/ranks.h"
#include "aia/core/interrupt.h"
#include "aia/core/io.h"
#include "aia/planning/decsb.h"
#include "aia/runtime/mission.h"
#include "aia/scenario/yaml.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ReadFile;
using testing::RunAia;

std::string WithoutWall(const std::string& csv) {
  return std::regex_replace(csv, std::regex(",[0-9.]+\n"), ",X\n");
}

// runs.csv's row is declared once (EvalRow::Columns): its header is the one
// tools/plot_eval.py and the docs name, and a row reads back as written.
TEST(EvalTest, TheRunsRowRoundTripsThroughItsDeclaration) {
  EXPECT_EQ(CsvHeader<EvalRow>(),
            "size,seed,policy,success,flowtime,fstar,bound,reversal_share,"
            "longest_reversal_run,mission_seconds,stalls,timeouts,wall_s");
  EvalRow r;
  r.size = "10x10";
  r.seed = 931000;
  r.policy = "igbnet";
  r.success = true;
  r.flowtime = 17;
  r.fstar = 15;
  r.bound = 9;
  r.reversal_share = 0.04166;
  r.longest_reversal_run = 2;
  r.mission_seconds = 21.2875;
  r.stalls = 3;
  r.timeouts = 1;
  r.wall_s = 1.5;
  const std::string line = CsvLine(r);
  EXPECT_EQ(line, "10x10,931000,igbnet,1,17,15,9,0.0417,2,21.288,3,1,1.5000\n");
  EvalRow back;
  ASSERT_TRUE(ParseCsvLine(line.substr(0, line.size() - 1), &back));
  EXPECT_EQ(CsvLine(back), line);
  r.success = false;
  r.flowtime = -1;  // not reached: an empty cell
  EXPECT_EQ(CsvLine(r),
            "10x10,931000,igbnet,0,,15,9,0.0417,2,21.288,3,1,1.5000\n");
  // summary.csv likewise; a size and policy without any expert plan has
  // empty figures.
  EXPECT_EQ(CsvHeader<SummaryRow>(),
            "size,policy,instances,success_rate,flowtime_increase,mean_"
            "flowtime,mean_fstar,mean_fstar_over_bound,no_expert_plan,"
            "reversal_share,longest_reversal_run,mission_seconds,stalls,"
            "timeouts");
  SummaryRow none;
  none.size = "2x2";
  none.policy = "greedy";
  none.no_expert_plan = 3;
  EXPECT_EQ(CsvLine(none), "2x2,greedy,0,,,,,,3,,,,,\n");
  SummaryRow back_none;
  ASSERT_TRUE(ParseCsvLine("2x2,greedy,0,,,,,,3,,,,,", &back_none));
  EXPECT_EQ(CsvLine(back_none), CsvLine(none));
}

TEST(EvalTest, SummaryCountsFailuresAsThreeFStar) {
  // Two instances with F* = 4 (lower bounds 4 and 2): one success in 6
  // steps, one failure.
  std::vector<EvalRow> rows = {
      {"2x2", 0, "greedy", true, 6, 4, 4, 0.25, 2, 9.0, 1, 0, 0.1},
      {"2x2", 1, "greedy", false, -1, 4, 2, 0.5, 7, 14.5, 4, 2, 0.1},
      {"2x2", 2, "greedy", false, -1, -1, 0, 0.0, 0, 0.0, 0, 0, 0.0}};
  const std::string csv = SummaryCsv(rows, {"2x2"}, {"greedy"});
  // success 1/2; increase mean((6-4)/4, (12-4)/4) = 1.25; F* / bound
  // mean(1, 2) = 1.5; one instance without a plan; reversal share
  // mean(0.25, 0.5) = 0.375, the longest run 7; mission seconds
  // mean(9, 14.5) = 11.75, stalls mean(1, 4) = 2.5, timeouts 1.
  EXPECT_NE(csv.find("2x2,greedy,2,0.5000,1.2500,9.000,4.000,1.5000,1,0.3750,"
                     "7,11.750,2.500,1.000\n"),
            std::string::npos)
      << csv;
}

TEST(EvalTest, AsyncRunsDoNotDependOnThreads) {
  const std::string a = testing::MakeTempDir("aia_eval_"),
                    b = testing::MakeTempDir("aia_eval_");
  auto eval = [](const std::string& dir, const std::string& threads) {
    return RunAia({"eval", "--sizes", "3x3", "--seeds", "3", "--seed-base",
                   "11", "--policies", "greedy,expert", "--set",
                   "mission.decisions=async", "--set",
                   "robots.model=diff_drive", "--out", dir, "--threads",
                   threads, "--quiet"});
  };
  const auto one = eval(a, "1");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  ASSERT_EQ(eval(b, "2").exit_code, 0);
  EXPECT_EQ(WithoutWall(ReadFile(a + "/runs.csv")),
            WithoutWall(ReadFile(b + "/runs.csv")));
  EXPECT_EQ(ReadRuns(a + "/runs.csv").size(), 6u);
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

// Issue 37: resuming `--policies greedy --sizes 3x3` into a folder of random
// and greedy rows wrote a summary with 3x3 random and without 4x4 (this
// eval's sizes and seeds, every policy). summary.csv now covers every row
// of runs.csv, whichever command wrote it last, and the command says so.
TEST(EvalTest, SummaryCoversEveryRowOfTheFolder) {
  const std::string dir = testing::MakeTempDir("aia_cover_");
  const auto eval = [&](const std::string& sizes, const std::string& policies,
                        const std::string& seed_base) {
    return RunAia({"eval", "--sizes", sizes, "--seeds", "2", "--seed-base",
                   seed_base, "--policies", policies, "--out", dir, "--threads",
                   "1", "--quiet"});
  };
  ASSERT_EQ(eval("3x3,4x4", "random,greedy", "0").exit_code, 0);
  const std::string whole = ReadFile(dir + "/summary.csv");
  // Every size and policy, resumed with some of them: the same summary.
  const auto r = eval("3x3", "greedy", "0");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("summary.csv (of all 8 rows of runs.csv: sizes 3x3, "
                       "4x4; 2 seeds, 0 to 1; policies greedy, random)"),
            std::string::npos)
      << r.out;
  const auto lines = [](const std::string& csv) {
    std::multiset<std::string> set;
    std::istringstream in(csv);
    for (std::string line; std::getline(in, line);) set.insert(line);
    return set;
  };
  EXPECT_EQ(lines(ReadFile(dir + "/summary.csv")), lines(whole));
  // Rows of other seeds count too: 3 instances of 3x3 greedy now.
  ASSERT_EQ(RunAia({"eval", "--sizes", "3x3", "--seeds", "1", "--seed-base",
                    "9", "--policies", "greedy", "--out", dir, "--threads", "1",
                    "--quiet"})
                .exit_code,
            0);
  const std::string summary = ReadFile(dir + "/summary.csv");
  EXPECT_NE(summary.find("\n3x3,greedy,3,"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\n4x4,random,2,"), std::string::npos) << summary;
  // A size of one policy alone: no row for the policies it was not run with
  // (it was a row of empty columns).
  ASSERT_EQ(eval("2x2", "random", "0").exit_code, 0);
  const std::string more = ReadFile(dir + "/summary.csv");
  EXPECT_NE(more.find("\n2x2,random,2,"), std::string::npos) << more;
  EXPECT_EQ(more.find("2x2,greedy"), std::string::npos) << more;
  EXPECT_EQ(lines(more).size(), lines(summary).size() + 1) << more;
  std::filesystem::remove_all(dir);
}

// The reversal columns: a random walker in the open reverses about a quarter
// of its moves (one of four moves undoes the last), and a runs.csv written
// before these columns (its older header) is run again, not misread.
TEST(EvalTest, ReversalColumnsAndRowsOfAnOlderLayout) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  auto eval = [&] {
    return RunAia({"eval", "--sizes", "10x10", "--seeds", "4", "--policies",
                   "random", "--set", "workspace.obstacles.random.count=0",
                   "--out", dir, "--threads", "2", "--quiet"});
  };
  ASSERT_EQ(eval().exit_code, 0);
  const auto rows = ReadRuns(dir + "/runs.csv");
  ASSERT_EQ(rows.size(), 4u);
  double share = 0.0;
  for (const auto& r : rows) {
    share += r.reversal_share / rows.size();
    EXPECT_GE(r.longest_reversal_run, 1);  // hundreds of moves
  }
  EXPECT_GT(share, 0.15);
  EXPECT_LT(share, 0.35);
  const std::string now = ReadFile(dir + "/runs.csv");
  // The same rows as the previous aia wrote them: no mission seconds,
  // stalls and timeouts.
  const std::string previous = std::regex_replace(
      std::regex_replace(now, std::regex(",[0-9.]+,[0-9]+,[0-9]+(,[0-9.]+\n)"),
                         "$1"),
      std::regex("mission_seconds,stalls,timeouts,"), "");
  ASSERT_EQ(previous.rfind("size,seed,policy,success,flowtime,fstar,bound,"
                           "reversal_share,longest_reversal_run,wall_s\n",
                           0),
            0u);
  // And as the older one did: no reversal columns either.
  const std::string older = std::regex_replace(
      std::regex_replace(previous, std::regex(",[0-9.]+,[0-9]+(,[0-9.]+\n)"),
                         "$1"),
      std::regex("reversal_share,longest_reversal_run,"), "");
  for (const auto& [layout, lacks] :
       {std::pair{previous, "no mission_seconds, stalls, timeouts"},
        std::pair{older, "no reversal columns"}}) {
    { std::ofstream(dir + "/runs.csv") << layout; }
    const auto resumed = eval();
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    EXPECT_NE(resumed.err.find(std::string("dropped 5 rows that will run "
                                           "again: line 1: the header of an "
                                           "older aia (") +
                               lacks + ")"),
              std::string::npos)
        << resumed.err;
    EXPECT_EQ(WithoutWall(ReadFile(dir + "/runs.csv")), WithoutWall(now));
  }
  std::filesystem::remove_all(dir);
}

// `mpirun -n 2 aia eval` (ranks take instances round-robin, rank 0 writes
// the rows) gives the files of one process; so does `aia dataset`'s one
// shard per rank. Skipped when aia was built without MPI or mpirun is absent.
TEST(EvalTest, TwoMpiRanksGiveTheFilesOfOneProcess) {
  if (!Ranks::Built() ||
      testing::RunCommand("command -v mpirun").exit_code != 0)
    GTEST_SKIP() << "built without MPI, or no mpirun";
  const std::string a = testing::MakeTempDir("aia_mpi_"),
                    b = testing::MakeTempDir("aia_mpi_");
  // Root may run mpirun only when it says so (CI containers run as root).
  const std::string mpirun =
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
      "OMPI_MCA_rmaps_base_oversubscribe=1 mpirun -n 2 '" +
      std::string(AIA_BINARY) + "' ";
  const std::string flags =
      "eval --sizes 2x2,3x2,4x3 --seeds 3 --seed-base 11 --policies "
      "greedy,random,decsb --threads 1 --quiet --out ";
  const auto one =
      RunAia({"eval", "--sizes", "2x2,3x2,4x3", "--seeds", "3", "--seed-base",
              "11", "--policies", "greedy,random,decsb", "--threads", "1",
              "--quiet", "--out", a});
  ASSERT_EQ(one.exit_code, 0) << one.err;
  // Half done first, then resumed under MPI.
  ASSERT_EQ(RunAia({"eval", "--sizes", "2x2", "--seeds", "3", "--seed-base",
                    "11", "--policies", "greedy,random,decsb", "--threads", "1",
                    "--quiet", "--out", b})
                .exit_code,
            0);
  const auto two = testing::RunCommand(mpirun + flags + b);
  ASSERT_EQ(two.exit_code, 0) << two.out << two.err;
  EXPECT_NE(two.out.find("9 rows already done, 18 to run on 2 MPI ranks"),
            std::string::npos)
      << two.out;
  EXPECT_EQ(ReadFile(a + "/summary.csv"), ReadFile(b + "/summary.csv"));
  EXPECT_EQ(WithoutWall(ReadFile(a + "/runs.csv")),
            WithoutWall(ReadFile(b + "/runs.csv")));
  EXPECT_EQ(ReadFile(a + "/effective.yaml"), ReadFile(b + "/effective.yaml"));
  // A folder of another configuration is refused by rank 0; no rank hangs.
  const auto refused =
      testing::RunCommand(mpirun + flags + b + " --set sensor.range=3");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("holds results of another configuration"),
            std::string::npos)
      << refused.err;
  // The dataset: one shard per rank, as --shard K/2 would write them.
  const auto ds = testing::RunCommand(
      mpirun + "dataset --episodes 3 --size 3x2 --keep 2 --quiet --out " + a +
      "/data");
  ASSERT_EQ(ds.exit_code, 0) << ds.err;
  for (const char* k : {"0", "1"}) {
    ASSERT_EQ(RunAia({"dataset", "--episodes", "3", "--size", "3x2", "--keep",
                      "2", "--quiet", "--shard", std::string(k) + "/2", "--out",
                      b + "/data"})
                  .exit_code,
              0);
  }
  const std::string info =
      "/usr/bin/python3 " + testing::SourcePath("tools/igbnet.py") + " info ";
  const auto ia = testing::RunCommand(info + a + "/data");
  const auto ib = testing::RunCommand(info + b + "/data");
  ASSERT_EQ(ia.exit_code, 0) << ia.err;
  EXPECT_NE(ia.out.find("3 episodes"), std::string::npos) << ia.out;
  EXPECT_EQ(ia.out, ib.out);
  EXPECT_TRUE(std::filesystem::exists(a + "/data/shard-1-of-2.sqlite"));
  std::filesystem::remove_all(a);
  std::filesystem::remove_all(b);
}

TEST(EvalTest, BadFlagsExitWith2) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  auto r = RunAia({"eval", "--sizes", "10x", "--out", dir});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("error: command line: --sizes: must be a size "
                       "ROBOTSxTARGETS such as 10x10, got 10x"),
            std::string::npos)
      << r.err;
  r = RunAia({"eval", "--policies", "greedy,nope", "--out", dir});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown policy 'nope'"), std::string::npos) << r.err;
  std::filesystem::remove_all(dir);
}

// Ctrl-C while an instance runs: a run cut short gives no row (it would
// read as a failure, and a resume would never run it again). Each test runs
// in its own process (gtest_discover_tests), so the flag set here stays
// here.
TEST(EvalPiecesTest, ARunCutShortByCtrlCGivesNoRow) {
  const PolicyRegistry registry = AllPolicies();
  const EvalSetup setup = MakeEvalSetup({"random"}, {}, registry);
  const EvalInstance instance{"2x2", 2, 2, 0};
  ASSERT_EQ(RunInstance(instance, setup).size(), 1u);
  {
    InterruptScope scope;
    std::raise(SIGINT);
    ASSERT_TRUE(Interrupted());
    EXPECT_THROW(RunInstance(instance, setup), RunInterrupted);
  }
  // The scope gave the previous handler back and cleared the flag.
  EXPECT_FALSE(Interrupted());
  EXPECT_EQ(RunInstance(instance, setup).size(), 1u);
}

TEST(EvalPiecesTest, EnumerateRunOneInstanceAndMerge) {
  const std::vector<EvalInstance> all =
      EnumerateInstances({{2, 2}, {3, 1}}, 2, 7);
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[3].size, "3x1");
  EXPECT_EQ(all[3].robots, 3);
  EXPECT_EQ(all[3].targets, 1);
  EXPECT_EQ(all[3].seed, 8u);
  const PolicyRegistry registry = AllPolicies();
  const EvalSetup setup = MakeEvalSetup({"greedy", "random"}, {}, registry);
  // A pure function of the instance: the same rows twice, wall time aside;
  // a subset of the policies gives the subset of the rows.
  const std::vector<EvalRow> a = RunInstance(all[0], setup);
  const std::vector<EvalRow> b = RunInstance(all[0], setup);
  const std::vector<EvalRow> only = RunInstance(all[0], setup, {"random"});
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(only.size(), 1u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].policy, setup.policies[i]->name());
    EXPECT_EQ(std::make_tuple(a[i].success, a[i].flowtime, a[i].fstar),
              std::make_tuple(b[i].success, b[i].flowtime, b[i].fstar));
  }
  EXPECT_EQ(only[0].flowtime, a[1].flowtime);
  const std::string csv = SummaryCsv(a, {"2x2"}, {"greedy", "random"});
  EXPECT_NE(csv.find("2x2,greedy,1,"), std::string::npos) << csv;
}

TEST(EvalPiecesTest, SetReachesTheInstancesAndThePoliciesThatDeclareIt) {
  const PolicyRegistry registry = AllPolicies();
  const EvalSetup setup = MakeEvalSetup(
      {"greedy", "decsb"},
      {"sensor.range=3", "policy.horizon=5", "policy.anytime=100"}, registry);
  EXPECT_EQ(InstanceScenario({"2x2", 2, 2, 4}, setup).sensor.range, 3.0);
  EXPECT_EQ(InstanceScenario({"2x2", 2, 2, 4}, setup).seed, 4u);
  EXPECT_EQ(ParamsOf<DecSbParams>(*setup.policies[1])->horizon, 5);
  EXPECT_EQ(ParamsOf<ExpertParams>(*setup.expert)->anytime, 100);
  const auto error = [&](const std::string& set) {
    try {
      MakeEvalSetup({"greedy"}, {set}, registry);
    } catch (const InputError& e) {
      return e.Format();
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("policy.horizon=5"),
            "command line: --set policy.horizon: no policy of this evaluation "
            "(expert, greedy) has the parameter `horizon` (aia policies lists "
            "them)");
  EXPECT_EQ(error("seed=3").rfind("command line: --set seed: is set by each "
                                  "instance",
                                  0),
            0u);
  EXPECT_EQ(
      error("robots.count=3").rfind("command line: --set robots.count:", 0),
      0u);
}

// Bad input in the generated scenarios of eval, bench and dataset names the
// flag behind it, before any work (it read `error: :0:` or `error:
// (generated scenario):0:`, exit 1, once the folder was made).
TEST(EvalTest, GeneratedScenarioErrorsNameTheirFlag) {
  const std::string dir = testing::MakeTempDir("aia_gen_");
  const std::string out = dir + "/out";
  const std::string bodies =
      "'5000x1': robots.count: 5000 robots, 1 targets and 30 obstacle boxes "
      "make 5031 bodies; aia simulates at most 5000\n";
  const std::string list =
      "targets.count: is 2 but targets.list has 1 targets; give count "
      "(random targets) or list, or make them agree (in the generated "
      "scenario of ";
  const std::vector<std::string> eval = {"eval",   "--seeds", "1", "--policies",
                                         "random", "--out",   out, "--quiet"};
  const auto with = [](std::vector<std::string> args,
                       const std::vector<std::string>& more) {
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {with(eval, {"--sizes", "5000x1"}),
       "error: command line: --sizes: " + bodies},
      {with(eval, {"--sizes", "2x2", "--set",
                   "targets.list=[{position: [1, "
                   "1]}]"}),
       "error: command line: --set targets.list: " + list + "--sizes 2x2)\n"},
      {with(eval, {"--sizes", "2x1", "--set", "sensor.range=3", "--set",
                   "workspace.size=[1, 1]"}),
       "error: command line: --set workspace.size: "
       "workspace.obstacles.random.max_size: must not be larger than the "
       "workspace [1, 1], got [2, 2] (in the generated scenario of --sizes "
       "2x1)\n"},
      {{"bench", "--sizes", "5000x1", "--steps", "1", "--repeats", "1",
        "--no-testspeed"},
       "error: command line: --sizes: " + bodies},
      {{"bench", "--expert", "--sizes", "2x2", "--seeds", "1", "--set",
        "targets.list=[{position: [1, 1]}]"},
       "error: command line: --set targets.list: " + list + "--sizes 2x2)\n"},
      {{"dataset", "--size", "5000x1", "--episodes", "1", "--out", out,
        "--quiet"},
       "error: command line: --size: " + bodies},
      {{"dataset", "--size", "2x2", "--episodes", "1", "--set",
        "targets.list=[{position: [1, 1]}]", "--out", out, "--quiet"},
       "error: command line: --set targets.list: " + list + "--size 2x2)\n"},
  };
  for (const auto& [args, err] : cases) {
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << err;
    EXPECT_EQ(r.err, err);
    EXPECT_FALSE(std::filesystem::exists(out)) << err;
  }
  // What the world of a size refuses (more robots than free lattice
  // points), found by building the first seed's world before any work.
  for (const std::vector<std::string>& args :
       {with(eval, {"--sizes", "2000x1"}),
        std::vector<std::string>{"dataset", "--size", "2000x1", "--episodes",
                                 "1", "--first-seed", "0", "--out", out}}) {
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << args[0];
    EXPECT_EQ(r.err.rfind("error: command line: --size" +
                              std::string(args[0] == "eval" ? "s" : "") +
                              ": robots.count: 2000 robots but only ",
                          0),
              0u)
        << r.err;
    EXPECT_NE(r.err.find("(in the generated world of --size"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("2000x1, seed 0)\n"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << r.err;
  }
  std::filesystem::remove_all(dir);
}

TEST(EvalPiecesTest, ErrorsOfGeneratedScenariosNameTheFlagBehindThem) {
  GeneratedSpec spec;
  spec.size = "2x2";
  spec.robots = 2;
  spec.targets = 2;
  spec.seed = 5;
  const auto named = [&spec](const InputError& e) {
    try {
      NameTheFlag(e, spec);
    } catch (const InputError& named) {
      return named.Format();
    }
    return std::string("no error");
  };
  // The generated world of a size it does not fit in, with a --set that
  // has nothing to do with it: the size is named.
  spec.size = "2000x1";
  spec.robots = 2000;
  spec.targets = 1;
  spec.overrides = {ParseSetFlag("sensor.range=3")};
  EXPECT_EQ(named(InputError("(generated scenario)", 0, "robots.count", "x"))
                .rfind("command line: --sizes: robots.count: 2000 robots but "
                       "only ",
                       0),
            0u);
  // A --set that makes the world fail is named.
  spec.size = "40x1";
  spec.robots = 40;
  spec.overrides.push_back(ParseSetFlag("workspace.size=[3, 3]"));
  spec.overrides.push_back(
      ParseSetFlag("workspace.obstacles.random.max_size=[1, 1]"));
  const std::string world =
      named(InputError("(generated scenario)", 0, "robots.count", "x"));
  EXPECT_EQ(world.rfind("command line: --set workspace.size: ", 0), 0u)
      << world;
  EXPECT_NE(world.find("(in the generated world of --sizes 40x1, seed 5)"),
            std::string::npos)
      << world;
  spec.size = "2x2";
  spec.robots = 2;
  spec.targets = 2;
  spec.overrides = {ParseSetFlag("sensor.range=3")};
  // Not found again (the error came from elsewhere): the size is named.
  EXPECT_EQ(named(InputError("(generated scenario)", 0, "robots.count", "x")),
            "command line: --sizes: robots.count: x (in the generated world "
            "of --sizes 2x2, seed 5)");
  // Already about a flag: as it is.
  EXPECT_EQ(named(InputError("command line", 0, "--set sensor.range", "y")),
            "command line: --set sensor.range: y");
  // The first override that breaks the scenario is the one named (here
  // with the reader's own error, which names it already).
  spec.overrides.push_back(ParseSetFlag("robots.start=[[1, 1]]"));
  spec.overrides.push_back(ParseSetFlag("mission.eps=0.5"));
  EXPECT_EQ(named(InputError("", 0, "robots.count", "z")),
            "command line: --set robots.start: has 1 positions but "
            "robots.count is 2; give one [x, y] per robot, or omit start for "
            "random ones");
  // A size refused by itself names the size.
  spec.robots = 6000;
  spec.size = "6000x2";
  EXPECT_EQ(named(InputError("", 0, "robots.count", "z")),
            "command line: --sizes: '6000x2': robots.count: must be an "
            "integer in [1, 5000], got 6000");
  // Sizes whose scenario fits: checked on them rather than on a 1x1 world
  // (which refused a robot index of 2).
  const PolicyRegistry registry = AllPolicies();
  const EvalSetup setup =
      MakeEvalSetup({"greedy"}, {"render.follow_robot=2"}, registry,
                    EnumerateInstances({{3, 1}}, 1, 0));
  EXPECT_EQ(InstanceScenario({"3x1", 3, 1, 0}, setup).render.follow_robot, 2);
  // The seeds of an eval fit in 64 bits.
  EXPECT_EQ(EnumerateInstances({{1, 1}}, 1, 18446744073709551615u).size(), 1u);
  try {
    EnumerateInstances({{1, 1}}, 2, 18446744073709551615u);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "--seed-base");
  }
  // 2^31 - 1 seeds of two sizes: refused before their list (280 GB) is
  // made; a million worlds is the most one evaluation takes.
  EXPECT_THROW(EnumerateInstances({{1, 1}}, 1000001, 0), InputError);
  try {
    EnumerateInstances({{1, 1}, {2, 1}}, 2147483647, 0);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "--seeds");
    EXPECT_NE(e.message().find("4294967294 worlds, more than one evaluation "
                               "takes (1000000)"),
              std::string::npos)
        << e.message();
  }
}

TEST(EvalTest, ResumeRefusesAnotherConfiguration) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  const auto eval = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"eval", "--sizes",    "2x1",    "--seeds",
                                     "2",    "--policies", "greedy", "--out",
                                     dir,    "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    return RunAia(args);
  };
  ASSERT_EQ(eval({"--set", "sensor.range=3"}).exit_code, 0);
  const std::string effective = ReadFile(dir + "/effective.yaml");
  EXPECT_NE(effective.find("range: 3"), std::string::npos) << effective;
  EXPECT_NE(effective.find("\npolicies:\n  greedy: {}\n"), std::string::npos)
      << effective;
  // The same configuration resumes (nothing left to run) ...
  auto r = eval({"--set", "sensor.range=3"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 rows already done, 0 to run"), std::string::npos);
  // ... also when its effective.yaml was written another way (it is
  // compared as a YAML document; here every indentation is doubled).
  {
    std::istringstream in(ReadFile(dir + "/effective.yaml"));
    std::string line, wider;
    while (std::getline(in, line)) {
      const std::size_t indent = line.find_first_not_of(' ');
      if (line.rfind("#", 0) == 0 || indent == std::string::npos)
        wider += line + "\n";
      else
        wider += std::string(2 * indent, ' ') + line.substr(indent) + "\n";
    }
    ASSERT_NE(wider, ReadFile(dir + "/effective.yaml"));
    WriteFileAtomic(dir + "/effective.yaml", wider);
  }
  r = eval({"--set", "sensor.range=3"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 rows already done, 0 to run"), std::string::npos)
      << r.out;
  // ... another does not mix its rows in.
  r = eval({});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("holds results of another configuration (the scenario "
                       "differs"),
            std::string::npos)
      << r.err;
  // Adding a policy to the same configuration is fine.
  r = RunAia({"eval", "--sizes", "2x1", "--seeds", "2", "--policies",
              "greedy,random", "--set", "sensor.range=3", "--out", dir,
              "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 rows already done, 2 to run"), std::string::npos);
  // Rows without the effective.yaml they were made under cannot be checked:
  // refused, not taken as another configuration's.
  std::filesystem::remove(dir + "/effective.yaml");
  r = eval({});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "error: command line: --out: " + dir +
                       " holds 4 rows in runs.csv but no effective.yaml to "
                       "check them against: put back the effective.yaml of "
                       "the run that made them, or use a new folder\n");
  std::filesystem::remove_all(dir);
}

// A structured world set on the generated instances takes the place of
// their random boxes (the two cannot be combined): each seed its own rooms.
TEST(EvalTest, GeneratorSetOnTheGeneratedWorlds) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  const auto r =
      RunAia({"eval", "--sizes", "3x3", "--seeds", "2", "--policies", "greedy",
              "--set", "workspace.obstacles.generator.type=rooms", "--out", dir,
              "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string effective = ReadFile(dir + "/effective.yaml");
  EXPECT_NE(effective.find("type: rooms"), std::string::npos) << effective;
  EXPECT_EQ(effective.find("random:"), std::string::npos) << effective;
  std::istringstream runs(ReadFile(dir + "/runs.csv"));
  std::string line;
  int rows = 0;
  while (std::getline(runs, line)) rows += line.rfind("3x3,", 0) == 0;
  EXPECT_EQ(rows, 2) << ReadFile(dir + "/runs.csv");
  std::filesystem::remove_all(dir);
}

// Issue 19: rows made with a model that was retrained since must not be
// resumed into: effective.yaml records the model by path and SHA-256.
TEST(EvalTest, ResumeRefusesARetrainedModel) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  const std::string model = dir + "/model.pt";
  std::filesystem::copy_file(testing::SourcePath("models/igbnet_10x10.pt"),
                             model);
  const auto eval = [&]() {
    return RunAia({"eval", "--sizes", "2x1", "--seeds", "1", "--policies",
                   "igbnet", "--set", "policy.model=" + model, "--out",
                   dir + "/e", "--quiet"});
  };
  ASSERT_EQ(eval().exit_code, 0);
  const std::string effective = ReadFile(dir + "/e/effective.yaml");
  const auto sha = testing::RunCommand("sha256sum '" + model + "'");
  ASSERT_EQ(sha.exit_code, 0);
  // The policy's parameters and its model file, as a mapping that parses.
  const ConfigNode config = ParseYaml(effective, "effective.yaml");
  ASSERT_NE(config.Find("policies"), nullptr) << effective;
  const ConfigNode* igbnet = config.Find("policies")->Find("igbnet");
  ASSERT_NE(igbnet, nullptr) << effective;
  EXPECT_EQ(
      ShowNode(*igbnet, 100000),
      "{coordination: rules, precision: auto, max_reversals: 1, max_walk: 0, "
      "search: "
      "true, share_search: true, no_undo: true, claims: route, "
      "approach: true, open: neighbours, refresh: 0.003, model: " +
          model + ", model_sha256: " + sha.out.substr(0, 64) + "}")
      << effective;
  EXPECT_EQ(eval().exit_code, 0);  // the same model resumes
  std::filesystem::copy_file(testing::SourcePath("models/igbnet.pt"), model,
                             std::filesystem::copy_options::overwrite_existing);
  const auto r = eval();
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("igbnet's model file differs: another file, or the "
                       "same one retrained"),
            std::string::npos)
      << r.err;
  std::filesystem::remove_all(dir);
}

// effective.yaml in the form an older aia wrote (issue 38): the policies in
// comment lines "#   NAME: PARAMS", a learned one's model after "; model ",
// the expert of F* on a line of its own, then the scenario keys.
std::string OlderForm(const std::string& effective,
                      const std::vector<std::string>& policy_lines) {
  const ConfigNode config = ParseYaml(effective, "effective.yaml");
  ConfigNode expert = *config.Find("policy");
  expert.Erase("name");
  std::string text =
      "# aia eval: the scenario of every instance, overrides applied. Per\n"
      "# instance, robots.count and targets.count are its size and seed its\n"
      "# seed (--sizes, --seeds, --seed-base); the expert gives F*, and each\n"
      "# policy runs with these parameters:\n"
      "#   expert (F*): " +
      ShowNode(expert, 100000) + "\n";
  for (const std::string& line : policy_lines) text += "#   " + line + "\n";
  // The scenario keys: every line from the first key after `policies`.
  std::istringstream in(effective);
  std::string line;
  bool in_policies = false, body = false;
  while (std::getline(in, line)) {
    if (line.rfind("policies:", 0) == 0) in_policies = true;
    if (in_policies && !line.empty() && line[0] != ' ' &&
        line.rfind("policies:", 0) != 0)
      body = true;
    if (body) text += line + "\n";
  }
  return text;
}

// A folder of an older aia, its policies in comment lines, still resumes:
// its rows are kept, its effective.yaml rewritten as a mapping; its model
// lines are still checked.
TEST(EvalTest, AnOlderFolderStillResumes) {
  const std::string dir = testing::MakeTempDir("aia_eval_");
  const std::string model = dir + "/model.pt";
  std::filesystem::copy_file(testing::SourcePath("models/igbnet_10x10.pt"),
                             model);
  const auto eval = [&](const std::string& policies) {
    return RunAia({"eval", "--sizes", "2x1", "--seeds", "2", "--policies",
                   policies, "--set", "policy.model=" + model, "--out",
                   dir + "/e", "--quiet"});
  };
  ASSERT_EQ(eval("greedy,igbnet").exit_code, 0);
  const std::string effective = ReadFile(dir + "/e/effective.yaml");
  const std::string sha =
      testing::RunCommand("sha256sum '" + model + "'").out.substr(0, 64);
  const std::string igbnet_line =
      "igbnet: {coordination: rules, precision: auto, max_reversals: 1, "
      "max_walk: 0, search: true, share_search: true, no_undo: true, claims: "
      "route, approach: true, open: neighbours, refresh: 0.003}; model " +
      model + " sha256 " + sha;
  const std::string older =
      OlderForm(effective, {"greedy: {}", igbnet_line, "random: {}"});
  ASSERT_EQ(older.find("policies"), std::string::npos) << older;
  WriteFileAtomic(dir + "/e/effective.yaml", older);
  auto r = eval("greedy,igbnet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("4 rows already done, 0 to run"), std::string::npos)
      << r.out;
  // Rewritten as this aia writes it, the older folder's other policy kept.
  const ConfigNode folder =
      ParseYaml(ReadFile(dir + "/e/effective.yaml"), "effective.yaml");
  ConfigNode written = ParseYaml(effective, "effective.yaml");
  written.Find("policies")->Set("random", ConfigNode::Map());
  EXPECT_TRUE(SameValue(folder, written))
      << ReadFile(dir + "/e/effective.yaml");
  // An older folder made with another model, or one that did not record it,
  // is refused.
  WriteFileAtomic(
      dir + "/e/effective.yaml",
      OlderForm(effective,
                {"greedy: {}", igbnet_line.substr(0, igbnet_line.size() - 64) +
                                   std::string(64, 'a')}));
  r = eval("greedy,igbnet");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("igbnet's model file differs: another file, or the "
                       "same one retrained"),
            std::string::npos)
      << r.err;
  WriteFileAtomic(
      dir + "/e/effective.yaml",
      OlderForm(effective,
                {"igbnet: {coordination: rules, precision: auto, "
                 "max_reversals: 1, max_walk: 0, search: true, share_search: "
                 "true, no_undo: true, claims: route, approach: true, open: "
                 "neighbours, refresh: 0.003}"}));
  r = eval("igbnet");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("igbnet's model file differs: the folder does not "
                       "record which was used"),
            std::string::npos)
      << r.err;
  // ... and other parameters.
  WriteFileAtomic(dir + "/e/effective.yaml",
                  OlderForm(effective, {"igbnet: {coordination: none}"}));
  r = eval("igbnet");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("igbnet's parameters differ"), std::string::npos)
      << r.err;
  std::filesystem::remove_all(dir);
}

// The folder's configuration compared as trees: the scenario keys, then each
// policy of both (its parameters, then its model file); a policy of one
// alone fits, and the folder's stay in the merged configuration.
TEST(EvalFolderTest, ConfigurationsComparedAsTrees) {
  const auto config = [](const std::string& yaml) {
    return ReadEvalConfig(yaml, "effective.yaml");
  };
  const ConfigNode run = config(
      "policies:\n  greedy: {}\n  igbnet: {claims: route, model: /m.pt, "
      "model_sha256: ab}\nseed: 0\nsensor: {range: 2}\n");
  EXPECT_EQ(ConfigMismatch(run, run), "");
  // Written another way: the same.
  EXPECT_EQ(ConfigMismatch(config("sensor:\n  range: 2\nseed: 0\npolicies:\n"
                                  "  igbnet:\n    model_sha256: ab\n    "
                                  "model: /m.pt\n    claims: route\n"),
                           run),
            "");
  EXPECT_EQ(ConfigMismatch(config("policies: {}\nseed: 0\nsensor: {range: "
                                  "3}\n"),
                           run),
            "the scenario differs (--set)");
  EXPECT_EQ(ConfigMismatch(config("policies: {igbnet: {claims: none, model: "
                                  "/m.pt, model_sha256: ab}}\nseed: "
                                  "0\nsensor: {range: 2}\n"),
                           run),
            "igbnet's parameters differ");
  EXPECT_EQ(ConfigMismatch(config("policies: {igbnet: {claims: route, model: "
                                  "/m.pt, model_sha256: cd}}\nseed: "
                                  "0\nsensor: {range: 2}\n"),
                           run),
            "igbnet's model file differs: another file, or the same one "
            "retrained (its SHA-256 changed)");
  // An older folder's comment lines read as the same tree.
  const ConfigNode older = config(
      "# aia eval: ...\n#   expert (F*): {p_v: 0.9}\n#   greedy: {}\n"
      "#   igbnet: {claims: route}; model /m.pt sha256 ab\n"
      "#   decsb: {horizon: 4}\nseed: 0\nsensor: {range: 2}\n");
  EXPECT_EQ(ConfigMismatch(older, run), "");
  const ConfigNode merged = WithFolderPolicies(older, run);
  EXPECT_EQ(ShowNode(*merged.Find("policies"), 1000),
            "{greedy: {}, igbnet: {claims: route, model: /m.pt, model_sha256: "
            "ab}, decsb: {horizon: 4}}");
  // A `policies` key that is not a mapping of mappings is bad input at its
  // line.
  for (const std::string& bad :
       {std::string("seed: 0\npolicies: [greedy]\n"),
        std::string("seed: 0\npolicies:\n  greedy: 3\n")}) {
    try {
      config(bad);
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "effective.yaml");
      EXPECT_GE(e.line(), 2) << e.Format();
      EXPECT_EQ(e.key().rfind("policies", 0), 0u) << e.Format();
    }
  }
}

}  // namespace
}  // namespace aia
