// The command line: bad input gives `error: FILE:LINE: key: ...` and exit 2,
// every scenario runs, the same seed gives byte-identical results.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "support/test_support.h"

namespace aia {
namespace {

using testing::ReadFile;
using testing::RunAia;
using testing::SourcePath;

namespace fs = std::filesystem;

struct Expectation {
  int line = 0;
  std::string key, substring;
};

Expectation ReadExpectation(const std::string& path) {
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  static const std::regex re("^# expect: ([0-9]+): ([^:]+): (.*)$");
  std::smatch m;
  Expectation e;
  if (std::regex_match(first, m, re)) {
    e.line = std::stoi(m[1]);
    e.key = m[2];
    e.substring = m[3];
  }
  return e;
}

std::vector<std::string> BadFiles() {
  std::vector<std::string> files;
  // tests/data/bad: rejected by the loader; tests/data/bad_world: loads,
  // but the world or the policy refuses it.
  for (const char* dir : {"tests/data/bad", "tests/data/bad_world"})
    for (const auto& entry : fs::directory_iterator(SourcePath(dir)))
      if (entry.path().extension() == ".yaml")
        files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

class BadInputTest : public ::testing::TestWithParam<std::string> {};

TEST_P(BadInputTest, PrintsFileLineKeyAndExitsWith2) {
  const std::string file = GetParam();
  const Expectation e = ReadExpectation(file);
  ASSERT_FALSE(e.key.empty()) << file << " lacks its '# expect:' line";
  const std::string out = testing::MakeTempDir("aia_bad_");
  const auto r = RunAia({"run", file, "--out", out, "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::string prefix = "error: " + file +
                             (e.line > 0 ? ":" + std::to_string(e.line) : "") +
                             ": " + e.key + ": ";
  EXPECT_EQ(r.err.rfind(prefix, 0), 0u)
      << "stderr: " << r.err << "expected prefix: " << prefix;
  EXPECT_NE(r.err.find(e.substring), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1)
      << "one line: " << r.err;
  EXPECT_FALSE(fs::exists(out + "/summary.json"));
  fs::remove_all(out);
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInputTest, ::testing::ValuesIn(BadFiles()),
                         [](const auto& info) {
                           const fs::path p(info.param);
                           return p.parent_path().filename().string() + "_" +
                                  p.stem().string();
                         });

TEST(CliTest, MissingScenarioFile) {
  const auto r = RunAia({"run", "/nonexistent/none.yaml", "--quiet"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err.rfind("error: /nonexistent/none.yaml: (file): cannot read file", 0),
      0u)
      << r.err;
}

TEST(CliTest, UnknownPolicyFlagListsValidNames) {
  const auto r = RunAia({"run", SourcePath("scenarios/default.yaml"),
                         "--policy", "nope", "--quiet"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(
      r.err.find("--policy: unknown policy 'nope' (valid: random, greedy"),
      std::string::npos)
      << r.err;
}

TEST(CliTest, UnknownFlagAndMissingArgumentExitWith2) {
  EXPECT_EQ(RunAia({"run", SourcePath("scenarios/default.yaml"), "--bogus"})
                .exit_code,
            2);
  EXPECT_EQ(RunAia({"run"}).exit_code, 2);
  EXPECT_EQ(RunAia({}).exit_code, 2);
  EXPECT_EQ(RunAia({"bench", "--sizes", "10by10"}).exit_code, 2);
  // A word that is no command is named (CLI11 said "A subcommand is
  // required").
  const auto unknown = RunAia({"RUN", SourcePath("scenarios/default.yaml")});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_EQ(unknown.err,
            "error: command line: 'RUN' is not a command; the commands are "
            "run, render, plan, world, eval, bench, dataset, train, policies, "
            "schema (aia --help lists them)\n");
  // One within two edits of a command is named.
  EXPECT_EQ(RunAia({"evl"}).err,
            "error: command line: 'evl' is not a command (did you mean "
            "`eval`?); the commands are run, render, plan, world, eval, "
            "bench, dataset, train, policies, schema (aia --help lists "
            "them)\n");
}

// aia bench's row: every column a number, mujoco-testspeed's rate and
// contacts read from its output (robots at rest there: no contact), the
// episodes' contacts per mj_step not negative.
TEST(CliTest, BenchRowHasEveryColumn) {
  const auto r =
      RunAia({"bench", "--sizes", "3x3", "--steps", "2", "--repeats", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line, header, row;
  while (std::getline(lines, line)) {
    if (line.rfind("size ", 0) == 0) header = line;
    if (line.rfind("3x3 ", 0) == 0) row = line;
  }
  std::istringstream h(header), v(row);
  std::vector<std::string> names, values;
  for (std::string w; h >> w;) names.push_back(w);
  for (std::string w; v >> w;) values.push_back(w);
  ASSERT_EQ(names.size(), 13u) << header;
  ASSERT_EQ(values.size(), names.size()) << row;
  EXPECT_EQ(names[10], "testspeed/s");
  EXPECT_EQ(names[12], "ts_contacts");
  EXPECT_GT(std::stod(values[10]), 0.0) << "mujoco-testspeed did not run";
  EXPECT_EQ(std::stod(values[12]), 0.0);
  EXPECT_GE(std::stod(values[11]), 0.0);
  // One run's row (of two): its phases add up to its ms/step (to the
  // printed digits) and steps/s is 1000 / ms/step. Medians taken column by
  // column apart did not.
  const double ms = std::stod(values[2]);
  double phases = 0.0;
  for (int c = 3; c <= 7; ++c) phases += std::stod(values[c]);
  EXPECT_NEAR(phases, ms, 0.003) << row;
  // steps/s comes from the unrounded ms/step: printed to 0.0005 ms, the
  // step's 1000 / ms is known to 1000 * 0.0005 / (ms (ms - 0.0005)) (more
  // than 1e-3 of itself below half a millisecond a step), plus its own 0.05.
  EXPECT_NEAR(std::stod(values[1]), 1000.0 / ms,
              0.06 + 0.5 / (ms * (ms - 0.0005)) + 1e-6 * 1000.0 / ms)
      << row;
}

// Flags the parser refuses read like any bad input: one `error:` line.
TEST(CliTest, ParserErrorsAreOneErrorLine) {
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", scenario, "--bogus"},
       "error: command line: --bogus: unknown option (aia run --help lists "
       "the options)\n"},
      // A typo of a flag is named with the flag it is a typo of, before the
      // value CLI11 would also list as unexpected.
      {{"run", scenario, "--sed", "3"},
       "error: command line: --sed: unknown option (did you mean `--seed`?) "
       "(aia run --help lists the options)\n"},
      {{"eval", "--out", "x", "--sizes=2x2", "--polices=random"},
       "error: command line: --polices: unknown option (did you mean "
       "`--policies`?) (aia eval --help lists the options)\n"},
      {{"--verison"},
       "error: command line: --verison: unknown option (did you mean "
       "`--version`?) (aia --help lists the options)\n"},
      // A word that is no flag keeps CLI11's words; after `--` nothing is a
      // flag.
      {{"run", scenario, "extra"},
       "error: command line: The following argument was not expected: "
       "extra (aia run --help lists the options)\n"},
      {{"run", scenario, "--", "--seed"},
       "error: command line: The following argument was not expected: "
       "--seed (aia run --help lists the options)\n"},
      // Declared flags are read as the scenario keys are.
      // Beyond the field's type, its bound is said (issue 37).
      {{"eval", "--seeds", "1000000000000", "--out", "x"},
       "error: command line: --seeds: must be an integer >= 1 that fits in "
       "32 bits (at most 2147483647), got 1000000000000\n"},
      {{"render", scenario, "--out", "x.mp4", "--width",
        "99999999999999999999"},
       "error: command line: --width: must be an integer in [16, 8192], "
       "got 99999999999999999999\n"},
      // An empty item of a list flag is a mistake, not one item fewer.
      {{"eval", "--sizes", "2x2,,3x3", "--out", "x"},
       "error: command line: --sizes: '2x2,,3x3' has an empty item; separate "
       "the items by one comma\n"},
      {{"eval", "--sizes", "2x2", "--policies", "random,", "--out", "x"},
       "error: command line: --policies: 'random,' has an empty item; "
       "separate the items by one comma\n"},
      // strtoull alone would read -1 as 18446744073709551615.
      {{"run", scenario, "--seed", "-1"},
       "error: command line: --seed: must be an integer >= 0, got -1\n"},
      {{"dataset", "--episodes", "1", "--out", "x", "--first-seed", "0x10"},
       "error: command line: --first-seed: must be an integer >= 0, got "
       "0x10\n"},
      // A flag given twice, in aia's words (CLI11's "At Most 1 required
      // but received 2" before).
      {{"run", scenario, "--seed", "1", "--seed", "2"},
       "error: command line: --seed: given 2 times; give it once (aia run "
       "--help lists the options)\n"},
      // A document that is not a mapping is the file's error, also with a
      // flag that sets a key in it (the flag was blamed).
      {{"run", SourcePath("tests/data/bad/top_level_list.yaml"), "--max-steps",
        "2"},
       "error: " + SourcePath("tests/data/bad/top_level_list.yaml") +
           ":2: (document): must be a mapping with keys among name, seed, "
           "workspace, robots, sensor, targets, mission, communication, "
           "policy, physics, render, got [robots, targets]\n"},
      // A --set given twice, or a section after a key in it: the later
      // silently undid the earlier (a key twice in a file is an error).
      {{"run", scenario, "--set", "seed=5", "--set", "seed=9"},
       "error: command line: --set seed: given twice (=5, then =9); give it "
       "once\n"},
      {{"eval", "--sizes", "3x3", "--seeds", "1", "--set", "sensor.range=3",
        "--set", "sensor={range: 2}", "--out", "/nonexistent/aia_eval"},
       "error: command line: --set sensor: replaces the whole section, and "
       "an earlier --set gives sensor.range in it; give the section once, or "
       "its keys one by one\n"},
      // A key inside a --set value is named under the path it sets (the
      // error said only --set).
      {{"run", scenario, "--set", "robots={count: 2, count: 3}"},
       "error: command line: --set robots.count: duplicate key (first given "
       "at line 1); give each key once\n"},
      // A model no evaluated policy reads changed nothing, unsaid.
      {{"eval", "--sizes", "3x3", "--seeds", "1", "--policies", "greedy",
        "--set", "policy.model=" + SourcePath("models/igbnet.pt"), "--out",
        "/nonexistent/aia_eval"},
       "error: command line: --set policy.model: no policy of this "
       "evaluation reads a model (a learned policy does: igbnet)\n"},
      {{"plan", scenario, "--budget", "many"},
       "error: command line: --budget: must be an integer in [0, "
       "1000000000], got many\n"},
      // As policy.anytime takes it: a plan's effective.yaml must load.
      {{"plan", scenario, "--budget", "99999999999"},
       "error: command line: --budget: must be an integer in [0, "
       "1000000000], got 99999999999\n"},
      // plan runs the expert; --budget is its anytime (a --set of either
      // named --policy, which plan lacks, or was overruled in silence).
      {{"plan", scenario, "--set", "policy.name=expert"},
       "error: command line: --set policy.name: aia plan runs the expert "
       "(C-SB) and sets policy.name itself; set the expert's keys one by one "
       "(--set policy.KEY=VALUE)\n"},
      {{"plan", scenario, "--budget", "7", "--set", "policy.anytime=5"},
       "error: command line: --set policy.anytime: is also given by "
       "--budget; give one of them\n"},
      {{"render", scenario, "--out", "x.mp4", "--width", "wide"},
       "error: command line: --width: must be an integer in [16, 8192], got "
       "wide\n"},
      {{},
       "error: command line: A subcommand is required (aia --help lists "
       "the options)\n"},
  };
  for (const auto& [args, err] : cases) {
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << err;
    EXPECT_EQ(r.err, err);
  }
}

// Benchmark sizes have ranges in every mode (--network --repeats 0 used to
// take the median of nothing and crash).
TEST(CliTest, BenchCountsOutOfRangeExitWith2) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"bench", "--network", "--repeats", "0"},
       "--repeats: must be an integer in [1, 1000], got 0"},
      {{"bench", "--repeats", "100000"},
       "--repeats: must be an integer in [1, 1000], got 100000"},
      {{"bench", "--expert", "--seeds", "0"},
       "--seeds: must be an integer in [1, 100000], got 0"},
      {{"bench", "--steps", "1000001"},
       "--steps: must be an integer in [1, 1000000], got 1000001"},
      {{"bench", "--policy-threads", "0"},
       "--policy-threads: must be an integer in [1, 256], got 0"},
      // A flag the mode does not read was ignored, even a bad one.
      {{"bench", "--network", "--set", "nosuch.key=1"},
       "--set: is not read by aia bench with --network"},
      {{"bench", "--expert", "--policy", "nosuch"},
       "--policy: is not read by aia bench with --expert"},
      {{"bench", "--network", "--policy-threads", "2"},
       "--policy-threads: is not read by aia bench with --network"},
      {{"bench", "--seeds", "3"},
       "--seeds: is not read by aia bench without "
       "--expert"},
      {{"bench", "--sizes", "2x2,2x2"}, "--sizes: 2x2 is given twice"},
      {{"bench", "--network", "--sizes", "3x3"},
       "--sizes: is not read by aia bench with --network"},
      // aia eval's counts, from the same kind of declaration.
      {{"eval", "--seeds", "0", "--out", "/nonexistent/aia_eval"},
       "--seeds: must be an integer >= 1, got 0"},
      {{"eval", "--threads", "-1", "--out", "/nonexistent/aia_eval"},
       "--threads: must be an integer >= 0, got -1"},
  };
  for (const auto& [args, message] : cases) {
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << message;
    EXPECT_EQ(r.err.rfind("error: command line: " + message, 0), 0u) << r.err;
  }
}

// An output file's path that is a pipe (or a device, or a folder) is refused
// before any work; renaming the finished file onto it would replace it.
TEST(CliTest, OutputFileThatIsNotARegularFileIsRefused) {
  const std::string dir = testing::MakeTempDir("aia_fifo_");
  const std::string fifo = dir + "/pipe.xml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const std::string scenario = SourcePath("scenarios/default.yaml");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"world", scenario, "--out", fifo},
        std::vector<std::string>{"plan", scenario, "--out", fifo}}) {
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << args[0];
    EXPECT_EQ(r.err, "error: command line: --out: cannot write '" + fifo +
                         "': it is a named pipe (FIFO), not a regular file; "
                         "give a file's path\n");
    struct stat st;
    ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode)) << args[0] << " replaced the pipe";
  }
  std::filesystem::remove_all(dir);
}

