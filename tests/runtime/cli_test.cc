// The command line: bad input gives `error: FILE:LINE: key: ...` and exit 2,
// every scenario runs, the same seed gives byte-identical results.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

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
  for (const std::string cmd : {"", "run", "render", "plan", "eval", "bench"}) {
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
  for (const auto& entry : fs::directory_iterator(SourcePath("scenarios")))
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

}  // namespace
}  // namespace aia
