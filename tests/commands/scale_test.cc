// Hundreds of robots through the command line (issue 19's probe): MuJoCo's
// memory is sized from the model, its errors are aia's, and no command waits
// on stdin or writes a log into the working folder.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunCommand;

std::string WriteScenario(const std::string& dir, const std::string& name,
                          int robots, int targets, double side, int boxes) {
  const std::string path = dir + "/" + name + ".yaml";
  std::ofstream(path) << "name: " << name << "\nseed: 2\n"
                      << "workspace: {size: [" << side << ", " << side
                      << "], obstacles: {random: {count: " << boxes << "}}}\n"
                      << "robots: {count: " << robots << "}\n"
                      << "targets: {count: " << targets << "}\n"
                      << "mission: {stop_at_success: false}\n"
                      << "policy: {name: random}\n";
  return path;
}

// Every file under `dir` whose name holds ".tmp." (an unfinished write).
std::vector<std::string> Temporaries(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".tmp.") != std::string::npos)
      found.push_back(e.path().string());
  return found;
}

// The probe's worlds that printed MuJoCo's "Stack overflow" and waited for
// Enter: 200 robots in 60 x 60 m without boxes, 150 robots with 51
// targets, 190 robots with 200 boxes, 320 robots with 270 boxes. Each runs
// from a folder of its own, which must hold no MUJOCO_LOG.TXT afterwards.
TEST(ScaleTest, TheProbesWorldsRunWithoutMujocoErrors) {
  const std::string dir = testing::MakeTempDir("aia_scale_");
  struct Case {
    const char* name;
    int robots, targets;
    double side;
    int boxes;
  };
  const Case cases[] = {{"r200", 200, 1, 60.0, 0},
                        {"r150", 150, 51, 20.0, 30},
                        {"r190", 190, 2, 45.0, 200},
                        {"r320", 320, 320, 57.0, 270}};
  for (const Case& c : cases) {
    const std::string scenario =
        WriteScenario(dir, c.name, c.robots, c.targets, c.side, c.boxes);
    const std::string out = dir + "/" + c.name;
    const auto r =
        RunCommand("cd '" + dir + "' && '" AIA_BINARY "' run '" + scenario +
                   "' --max-steps 3 --quiet --out '" + out + "'");
    ASSERT_EQ(r.exit_code, 0) << c.name << ": " << r.err << r.out;
    EXPECT_EQ(r.out.find("ERROR"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("Press Enter"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir + "/MUJOCO_LOG.TXT")) << c.name;
    EXPECT_TRUE(Temporaries(out).empty()) << c.name;
    const std::string diagnostics = ReadFile(out + "/diagnostics.json");
    EXPECT_NE(diagnostics.find("\"mujoco_warnings\": {}"), std::string::npos)
        << c.name << ": " << diagnostics;
  }
  fs::remove_all(dir);
}

// Commands run with a pseudo-terminal as stdin, as in a user's shell: any
// read of stdin (MuJoCo's default error handler waits for Enter there) would
// block until the timeout. The harness itself is checked on a command that
// does read stdin.
TEST(ScaleTest, NoCommandWaitsOnStdinUnderATerminal) {
  const std::string dir = testing::MakeTempDir("aia_pty_");
  // script(1) gives the command a terminal fed from a pipe that stays open
  // and silent (a sleep), so a read of stdin waits rather than sees EOF.
  const auto under_pty = [&](const std::string& command, int seconds) {
    std::ofstream(dir + "/command.sh") << command << "\n";
    const std::string t = std::to_string(seconds);
    return RunCommand("cd '" + dir + "' && bash -c \"timeout " + t +
                      " script -qec 'sh command.sh' /dev/null < <(sleep " +
                      std::to_string(seconds + 5) + ")\"");
  };
  EXPECT_EQ(under_pty("head -c 1", 3).exit_code, 124);  // the harness works

  const std::string big = WriteScenario(dir, "big", 200, 2, 45.0, 100);
  const std::string aia = std::string("'") + AIA_BINARY + "'";
  const std::vector<std::string> commands = {
      aia + " run '" + big + "' --max-steps 2 --out run",
      aia + " render '" + big + "' --max-steps 1 --out video/big.mp4 --quiet",
      aia + " world '" + big + "' --out world.xml",
      aia + " plan '" + testing::SourcePath("scenarios/default.yaml") +
          "' --budget 100",
      aia + " run '" + testing::SourcePath("tests/data/bad/bool_as_yes.yaml") +
          "' --out bad",
      aia + " eval --sizes 3x3 --seeds 1 --policies greedy --out eval --quiet",
  };
  for (const std::string& c : commands) {
    const auto r = under_pty(c, 240);
    EXPECT_NE(r.exit_code, 124) << "timed out: " << c;
    EXPECT_EQ(r.out.find("Press Enter"), std::string::npos) << c;
  }
  EXPECT_FALSE(fs::exists(dir + "/MUJOCO_LOG.TXT"));
  fs::remove_all(dir);
}

TEST(ScaleTest, TraceOfManyRobotsKeepsTheTeamColumnOnly) {
  const std::string dir = testing::MakeTempDir("aia_trace_");
  const std::string scenario = WriteScenario(dir, "t", 120, 3, 30.0, 20);
  const auto first_line = [](const std::string& path) {
    const std::string text = ReadFile(path);
    return text.substr(0, text.find('\n'));
  };
  auto r = testing::RunAia(
      {"run", scenario, "--max-steps", "1", "--quiet", "--out", dir + "/auto"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(first_line(dir + "/auto/trace.csv"), "step,target,min_det");
  r = testing::RunAia({"run", scenario, "--max-steps", "1", "--quiet",
                       "--trace", "full", "--out", dir + "/full"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(first_line(dir + "/full/trace.csv")
                .rfind("step,target,min_det,det_r0,det_r1,", 0),
            0u);
  r = testing::RunAia(
      {"run", scenario, "--trace", "some", "--out", dir + "/bad"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(
      r.err,
      "error: command line: --trace: must be auto, full or min, got some\n");
  fs::remove_all(dir);
}

// tools/bench_scale.py with the policy's threads: one row per size, the
// threads kept in the folder's settings (a folder measured with one
// thread is not resumed with two), and no threads refused.
TEST(ScaleTest, BenchScaleKeepsItsPolicyThreads) {
  if (RunCommand("/usr/bin/python3 -c 'import matplotlib'").exit_code != 0)
    GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_bench_scale_");
  const std::string tool = "/usr/bin/python3 " +
                           testing::SourcePath("tools/bench_scale.py") +
                           " --aia '" + AIA_BINARY + "' --out " + dir +
                           " --sizes 5 --steps 2 --repeats 1 --policy random";
  const auto two = RunCommand(tool + " --policy-threads 2");
  ASSERT_EQ(two.exit_code, 0) << two.out << two.err;
  const std::string csv = ReadFile(dir + "/scale.csv");
  EXPECT_NE(csv.find("\n5,20.0,30,"), std::string::npos) << csv;
  EXPECT_NE(ReadFile(dir + "/settings.json").find("\"policy_threads\": 2"),
            std::string::npos);
  const auto one = RunCommand(tool + " --policy-threads 1");
  EXPECT_EQ(one.exit_code, 2);
  EXPECT_NE(one.err.find("this folder was measured with"), std::string::npos)
      << one.err;
  const auto none = RunCommand(tool + " --policy-threads 0");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("error: --policy-threads"), std::string::npos)
      << none.err;
  fs::remove_all(dir);
}

// bench_scale.py refuses bad input with one line and exit 2 before anything
// is written (a bad policy left a settings.json that refused the corrected
// command), and a folder another call holds (two calls lost each other's
// rows).
TEST(ScaleTest, BenchScaleRefusesBadInputAndABusyFolder) {
  if (RunCommand("/usr/bin/python3 -c 'import matplotlib'").exit_code != 0)
    GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_bench_scale_bad_");
  const std::string tool = "/usr/bin/python3 " +
                           testing::SourcePath("tools/bench_scale.py") +
                           " --aia '" + AIA_BINARY + "' --out " + dir +
                           " --sizes 2 --repeats 1 --steps 2";
  const auto steps = RunCommand(tool + " --steps 0");
  EXPECT_EQ(steps.exit_code, 2);
  EXPECT_EQ(steps.err, "error: --steps: give at least 1, got 0\n");
  const auto policy = RunCommand(tool + " --policy nosuch");
  EXPECT_EQ(policy.exit_code, 2);
  EXPECT_NE(policy.err.find("error: 2x2: command line: --policy: unknown "
                            "policy 'nosuch'"),
            std::string::npos)
      << policy.err;
  EXPECT_FALSE(fs::exists(dir + "/settings.json"));
  const auto busy =
      RunCommand("flock -n " + dir + "/.lock " + tool + " --policy random");
  EXPECT_EQ(busy.exit_code, 2);
  EXPECT_NE(busy.err.find("is in use by another bench_scale.py"),
            std::string::npos)
      << busy.err;
  EXPECT_EQ(RunCommand(tool + " --policy random").exit_code, 0);
  fs::remove_all(dir);
}

// bench_scale.py splits physics into MuJoCo's time per mj_step call and the
// calls per decision step, from rows already measured (none is run again).
// By hand: 10 ms at 10000 calls/s is 0.1 ms x 100 calls; 40 ms at 4000/s
// is 0.25 ms x 160 calls; from N = 80 to 160 the growths are log 2.5 / log
// 2 = 1.32 and log 1.6 / log 2 = 0.68, which add to physics' N^2.00.
TEST(ScaleTest, BenchScaleSplitsPhysicsIntoCallsAndTheirCost) {
  if (RunCommand("/usr/bin/python3 -c 'import matplotlib'").exit_code != 0)
    GTEST_SKIP() << "no python3-matplotlib";
  const std::string dir = testing::MakeTempDir("aia_bench_scale_split_");
  std::ofstream(dir + "/settings.json")
      << R"({"policy": "random", "set": [], "steps": 2, "repeats": 1, )"
      << R"("seed": 1})";
  std::ofstream(dir + "/scale.csv")
      << "robots,side_m,boxes,steps_per_s,ms_step,physics,sensing,fusion,"
         "policy,rest,mj_step_pct,mj_step_per_s,testspeed_per_s,contacts,"
         "testspeed_contacts,peak_rss_mib,wall_s\n"
      << "80,28.3,60,50,20,10,1,1,7,1,50,10000,12000,1,0,250,1\n"
      << "160,40.0,120,20,50,40,2,2,5,1,80,4000,5000,2,0,260,2\n";
  const auto r = RunCommand("/usr/bin/python3 " +
                            testing::SourcePath("tools/bench_scale.py") +
                            " --aia /nonexistent --out " + dir +
                            " --sizes 80,160 --steps 2 --repeats 1 "
                            "--policy random");
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const std::string md = ReadFile(dir + "/scale.md");
  EXPECT_NE(md.find("physics = ms per mj_step x mj_step calls per decision "
                    "step: 80: 0.100 x 100.0, 160: 0.250 x 160.0; growth "
                    "N^1.32 x N^0.68\n"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("N^2.00"), std::string::npos) << md;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace aia