TEST(CliTest, UncreatableOutputFolderIsBadInput) {
  const auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--out",
                         "/proc/aia-no-such-dir/out", "--quiet"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err.rfind("error: command line: --out: cannot create directory", 0), 0u)
      << r.err;
}

TEST(CliTest, HelpOnEveryCommand) {
  for (const std::string cmd :
       {"", "run", "render", "plan", "world", "eval", "bench", "dataset",
        "train", "policies", "schema"}) {
    std::vector<std::string> args;
    if (!cmd.empty()) args.push_back(cmd);
    args.push_back("--help");
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << cmd << ": " << r.out;
  }
}

std::vector<std::string> ScenarioFiles() {
  std::vector<std::string> files;
  // scenarios/long/ (the expert's long-horizon worlds) included.
  for (const auto& entry :
       fs::recursive_directory_iterator(SourcePath("scenarios")))
    if (entry.path().extension() == ".yaml")
      files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

class ScenarioFileTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ScenarioFileTest, RunsAFewSteps) {
  const std::string out = testing::MakeTempDir("aia_scn_");
  const auto r =
      RunAia({"run", GetParam(), "--max-steps", "3", "--out", out, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string summary = ReadFile(out + "/summary.json");
  EXPECT_NE(summary.find("\"steps\""), std::string::npos);
  const std::string trace = ReadFile(out + "/trace.csv");
  EXPECT_EQ(trace.rfind("step,target,min_det,det_r0", 0), 0u);
  fs::remove_all(out);
}

INSTANTIATE_TEST_SUITE_P(Scenarios, ScenarioFileTest,
                         ::testing::ValuesIn(ScenarioFiles()),
                         [](const auto& info) {
                           return fs::path(info.param).stem().string();
                         });

std::string WithoutWallTime(const std::string& json) {
  return std::regex_replace(json, std::regex("\"wall_s\": [^\n]*"),
                            "\"wall_s\": X");
}

TEST(CliTest, SameScenarioAndSeedGiveByteIdenticalResults) {
  const std::string a = testing::MakeTempDir("aia_det_"),
                    b = testing::MakeTempDir("aia_det_");
  for (const auto& dir : {a, b}) {
    const auto r =
        RunAia({"run", SourcePath("scenarios/robustness.yaml"), "--policy",
                "greedy", "--max-steps", "40", "--out", dir, "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  EXPECT_EQ(ReadFile(a + "/trace.csv"), ReadFile(b + "/trace.csv"));
  EXPECT_EQ(WithoutWallTime(ReadFile(a + "/summary.json")),
            WithoutWallTime(ReadFile(b + "/summary.json")));
  // A different seed gives a different mission.
  const auto r =
      RunAia({"run", SourcePath("scenarios/robustness.yaml"), "--seed", "99",
              "--max-steps", "40", "--out", b, "--quiet"});
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_NE(ReadFile(a + "/trace.csv"), ReadFile(b + "/trace.csv"));
  fs::remove_all(a);
  fs::remove_all(b);
}

// Every robot failed at step 0: no robot is active, so no minimum det
// Sigma. trace.csv leaves the field empty (it wrote "inf"), as
// summary.json's final_min_det is null; aia bench, with no step to time,
// says so (it printed -nan).
TEST(CliTest, NoActiveRobotWritesNoInfinityAndBenchHasNothingToTime) {
  const std::string dir = testing::MakeTempDir("aia_all_failed_");
  const std::string failures =
      "communication.failures=[{robot: 0, step: 0}, {robot: 1, step: 0}]";
  const auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--out",
                         dir, "--quiet", "--policy", "greedy", "--set",
                         "robots.count=2", "--set", failures});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string trace = ReadFile(dir + "/trace.csv");
  EXPECT_EQ(trace.find("inf"), std::string::npos) << trace;
  EXPECT_EQ(trace.find("nan"), std::string::npos) << trace;
  EXPECT_NE(trace.find("\n0,0,,1.000000e+00,"), std::string::npos) << trace;
  const auto b = RunAia({"bench", "--steps", "2", "--repeats", "1",
                         "--no-testspeed", "--sizes", "1x1", "--set",
                         "communication.failures=[{robot: 0, step: 0}]"});
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_EQ(b.err,
            "error: command line: --sizes 1x1: the mission ended before its "
            "first decision step (no robot active: every robot fails at step "
            "0?), so there is nothing to time\n");
  EXPECT_EQ(b.out.find("nan"), std::string::npos) << b.out;
  fs::remove_all(dir);
}

// aia eval ends each run at 3 F* and aia bench after --steps: a --set
// mission.max_steps was written to effective.yaml and ignored.
TEST(CliTest, EvalAndBenchRefuseASetMaxSteps) {
  const std::string dir = testing::MakeTempDir("aia_eval_max_steps_");
  const std::string expect =
      "error: command line: --set mission.max_steps: is set by the command, "
      "not by --set: aia eval runs each mission to 3 F* of the expert's "
      "plan, aia bench for --steps decision steps\n";
  const auto e =
      RunAia({"eval", "--sizes", "1x1", "--seeds", "1", "--policies", "random",
              "--quiet", "--set", "mission.max_steps=1", "--out", dir + "/e"});
  EXPECT_EQ(e.exit_code, 2);
  EXPECT_EQ(e.err, expect);
  const auto b =
      RunAia({"bench", "--steps", "2", "--repeats", "1", "--no-testspeed",
              "--sizes", "1x1", "--set", "mission.max_steps=3"});
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_EQ(b.err, expect);
  fs::remove_all(dir);
}

// A key that changes nothing where it stands runs, with one warning line on
// stderr naming the flag (or the file's line): once per command, however
// many worlds an evaluation reads.
TEST(CliTest, AKeyThatChangesNothingIsWarnedOfOnce) {
  const std::string dir = testing::MakeTempDir("aia_inert_");
  const std::string expect =
      "warning: command line: --set communication.range: applies to "
      "communication.mode range only; with mode full every pair of active "
      "robots talks, so it changes nothing\n";
  const auto r =
      RunAia({"run", testing::SourcePath("scenarios/default.yaml"), "--policy",
              "greedy", "--max-steps", "2", "--set", "communication.range=5",
              "--out", dir + "/run", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, expect);
  const auto e = RunAia({"eval", "--sizes", "2x2", "--seeds", "3", "--policies",
                         "greedy", "--out", dir + "/eval", "--quiet", "--set",
                         "communication.range=5"});
  EXPECT_EQ(e.exit_code, 0) << e.err;
  EXPECT_EQ(e.err, expect);
  fs::remove_all(dir);
}

// A model for a policy that reads none: a warning at its line (or flag),
// but not for the file's model where the command line switched away from
// the file's policy.
TEST(CliTest, AModelForAPolicyThatReadsNoneIsWarnedOf) {
  const std::string dir = testing::MakeTempDir("aia_nomodel_");
  const std::string file = dir + "/greedy.yaml";
  std::ofstream(file) << "robots: {count: 2}\n"
                         "targets: {count: 2}\n"
                         "policy: {name: greedy, model: nowhere.pt}\n"
                         "mission: {max_steps: 1}\n";
  const auto r = RunAia({"run", file, "--out", dir + "/a", "--quiet"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "warning: " + file +
                       ":3: policy.model: policy greedy reads no model: it "
                       "changes nothing\n");
  const auto flag =
      RunAia({"run", testing::SourcePath("scenarios/default.yaml"), "--policy",
              "random", "--set", "policy.model=" + file, "--max-steps", "1",
              "--out", dir + "/b", "--quiet"});
  EXPECT_EQ(flag.exit_code, 0) << flag.err;
  EXPECT_EQ(flag.err,
            "warning: command line: --set policy.model: policy random reads "
            "no model: it changes nothing\n");
  const auto other = RunAia(
      {"run", file, "--policy", "random", "--out", dir + "/c", "--quiet"});
  EXPECT_EQ(other.exit_code, 0) << other.err;
  EXPECT_EQ(other.err, "");
  // The command line's model for the file's policy.
  const std::string plain = dir + "/plain.yaml";
  std::ofstream(plain) << "robots: {count: 2}\n"
                          "targets: {count: 2}\n"
                          "policy: {name: greedy}\n"
                          "mission: {max_steps: 1}\n";
  const auto set = RunAia({"run", plain, "--set", "policy.model=" + file,
                           "--out", dir + "/d", "--quiet"});
  EXPECT_EQ(set.exit_code, 0) << set.err;
  EXPECT_EQ(set.err,
            "warning: command line: --set policy.model: policy greedy reads "
            "no model: it changes nothing\n");
  fs::remove_all(dir);
}

// Wheeled robots with absurd motors (10 g, 1000 N m): MuJoCo resets their
// unstable state. The run writes its files and exits 0, but says so on
// stderr, naming the counts that diagnostics.json holds and what to change.
TEST(CliTest, AnUnstablePhysicsStateIsWarnedOf) {
  const std::string dir = testing::MakeTempDir("aia_qacc_");
  const std::string file = dir + "/motors.yaml";
  std::ofstream(file) << "name: motors\n"
                         "seed: 2\n"
                         "workspace: {size: [12, 12]}\n"
                         "robots:\n"
                         "  count: 3\n"
                         "  model: diff_drive\n"
                         "  diff_drive: {mass: 0.01, max_torque: 1000, "
                         "max_speed: 100}\n"
                         "targets: {count: 2}\n"
                         "policy: {name: greedy}\n"
                         "mission: {max_steps: 4}\n"
                         "physics: {timestep: 0.02}\n";
  const auto r = RunAia({"run", file, "--out", dir + "/out", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string diagnostics = ReadFile(dir + "/out/diagnostics.json");
  std::smatch count;
  ASSERT_TRUE(std::regex_search(diagnostics, count,
                                std::regex("\"bad_qacc\": ([0-9]+)")))
      << diagnostics;
  const std::string unstable =
      "warning: motors, seed 2: MuJoCo reset an unstable state " +
      count[1].str() + " time" + (count[1] == "1" ? "" : "s") + " (bad_qacc " +
      count[1].str() +
      "): the robots' motion after it is not physical (too strong a motor for "
      "its mass and time step: lower robots.diff_drive.max_torque, raise "
      "robots.diff_drive.mass or lower physics.timestep)\n";
  ASSERT_EQ(r.err.substr(0, unstable.size()), unstable) << r.err;
  // Such motion is chaotic (the counts differ between builds): whether any
  // robot still arrives somewhere does too. If none does, that is said.
  const std::string rest = r.err.substr(unstable.size());
  EXPECT_TRUE(
      rest.empty() ||
      std::regex_match(rest, std::regex("warning: motors, seed 2: no robot "
                                        "reached the lattice point it drove "
                                        "to in [0-9]+ moves \\([^\n]*\n")))
      << rest;
  // aia eval writes no diagnostics per run: it says it per run.
  const auto e = RunAia({"eval",        "--sizes",
                         "3x2",         "--seeds",
                         "1",           "--policies",
                         "greedy",      "--out",
                         dir + "/eval", "--quiet",
                         "--set",       "robots.model=diff_drive",
                         "--set",       "robots.diff_drive.mass=0.01",
                         "--set",       "robots.diff_drive.max_torque=1000",
                         "--set",       "robots.diff_drive.max_speed=100",
                         "--set",       "physics.timestep=0.02"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_TRUE(std::regex_search(
      e.err, std::regex("^warning: aia eval: 3x2, seed 0, greedy: MuJoCo "
                        "reset an unstable state [0-9]+ times \\(bad_qacc "
                        "[0-9]+\\): the robots' motion after it is not "
                        "physical")))
      << e.err;
}

// Wheeled robots: the same mission twice gives the same files, which report
// robot_model, the simulated seconds it took (each decision step at least a
// 0.5 m drive at 0.7 m/s) and each robot's stalls and timeouts; eval takes the
// model with --set and times its rows in seconds too.
// A learned policy's renderers keep grids over the whole workspace, one pixel
// per lattice step (AtLatticeStep): a 10 km world at the model's 0.5 m asked
// for 20 GB and was killed by the kernel, and was then refused; at a 10 m
// lattice step it is 1000 x 1000 pixels, as many as lattice points, and
// runs.
TEST(CliTest, AWorkspaceOfALargeStepIsReadAtItsStep) {
  const std::string dir = testing::MakeTempDir("aia_huge_world_");
  const auto r = RunAia({"run",
                         SourcePath("scenarios/default.yaml"),
                         "--out",
                         dir,
                         "--quiet",
                         "--policy",
                         "igbnet",
                         "--max-steps",
                         "1",
                         "--set",
                         "workspace.size=[10000,10000]",
                         "--set",
                         "robots.step=10",
                         "--set",
                         "robots.radius=1",
                         "--set",
                         "workspace.cell=10",
                         "--set",
                         "sensor.range=30",
                         "--set",
                         "robots.count=1",
                         "--set",
                         "targets.count=1",
                         "--set",
                         "workspace.obstacles.random.count=0"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir + "/summary.json"));
  fs::remove_all(dir);
}

// Wheeled robots whose every move ends at a step timeout too short for them
// run, but say so (point robots are refused ahead; this used to be silent).
TEST(CliTest, WheeledRobotsThatNeverArriveAreWarnedOf) {
  const std::string dir = testing::MakeTempDir("aia_no_arrival_");
  const auto r = RunAia({"run", SourcePath("scenarios/wheeled.yaml"), "--out",
                         dir, "--quiet", "--max-steps", "3", "--set",
                         "physics.step_timeout=0.001"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.rfind("warning: wheeled, seed 3: no robot reached the "
                        "lattice point it drove to in 18 moves (18 ended at "
                        "physics.step_timeout, 0 stalled)",
                        0),
            0u)
      << r.err;
  fs::remove_all(dir);
}

TEST(CliTest, DiffDriveRunsRepeatAndCountSeconds) {
  const std::string a = testing::MakeTempDir("aia_dd_"),
                    b = testing::MakeTempDir("aia_dd_");
  for (const auto& dir : {a, b}) {
    const auto r = RunAia({"run", SourcePath("scenarios/robustness.yaml"),
                           "--set", "robots.model=diff_drive", "--max-steps",
                           "12", "--out", dir, "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");  // no warning: the motors are sane
  }
  EXPECT_EQ(ReadFile(a + "/trace.csv"), ReadFile(b + "/trace.csv"));
  const std::string summary = ReadFile(a + "/summary.json");
  EXPECT_EQ(WithoutWallTime(summary),
            WithoutWallTime(ReadFile(b + "/summary.json")));
  EXPECT_NE(summary.find("\"robot_model\": \"diff_drive\""), std::string::npos)
      << summary;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      summary, m,
      std::regex("\"steps\": ([0-9]+)[^}]*\"mission_seconds\": "
                 "([0-9.e+-]+)")))
      << summary;
  EXPECT_GT(std::stod(m[2]), std::stoi(m[1]) * 0.5 / 0.7);
  const std::string diagnostics = ReadFile(a + "/diagnostics.json");
  EXPECT_TRUE(std::regex_search(
      diagnostics,
      std::regex("\"robot_stalls\": \\[(\\s*[0-9]+,){4}\\s*[0-9]+\\s*\\]")))
      << diagnostics;
  const auto e = RunAia({"eval", "--sizes", "2x2", "--seeds", "2", "--policies",
                         "greedy", "--set", "robots.model=diff_drive", "--out",
                         b + "/eval", "--quiet"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const std::string runs = ReadFile(b + "/eval/runs.csv");
  std::smatch row;
  ASSERT_TRUE(std::regex_search(
      runs, row,
      std::regex("\n2x2,0,greedy,1,([0-9]+),[^,]*,[^,]*,[^,]*,[^,]*,"
                 "([0-9.]+),")))
      << runs;
  EXPECT_GT(std::stod(row[2]), std::stoi(row[1]) * 0.5 / 0.7);
  fs::remove_all(a);
  fs::remove_all(b);
}

// The text between `<!-- BEGIN name -->` and `<!-- END name -->`.
std::string Section(const std::string& doc, const std::string& name) {
  const std::string begin = "<!-- BEGIN " + name + " -->\n";
  const std::size_t a = doc.find(begin);
  const std::size_t b = doc.find("<!-- END " + name + " -->");
  if (a == std::string::npos || b == std::string::npos) return "(missing)";
  return doc.substr(a + begin.size(), b - a - begin.size());
}

std::string TrimEnd(std::string s) {
  while (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

TEST(CliTest, DocsTablesAreTheDeclarations) {
  const std::string doc = ReadFile(SourcePath("docs/scenarios.md"));
  for (const std::string cmd : {"schema", "policies"}) {
    const auto r = RunAia({cmd, "--markdown"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(TrimEnd(Section(doc, "aia " + cmd + " --markdown")),
              TrimEnd(r.out))
        << "docs/scenarios.md is out of date: run tools/update_docs.sh";
  }
}

TEST(CliTest, PoliciesListsEveryPolicyWithItsParameters) {
  const auto r = RunAia({"policies"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* text :
       {"random (distributed)", "greedy (distributed)", "expert (centralized)",
        "decsb (distributed)", "policy.p_v", "policy.anytime", "20000",
        "policy.horizon", "integer in [1, 1000]"})
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
}

TEST(CliTest, RunWritesItsResultFiles) {
  const std::string out = testing::MakeTempDir("aia_files_");
  const auto r = RunAia({"run", SourcePath("scenarios/tracking.yaml"),
                         "--max-steps", "6", "--out", out, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(out))
    files.insert(entry.path().filename().string());
  EXPECT_EQ(files,
            (std::set<std::string>{"summary.json", "trace.csv", "estimate.csv",
                                   "effective.yaml", "diagnostics.json"}));
  const std::string estimate = ReadFile(out + "/estimate.csv");
  EXPECT_EQ(estimate.rfind("step,target,robot,error_m,nees\n", 0), 0u);
  EXPECT_EQ(std::count(estimate.begin(), estimate.end(), '\n'), 1 + 7 * 2);
  const std::string diagnostics = ReadFile(out + "/diagnostics.json");
  for (const char* key :
       {"\"policy_status\"", "\"no_valid_move\"", "\"policy_counters\"",
        "\"timeouts\"", "\"rmse_m\"", "\"mean_nees\""})
    EXPECT_NE(diagnostics.find(key), std::string::npos) << key;
  fs::remove_all(out);
}

// policy.precision follows the CPU: with oneDNN capped below bfloat16
// (its ONEDNN_MAX_CPU_ISA) bfloat16 is refused at its key and auto stays
// float32 at 100 robots; uncapped, on a CPU that has it, auto is bfloat16
// there (diagnostics.json counts the decisions).
TEST(CliTest, PolicyPrecisionFollowsTheCpu) {
  const std::string out = testing::MakeTempDir("aia_precision_");
  const std::string aia = "'" + std::string(AIA_BINARY) + "' run '" +
                          SourcePath("scenarios/default.yaml") +
                          "' --policy igbnet --max-steps 1 --quiet --out " +
                          out;
  const auto refused = testing::RunCommand("ONEDNN_MAX_CPU_ISA=AVX2 " + aia +
                                           " --set policy.precision=bfloat16");
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_EQ(refused.err,
            "error: command line: --set policy.precision: bfloat16: this CPU "
            "has no native bfloat16 (AMX-BF16 or AVX-512 BF16), or libtorch "
            "has no oneDNN; use float32 or auto\n");
  const std::string team =
      " --set robots.count=100 --set targets.count=100 --set "
      "workspace.size=[40,40]";
  const auto counted = [&](const std::string& env) {
    const auto r = testing::RunCommand(env + aia + team);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const std::string d = ReadFile(out + "/diagnostics.json");
    const std::string key = "\"bfloat16_decisions\": ";
    const std::size_t at = d.find(key);
    return at == std::string::npos ? -1L : std::stol(d.substr(at + key.size()));
  };
  EXPECT_EQ(counted("ONEDNN_MAX_CPU_ISA=AVX512_CORE "), 0);
  // The kernel's flags say whether the CPU has it (a container's view of
  // /proc/cpuinfo may lack them; then nothing is asserted).
  const std::string cpu = ReadFile("/proc/cpuinfo");
  const bool has = cpu.find(" avx512_bf16") != std::string::npos ||
                   cpu.find(" amx_bf16") != std::string::npos;
  const long native = counted("");
  // 100 robots decide at step 0 (but those the walk moves).
  if (has) {
    EXPECT_GT(native, 50);
    EXPECT_LE(native, 100);
  }
  fs::remove_all(out);
}

TEST(CliTest, WorldWritesAnMjcfThatMujocoLoads) {
  const std::string dir = testing::MakeTempDir("aia_world_");
  const std::string scenario = dir + "/placed.yaml";
  // Hand-placed robots and a target among random clutter.
  std::ofstream(scenario) << "name: placed\nseed: 7\nrobots:\n  count: 2\n  "
                             "start: [[1, 1], [2.5, 1]]\n"
                             "targets:\n  list:\n    - {position: [10, 10]}\n"
                             "workspace: {obstacles: {random: {count: 40}}}\n";
  const auto r =
      RunAia({"world", scenario, "--seed", "3", "--out", dir + "/world.xml"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 robots, 1 targets, 40 obstacle boxes"),
            std::string::npos)
      << r.out;
  const std::string xml = ReadFile(dir + "/world.xml");
  for (const char* body : {"name=\"robot0\"", "name=\"robot1\"",
                           "name=\"target0\"", "name=\"obstacle39\""})
    EXPECT_NE(xml.find(body), std::string::npos) << body;
  EXPECT_EQ(xml.find("name=\"robot2\""), std::string::npos);
  // MuJoCo's own tool loads it, saves it and compiles both to one model.
  const auto t =
      testing::RunCommand("cd " + dir + " && mujoco-testxml world.xml");
  EXPECT_EQ(t.exit_code, 0) << t.out << t.err;
  EXPECT_NE(t.out.find("Max difference : 0"), std::string::npos) << t.out;
  // --set applies; a missing folder is made (as every command makes its
  // --out's); a file in its place and a bad scenario are bad input.
  const auto s = RunAia({"world", SourcePath("scenarios/default.yaml"), "--set",
                         "robots.count=3", "--out", dir + "/three.xml"});
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_NE(s.out.find("3 robots"), std::string::npos) << s.out;
  const auto made = RunAia({"world", SourcePath("scenarios/default.yaml"),
                            "--out", dir + "/new/folder/world.xml"});
  EXPECT_EQ(made.exit_code, 0) << made.err;
  EXPECT_TRUE(fs::exists(dir + "/new/folder/world.xml"));
  const auto m = RunAia({"world", SourcePath("scenarios/default.yaml"), "--out",
                         dir + "/three.xml/world.xml"});
  EXPECT_EQ(m.exit_code, 2);
  EXPECT_EQ(m.err, "error: command line: --out: '" + dir +
                       "/three.xml' is not a folder\n");
  const auto b = RunAia({"world", scenario, "--set", "robots.radius=-1",
                         "--out", dir + "/bad.xml"});
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_EQ(b.err.rfind("error: ", 0), 0u) << b.err;
  EXPECT_FALSE(fs::exists(dir + "/bad.xml"));
  fs::remove_all(dir);
}

std::string WithoutFileAndWallTime(const std::string& json) {
  return std::regex_replace(WithoutWallTime(json),
                            std::regex("\"scenario_file\": [^\n]*"),
                            "\"scenario_file\": X");
}

// A scenario `aia run` refuses for its policy's name is refused by `aia
// world` too, though the world needs no policy (it wrote the world).
TEST(CliTest, WorldRefusesAnUnknownPolicyAsRunDoes) {
  const std::string dir = testing::MakeTempDir("aia_world_policy_");
  const std::string file =
      SourcePath("tests/data/bad_world/unknown_policy.yaml");
  const auto run = RunAia({"run", file, "--out", dir, "--quiet"});
  const auto world = RunAia({"world", file, "--out", dir + "/w.xml"});
  EXPECT_EQ(world.exit_code, 2);
  EXPECT_EQ(world.err, run.err);
  EXPECT_NE(world.err.find("policy.name: unknown policy"), std::string::npos)
      << world.err;
  EXPECT_FALSE(fs::exists(dir + "/w.xml"));
  fs::remove_all(dir);
}

// The default policy searches a prior whose mean no point sees, instead of
// standing beside it: a mean in a box (3 robots: the team's shared misses
// end the first search and it starts again; robots stood 706 of 900
// decisions when that lost the mean's mark, 821 before any fix), and a
// free mean at a cell's corner beyond a 0.3 m sensor (170 of 200). The
// target is far from its prior, so the team searches the whole horizon.
TEST(CliTest, TheDefaultPolicySearchesAPriorWhoseMeanNoPointSees) {
  const std::string dir = testing::MakeTempDir("aia_unseen_");
  const std::vector<std::pair<std::string, long>> cases = {
      {"workspace: {size: [20.0, 20.0], obstacles: {boxes: [{center: [6.0, "
       "5.25], size: [2.0, 2.0]}]}}\n"
       "robots: {count: 3, start: [[1.25, 1.25], [1.75, 1.25], [1.25, "
       "1.75]]}\n"
       "targets: {list: [{position: [18.5, 18.5], prior_mean: [6.0, 5.25], "
       "prior_sigma: 0.6}]}\nmission: {max_steps: 300}\n",
       900},
      {"workspace: {size: [20.0, 20.0]}\n"
       "robots: {count: 1, start: [[1.25, 1.25]]}\nsensor: {range: 0.3}\n"
       "targets: {list: [{position: [18.25, 18.25], prior_mean: [5.0, 5.0], "
       "prior_sigma: 0.6}]}\nmission: {max_steps: 200}\n",
       200}};
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::string yaml = dir + "/s" + std::to_string(c) + ".yaml";
    std::ofstream(yaml) << cases[c].first;
    const std::string out = dir + "/o" + std::to_string(c);
    const auto r =
        RunAia({"run", yaml, "--policy", "igbnet", "--out", out, "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string diagnostics = ReadFile(out + "/diagnostics.json");
    const std::size_t at = diagnostics.find("\"stays\": ");
    ASSERT_NE(at, std::string::npos) << diagnostics;
    const long stays = std::stol(diagnostics.substr(at + 9));
    EXPECT_LT(stays, cases[c].second / 10) << "case " << c;
  }
  fs::remove_all(dir);
}

TEST(CliTest, EffectiveYamlRepeatsTheMission) {
  const std::string a = testing::MakeTempDir("aia_eff_"),
                    b = testing::MakeTempDir("aia_eff_");
  auto r = RunAia({"run", SourcePath("scenarios/robustness.yaml"), "--policy",
                   "decsb", "--max-steps", "25", "--set",
                   "communication.packet_loss_lambda=2", "--set",
                   "policy.horizon=6", "--out", a, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string effective = ReadFile(a + "/effective.yaml");
  EXPECT_NE(effective.find("packet_loss_lambda: 2"), std::string::npos);
  EXPECT_NE(effective.find("horizon: 6"), std::string::npos);
  EXPECT_NE(effective.find("iterations: 300"), std::string::npos);  // default
  r = RunAia({"run", a + "/effective.yaml", "--out", b, "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(a + "/trace.csv"), ReadFile(b + "/trace.csv"));
  EXPECT_EQ(WithoutFileAndWallTime(ReadFile(a + "/summary.json")),
            WithoutFileAndWallTime(ReadFile(b + "/summary.json")));
  EXPECT_EQ(ReadFile(a + "/effective.yaml"), ReadFile(b + "/effective.yaml"));
  fs::remove_all(a);
  fs::remove_all(b);
}

// Issue 19: "repeat exactly" must tell a retrained model from the one used:
// effective.yaml records the model's absolute path and SHA-256, and a run
// of it refuses a file whose content has changed since.
TEST(CliTest, EffectiveYamlRecordsTheModelAndRefusesAnotherOne) {
  const std::string dir = testing::MakeTempDir("aia_model_");
  const std::string model = dir + "/model.pt";
  fs::copy_file(SourcePath("models/igbnet_10x10.pt"), model);
  auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--policy",
                   "igbnet", "--set", "policy.model=" + model, "--max-steps",
                   "3", "--out", dir + "/a", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto sha = testing::RunCommand("sha256sum '" + model + "'");
  ASSERT_EQ(sha.exit_code, 0);
  const std::string effective = ReadFile(dir + "/a/effective.yaml");
  EXPECT_NE(effective.find("  model: " + model +
                           "\n  model_sha256: " + sha.out.substr(0, 64) + "\n"),
            std::string::npos)
      << effective;
  r = RunAia(
      {"run", dir + "/a/effective.yaml", "--out", dir + "/b", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(ReadFile(dir + "/a/trace.csv"), ReadFile(dir + "/b/trace.csv"));
  // The same path, retrained (here: another model copied over it).
  fs::copy_file(SourcePath("models/igbnet.pt"), model,
                fs::copy_options::overwrite_existing);
  r = RunAia(
      {"run", dir + "/a/effective.yaml", "--out", dir + "/c", "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("effective.yaml:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(": policy.model_sha256: the model file '" + model +
                       "' has SHA-256 "),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/c/summary.json"));
  // The default model is recorded by its resolved path.
  r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--max-steps", "1",
              "--out", dir + "/d", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadFile(dir + "/d/effective.yaml").find("/models/igbnet.pt\n"),
            std::string::npos);
  // With coordination none it is the model trained for the network alone,
  // and a model given is still the one taken.
  r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--policy", "igbnet",
              "--set", "policy.coordination=none", "--max-steps", "1", "--out",
              dir + "/e", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      ReadFile(dir + "/e/effective.yaml").find("/models/igbnet_learned.pt\n"),
      std::string::npos);
  r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--policy", "igbnet",
              "--set", "policy.coordination=none", "--set",
              "policy.model=" + SourcePath("models/igbnet_10x10.pt"),
              "--max-steps", "1", "--out", dir + "/f", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(
      ReadFile(dir + "/f/effective.yaml").find("/models/igbnet_10x10.pt\n"),
      std::string::npos);
  // A file's igbnet switched by --policy greedy runs without a word, and so
  // does its repeat: the model that greedy does not read is not recorded
  // (it was, and the repeat warned that it changes nothing).
  r = RunAia({"run", dir + "/d/effective.yaml", "--policy", "greedy",
              "--max-steps", "1", "--out", dir + "/g", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(ReadFile(dir + "/g/effective.yaml").find("model_sha256: "),
            std::string::npos);
  r = RunAia(
      {"run", dir + "/g/effective.yaml", "--out", dir + "/h", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(ReadFile(dir + "/g/trace.csv"), ReadFile(dir + "/h/trace.csv"));
  fs::remove_all(dir);
}

TEST(CliTest, SetWorksOnRunRenderAndPlan) {
  const std::string out = testing::MakeTempDir("aia_set_");
  auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--set",
                   "mission.max_steps=3", "--set", "sensor.range=3", "--out",
                   out + "/run", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadFile(out + "/run/summary.json").find("\"max_steps\": 3"),
            std::string::npos);
  EXPECT_NE(ReadFile(out + "/run/effective.yaml").find("range: 3"),
            std::string::npos);
  r = RunAia({"render", SourcePath("scenarios/tracking.yaml"), "--out",
              out + "/v.mp4", "--set", "mission.max_steps=2", "--set",
              "render.width=64", "--height", "48", "--hold", "0", "--quiet"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadFile(out + "/v.summary.json").find("\"width\": 64"),
            std::string::npos);
  r = RunAia({"plan", SourcePath("scenarios/default.yaml"), "--set",
              "policy.anytime=50", "--out", out + "/plan.json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadFile(out + "/plan.effective.yaml").find("anytime: 50"),
            std::string::npos);
  fs::remove_all(out);
}

TEST(CliTest, BadSetIsBadInputOnEveryCommand) {
  const std::string out = testing::MakeTempDir("aia_badset_");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", scenario, "--set", "robots.cuont=1", "--out", out},
       "error: command line: --set robots.cuont: unknown key (did you mean "
       "`count`?)"},
      {{"run", scenario, "--set", "mission.eps", "--out", out},
       "error: command line: --set: 'mission.eps' is not key.path=value"},
      {{"run", scenario, "--set", "policy.p_v=0.5", "--out", out},
       "error: command line: --set policy.p_v: unknown parameter for policy "
       "'igbnet'"},
      {{"render", scenario, "--out", out + "/v.mp4", "--set", "render.fps=0"},
       "error: command line: --set render.fps: must be an integer in [1, "
       "1000]"},
      {{"plan", scenario, "--set", "policy.p_vv=1"},
       "error: command line: --set policy.p_vv: unknown parameter for policy "
       "'expert' (did you mean `p_v`?)"},
      {{"plan", scenario, "--set", "policy.p_v=2"},
       "error: command line: --set policy.p_v: must be a number in [0, 1]"},
      {{"eval", "--sizes", "2x2", "--seeds", "1", "--set", "sensor.rang=3",
        "--out", out},
       "error: command line: --set sensor.rang: unknown key (did you mean "
       "`range`?)"},
      // yaml-cpp dropped a second document and read bytes that are not
      // UTF-8 as nothing.
      {{"run", scenario, "--set", "seed=1\n---\n2", "--out", out},
       "error: command line: --set seed: the value holds 2 YAML documents "
       "(separated by ---), not one: '1\\n---\\n2'"},
      {{"run", scenario, "--set", "name=\xff", "--out", out},
       "error: command line: --set name: the value is not UTF-8 text"},
      {{"run", scenario, "--set", "mission.eps=\xff\xfe", "--out", out},
       "error: command line: --set mission.eps: the value is not UTF-8 text"},
      {{"run", scenario, "--set", "sensor.sigma0=1e-400", "--out", out},
       "error: command line: --set sensor.sigma0: must be a number in [1e-06, "
       "10000], got 1e-400, which is too small: it underflows to 0"},
      // A key given by its own flag too: --set won silently.
      {{"run", scenario, "--seed", "6", "--set", "seed=5", "--out", out},
       "error: command line: --set seed: is also given by --seed; give one "
       "of them\n"},
      {{"run", scenario, "--max-steps", "4", "--set", "mission.max_steps=2",
        "--out", out},
       "error: command line: --set mission.max_steps: is also given by "
       "--max-steps; give one of them\n"},
      {{"render", scenario, "--out", out + "/v.mp4", "--policy", "greedy",
        "--set", "policy.name=random"},
       "error: command line: --set policy.name: is also given by --policy; "
       "give one of them\n"},
      // A whole section replaced by --set after a flag set a key in it: the
      // flag lost silently.
      {{"run", scenario, "--max-steps", "2", "--set", "mission={eps: 0.05}",
        "--out", out},
       "error: command line: --set mission: replaces the whole section, and "
       "--max-steps gives mission.max_steps in it; set the section's keys "
       "one by one (--set mission.KEY=VALUE) or drop --max-steps\n"},
      {{"eval", "--sizes", "2x2", "--set", "policy={name: random}", "--out",
        out},
       "error: command line: --set policy: replaces the whole section, which "
       "holds policy.name, set by the command; set the section's keys one by "
       "one (--set policy.KEY=VALUE)\n"},
      // A section given nothing read as absent: every key at its default.
      {{"run", scenario, "--set", "mission=", "--out", out},
       "error: command line: --set mission: must be a mapping with keys among "
       "eps, max_steps, stop_at_success, decisions, avoidance, got nothing\n"},
  };
  for (const auto& [args, prefix] : cases) {
    std::vector<std::string> a = args;
    a.push_back("--quiet");
    if (a[0] == "plan") a.pop_back();
    const auto r = RunAia(a);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(r.err.rfind(prefix, 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(out + "/summary.json"));
  fs::remove_all(out);
}

// A key path of 40 000 characters overflowed the stack of a std::regex
// (SIGSEGV, nothing printed); it is an unknown key like any other.
TEST(CliTest, LongSetKeyIsOneErrorLine) {
  const std::string key(40000, 'a');
  const auto r = RunAia({"run", SourcePath("scenarios/default.yaml"), "--set",
                         key + "=1", "--quiet"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err.rfind("error: command line: --set " + key + ": unknown key", 0), 0u)
      << r.err.substr(0, 300);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1);
  const auto bad = RunAia({"run", SourcePath("scenarios/default.yaml"), "--set",
                           key + "-=1", "--quiet"});
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.err.rfind("error: command line: --set: '" + key +
                              "-' is not "
                              "a key path",
                          0),
            0u)
      << bad.err.substr(0, 300);
}

// Seeds are whole numbers that fit in 64 bits, read as decimal: CLI11's
// strtoull saturated 2^64 and beyond to 2^64 - 1 and read 010 as octal 8,
// so distinct flags gave one seed.
TEST(CliTest, SeedsThatDoNotFitIn64BitsAreRefused) {
  const std::string dir = testing::MakeTempDir("aia_seed_");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::string big = "18446744073709551616";
  const std::string too_big =
      "must be an integer >= 0 that fits in 64 bits (at most "
      "18446744073709551615), got ";
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"run", scenario, "--seed", big, "--out", dir + "/r"},
       "error: command line: --seed: " + too_big + big + "\n"},
      {{"world", scenario, "--seed", std::string(60, '9'), "--out",
        dir + "/w.xml"},
       "error: command line: --seed: " + too_big + std::string(60, '9') + "\n"},
      {{"bench", "--seed", big},
       "error: command line: --seed: " + too_big + big + "\n"},
      {{"train", "--data", dir, "--seed", big},
       "error: command line: --seed: " + too_big + big + "\n"},
      {{"eval", "--seed-base", big, "--out", dir + "/e"},
       "error: command line: --seed-base: " + too_big + big + "\n"},
      // The last seed of a range must fit too: it used to wrap to 0.
      {{"eval", "--sizes", "2x1", "--seeds", "2", "--seed-base",
        "18446744073709551615", "--out", dir + "/e"},
       "error: command line: --seed-base: seeds 18446744073709551615 .. "
       "18446744073709551615 + 1 do not fit in 64 bits (the largest seed is "
       "18446744073709551615); with --seeds 2, --seed-base must be at most "
       "18446744073709551614\n"},
      {{"dataset", "--episodes", "3", "--first-seed", "18446744073709551614",
        "--out", dir + "/d"},
       "error: command line: --first-seed: seeds 18446744073709551614 .. "
       "18446744073709551614 + 2 do not fit in 64 bits (the largest seed is "
       "18446744073709551615); with --episodes 3, --first-seed must be at "
       "most 18446744073709551613\n"},
      {{"bench", "--expert", "--seeds", "2", "--seed", "18446744073709551615"},
       "error: command line: --seed: seeds 18446744073709551615 .. "
       "18446744073709551615 + 1 do not fit in 64 bits (the largest seed is "
       "18446744073709551615); with --seeds 2, --seed must be at most "
       "18446744073709551614\n"},
  };
  for (const auto& [args, err] : cases) {
    const auto r = RunAia(args);
    EXPECT_EQ(r.exit_code, 2) << err;
    EXPECT_EQ(r.err, err);
  }
  for (const char* out : {"/r", "/w.xml", "/e", "/d"})
    EXPECT_FALSE(fs::exists(dir + out)) << out;
  // The largest seed is a seed; leading zeros do not make octal.
  for (const char* seed : {"18446744073709551615", "010"}) {
    const auto r =
        RunAia({"world", scenario, "--seed", seed, "--out", dir + "/w.xml"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(std::string("(seed ") +
                         (seed[0] == '0' ? "10" : seed) + ")"),
              std::string::npos)
        << r.out;
  }
  fs::remove_all(dir);
}

// An empty path given to a flag is a mistake (an unset shell variable), not
// the flag's default: --out "" used to write renders/<name>/ or nothing.
TEST(CliTest, EmptyPathFlagsAreRefused) {
  const std::string dir = testing::MakeTempDir("aia_empty_");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::vector<std::vector<std::string>> cases = {
      {"run", scenario, "--out", ""},
      {"render", scenario, "--out", ""},
      {"render", scenario, "--out", dir + "/v.mp4", "--frames", ""},
      {"plan", scenario, "--out", ""},
      {"world", scenario, "--out", ""},
      {"eval", "--sizes", "2x1", "--seeds", "1", "--out", ""},
      {"train", "--data", dir, "--out", ""},
      {"train", "--data", ""},
      {"dataset", "--episodes", "1", "--out", ""},
      {"dataset", "--episodes", "1", "--out", dir + "/d", "--model", ""},
  };
  for (const std::vector<std::string>& args : cases) {
    const auto r = testing::RunCommand(
        "cd " + dir + " && '" + std::string(AIA_BINARY) + "' " + [&args]() {
          std::string line;
          for (const std::string& a : args) line += "'" + a + "' ";
          return line;
        }());
    const std::string flag = args[args.size() - 2];
    EXPECT_EQ(r.exit_code, 2) << args[0] << " " << flag;
    EXPECT_EQ(r.err, "error: command line: " + flag +
                         ": an empty path; give a file or folder (aia " +
                         args[0] + " --help lists the options)\n");
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "something was written";
  fs::remove_all(dir);
}

// Output that cannot be written to standard output fails the command
// (it exited 0 with nothing written).
TEST(CliTest, FailedWriteToStandardOutputIsAnError) {
  for (const std::string args :
       {"schema", "policies", "schema --markdown", "--help", "eval --help"}) {
    const auto r = testing::RunCommand("{ '" + std::string(AIA_BINARY) + "' " +
                                       args + " >/dev/full; }");
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_EQ(r.err,
              "error: cannot write to standard output: No space left on "
              "device\n")
        << args;
  }
}

}  // namespace
}  // namespace aia
