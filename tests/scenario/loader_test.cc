#include "aia/scenario/loader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/scenario/config.h"
#include "aia/scenario/yaml.h"
#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

constexpr char kMinimal[] = "robots: {count: 2}\ntargets: {count: 3}\n";

// An example with every key at once, consistent. The example it comes from
// gave 2 start positions for 10 robots and both `count: 10` and a list of 2
// targets, each of which the loader rejects (SpecExampleAsWrittenIsRejected).
constexpr char kFullExample[] = R"(name: demo
seed: 7
workspace:
  size: [20.0, 20.0]          # metres
  cell: 0.1                   # occupancy grid cell
  obstacles:
    random: {count: 30, min_size: [0.4, 0.4], max_size: [2.0, 2.0]}
    boxes: [{center: [5.0, 5.0], size: [1.0, 4.0]}]
    map: maps/maze.pgm        # dark pixels are occupied, scaled to `size`
robots:
  count: 2
  radius: 0.15
  step: 0.5
  start: [[1.25, 1.25], [2.25, 1.25]]   # or omitted: random free lattice points
sensor: {range: 2.0, eta: 0.05, sigma0: 0.01, line_of_sight: true}
targets:
  count: 2                    # random static targets, or a list:
  list:
    - {position: [3.0, 4.0], prior_mean: [3.5, 4.2], prior_sigma: 1.0}
    - {position: [10.0, 10.0], dynamics: {A: [[1, 0], [0, 1]], b: [0.05, 0.0], q: 0.001}}
  prior_sigma: 1.0            # default for targets without their own
mission: {eps: 0.1, max_steps: 400, stop_at_success: true}
communication:
  mode: full                  # full | range
  range: 4.0
  kappa_self: 0.75
  packet_loss_lambda: 0.0
  failures: [{robot: random, step: 10}]
policy: {name: greedy, model: ../models/igbnet.pt}   # random|greedy|expert|decsb|igbnet
physics: {timestep: 0.005, kp: 200}
render: {width: 640, height: 480, fps: 30, follow_robot: 0}
)";

// Writes `text` to dir/name, creating parent folders.
std::string WriteFile(const std::string& dir, const std::string& name,
                      const std::string& text) {
  const fs::path path = fs::path(dir) / name;
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
  return path.string();
}

// The InputError that parsing `yaml` throws (fails the test if none).
InputError ErrorOf(const std::string& yaml) {
  try {
    testing::ScenarioFromYaml(yaml);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << yaml;
  return InputError("", 0, "", "");
}

TEST(LoaderTest, MinimalFileKeepsEveryDefault) {
  const Scenario s = testing::ScenarioFromYaml(kMinimal, "minimal.yaml");
  const Scenario d;  // the defaults, from config.h only
  EXPECT_EQ(s.file, "minimal.yaml");
  EXPECT_EQ(s.name, d.name);
  EXPECT_EQ(s.seed, d.seed);
  EXPECT_EQ(s.workspace.size, d.workspace.size);
  EXPECT_EQ(s.workspace.cell, d.workspace.cell);
  EXPECT_FALSE(s.workspace.obstacles.random.has_value());
  EXPECT_TRUE(s.workspace.obstacles.boxes.empty());
  EXPECT_TRUE(s.workspace.obstacles.map.empty());
  EXPECT_EQ(s.workspace.obstacles.map_threshold,
            d.workspace.obstacles.map_threshold);
  EXPECT_EQ(s.robots.count, 2);
  EXPECT_EQ(s.robots.radius, d.robots.radius);
  EXPECT_EQ(s.robots.step, d.robots.step);
  EXPECT_TRUE(s.robots.start.empty());
  EXPECT_EQ(s.sensor.range, d.sensor.range);
  EXPECT_EQ(s.sensor.eta, d.sensor.eta);
  EXPECT_EQ(s.sensor.sigma0, d.sensor.sigma0);
  EXPECT_EQ(s.sensor.line_of_sight, d.sensor.line_of_sight);
  EXPECT_EQ(s.targets.count, 3);
  EXPECT_TRUE(s.targets.list.empty());
  EXPECT_EQ(s.targets.prior_sigma, d.targets.prior_sigma);
  EXPECT_EQ(s.targets.prior_offset, d.targets.prior_offset);
  EXPECT_EQ(s.NumTargets(), 3);
  EXPECT_EQ(s.mission.eps, d.mission.eps);
  EXPECT_EQ(s.mission.max_steps, d.mission.max_steps);
  EXPECT_EQ(s.mission.stop_at_success, d.mission.stop_at_success);
  EXPECT_EQ(s.communication.mode, d.communication.mode);
  EXPECT_EQ(s.communication.range, d.communication.range);
  EXPECT_EQ(s.communication.kappa_self, d.communication.kappa_self);
  EXPECT_EQ(s.communication.packet_loss_lambda,
            d.communication.packet_loss_lambda);
  EXPECT_TRUE(s.communication.failures.empty());
  EXPECT_EQ(s.policy.name, d.policy.name);
  EXPECT_TRUE(s.policy.model.empty());
  EXPECT_TRUE(s.policy.params.entries.empty());
  EXPECT_EQ(s.physics.timestep, d.physics.timestep);
  EXPECT_EQ(s.physics.kp, d.physics.kp);
  EXPECT_EQ(s.physics.robot_mass, d.physics.robot_mass);
  EXPECT_EQ(s.physics.tolerance, d.physics.tolerance);
  EXPECT_EQ(s.physics.step_timeout, d.physics.step_timeout);
  EXPECT_EQ(s.render.width, d.render.width);
  EXPECT_EQ(s.render.height, d.render.height);
  EXPECT_EQ(s.render.fps, d.render.fps);
  EXPECT_EQ(s.render.follow_robot, d.render.follow_robot);
}

TEST(LoaderTest, FullSpecExampleParsesWithAllValues) {
  const std::string dir = testing::MakeTempDir("aia_scenario_");
  WriteFile(dir, "maps/maze.pgm", "P2\n1 1\n255\n0\n");
  const std::string path = WriteFile(dir, "demo.yaml", kFullExample);
  const Scenario s = LoadScenario(path);

  EXPECT_EQ(s.file, path);
  EXPECT_EQ(s.name, "demo");
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.workspace.size, Vec2(20.0, 20.0));
  EXPECT_EQ(s.workspace.cell, 0.1);
  const ObstaclesConfig& o = s.workspace.obstacles;
  ASSERT_TRUE(o.random.has_value());
  EXPECT_EQ(o.random->count, 30);
  EXPECT_EQ(o.random->min_size, Vec2(0.4, 0.4));
  EXPECT_EQ(o.random->max_size, Vec2(2.0, 2.0));
  ASSERT_EQ(o.boxes.size(), 1u);
  EXPECT_EQ(o.boxes[0].center, Vec2(5.0, 5.0));
  EXPECT_EQ(o.boxes[0].size, Vec2(1.0, 4.0));
  EXPECT_EQ(o.map, (fs::path(dir) / "maps/maze.pgm").string());

  EXPECT_EQ(s.robots.count, 2);
  EXPECT_EQ(s.robots.radius, 0.15);
  EXPECT_EQ(s.robots.step, 0.5);
  ASSERT_EQ(s.robots.start.size(), 2u);
  EXPECT_EQ(s.robots.start[0], Vec2(1.25, 1.25));
  EXPECT_EQ(s.robots.start[1], Vec2(2.25, 1.25));

  EXPECT_EQ(s.sensor.range, 2.0);
  EXPECT_EQ(s.sensor.eta, 0.05);
  EXPECT_EQ(s.sensor.sigma0, 0.01);
  EXPECT_TRUE(s.sensor.line_of_sight);

  EXPECT_EQ(s.targets.count, 2);
  EXPECT_EQ(s.targets.prior_sigma, 1.0);
  ASSERT_EQ(s.targets.list.size(), 2u);
  const TargetConfig& t0 = s.targets.list[0];
  EXPECT_EQ(t0.position, Vec2(3.0, 4.0));
  ASSERT_TRUE(t0.prior_mean.has_value());
  EXPECT_EQ(*t0.prior_mean, Vec2(3.5, 4.2));
  ASSERT_TRUE(t0.prior_sigma.has_value());
  EXPECT_EQ(*t0.prior_sigma, 1.0);
  EXPECT_TRUE(t0.dynamics.IsStatic());
  const TargetConfig& t1 = s.targets.list[1];
  EXPECT_EQ(t1.position, Vec2(10.0, 10.0));
  EXPECT_FALSE(t1.prior_mean.has_value());
  EXPECT_FALSE(t1.prior_sigma.has_value());
  EXPECT_EQ(t1.dynamics.dim(), 2);
  EXPECT_EQ(t1.dynamics.A, Eigen::MatrixXd::Identity(2, 2));
  EXPECT_EQ(t1.dynamics.b, Eigen::Vector2d(0.05, 0.0));
  EXPECT_EQ(t1.dynamics.q, 0.001);
  EXPECT_FALSE(t1.dynamics.IsStatic());

  EXPECT_EQ(s.mission.eps, 0.1);
  EXPECT_EQ(s.mission.max_steps, 400);
  EXPECT_TRUE(s.mission.stop_at_success);

  EXPECT_EQ(s.communication.mode, CommMode::kFull);
  EXPECT_EQ(s.communication.range, 4.0);
  EXPECT_EQ(s.communication.kappa_self, 0.75);
  EXPECT_EQ(s.communication.packet_loss_lambda, 0.0);
  ASSERT_EQ(s.communication.failures.size(), 1u);
  EXPECT_EQ(s.communication.failures[0].robot, -1);
  EXPECT_EQ(s.communication.failures[0].step, 10);

  EXPECT_EQ(s.policy.name, "greedy");
  EXPECT_EQ(s.policy.model,
            (fs::path(dir).parent_path() / "models/igbnet.pt").string());
  EXPECT_TRUE(s.policy.params.entries.empty());

  EXPECT_EQ(s.physics.timestep, 0.005);
  EXPECT_EQ(s.physics.kp, 200.0);

  EXPECT_EQ(s.render.width, 640);
  EXPECT_EQ(s.render.height, 480);
  EXPECT_EQ(s.render.fps, 30);
  EXPECT_EQ(s.render.follow_robot, 0);
  fs::remove_all(dir);
}

TEST(LoaderTest, SpecExampleAsWrittenIsRejected) {
  // As first written: 2 start positions for 10 robots.
  const std::string dir = testing::MakeTempDir("aia_scenario_");
  WriteFile(dir, "maps/maze.pgm", "P2\n1 1\n255\n0\n");
  std::string yaml = kFullExample;
  yaml.replace(yaml.find("  count: 2\n"), 11, "  count: 10\n");
  try {
    ParseScenario(yaml, "spec.yaml", dir);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "robots.start");
    EXPECT_EQ(e.line(), 14);
  }
  fs::remove_all(dir);
}

TEST(LoaderTest, RelativePathsResolveAgainstBaseDir) {
  const std::string dir = testing::MakeTempDir("aia_scenario_");
  WriteFile(dir, "scenarios/maps/m.pgm", "P2\n1 1\n255\n0\n");
  const std::string yaml = std::string(kMinimal) +
                           "workspace: {obstacles: {map: maps/m.pgm}}\n"
                           "policy: {name: igbnet, model: ../models/net.pt}\n";
  const std::string base = dir + "/scenarios";
  const Scenario s = ParseScenario(yaml, "inline.yaml", base);
  EXPECT_EQ(s.workspace.obstacles.map, base + "/maps/m.pgm");
  EXPECT_EQ(s.policy.model, dir + "/models/net.pt");  // need not exist yet

  // A path given on the command line is the user's, relative to the
  // working folder, not to the scenario's.
  const Scenario flagged =
      ParseScenario(yaml, "inline.yaml", base,
                    {ParseSetFlag("policy.model=models/other.pt")});
  EXPECT_EQ(flagged.policy.model,
            (fs::current_path() / "models/other.pt").string());

  // Absolute paths stay as they are.
  const std::string absolute = std::string(kMinimal) +
                               "workspace: {obstacles: {map: " + base +
                               "/maps/m.pgm}}\n";
  EXPECT_EQ(ParseScenario(absolute, "inline.yaml", "/nowhere")
                .workspace.obstacles.map,
            base + "/maps/m.pgm");

  // The same map, but the file is looked for next to the scenario.
  const InputError e = [&] {
    try {
      ParseScenario(yaml, "inline.yaml", dir);
    } catch (const InputError& err) {
      return err;
    }
    return InputError("", 0, "", "no error");
  }();
  EXPECT_EQ(e.key(), "workspace.obstacles.map");
  EXPECT_NE(e.message().find(dir + "/maps/m.pgm"), std::string::npos)
      << e.message();
  fs::remove_all(dir);
}

TEST(LoaderTest, LoadScenarioResolvesAgainstTheFilesDirectory) {
  const std::string dir = testing::MakeTempDir("aia_scenario_");
  WriteFile(dir, "sub/maps/m.pgm", "P2\n1 1\n255\n0\n");
  const std::string path = WriteFile(
      dir, "sub/s.yaml",
      std::string(kMinimal) + "workspace: {obstacles: {map: maps/m.pgm}}\n");
  EXPECT_EQ(LoadScenario(path).workspace.obstacles.map,
            dir + "/sub/maps/m.pgm");
  fs::remove_all(dir);
}

TEST(LoaderTest, MissingFileIsAnErrorWithoutLine) {
  try {
    LoadScenario("/nonexistent/dir/s.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/s.yaml");
    EXPECT_EQ(e.line(), 0);
    EXPECT_EQ(e.key(), "(file)");
    EXPECT_EQ(e.message(), "cannot read file: No such file or directory");
    EXPECT_EQ(
        e.Format(),
        "/nonexistent/dir/s.yaml: (file): cannot read file: No such file or "
        "directory");
  }
}

TEST(LoaderTest, DirectoryIsNotAScenarioFile) {
  const std::string dir = testing::MakeTempDir("aia_scenario_");
  try {
    LoadScenario(dir);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "(file)");
    EXPECT_NE(e.message().find("cannot read file"), std::string::npos);
  }
  fs::remove_all(dir);
}

TEST(LoaderTest, ErrorNamesFileLineAndKey) {
  const InputError e = ErrorOf(
      "robots: {count: 2}\ntargets: {count: 1}\n"
      "workspace:\n  size: [0, 20]\n");
  EXPECT_EQ(e.Format(),
            "test.yaml:4: workspace.size: must be two numbers in [0.1, 10000] "
            "[width, "
            "height], "
            "got [0, 20]");
}

TEST(LoaderTest, YamlSyntaxErrorsCarryTheirLine) {
  const InputError e =
      ErrorOf("robots: {count: 2}\ntargets:\n  count: 3\n bad: 1\n");
  EXPECT_EQ(e.key(), "(yaml)");
  EXPECT_GT(e.line(), 0);
  EXPECT_NE(e.message().find("invalid YAML"), std::string::npos);
}

TEST(LoaderTest, LineOfFindsKeysItemsAndParents) {
  const Scenario s = testing::ScenarioFromYaml(R"(robots:
  count: 3
  start:
    - [1, 1]
    - [2, 1]
    - [3, 1]
targets:
  list:
    - position: [4, 4]
      dynamics: {A: [[1, 0], [0, 1]]}
communication:
  failures:
    - {robot: 1, step: 2}
policy:
  name: greedy
  model: net.pt
)");
  EXPECT_EQ(s.LineOf("robots"), 1);
  EXPECT_EQ(s.LineOf("robots.count"), 2);
  EXPECT_EQ(s.LineOf("robots.start"), 3);
  EXPECT_EQ(s.LineOf("robots.start[2]"), 6);
  EXPECT_EQ(s.LineOf("targets.list[0]"), 9);
  EXPECT_EQ(s.LineOf("targets.list[0].position"), 9);
  EXPECT_EQ(s.LineOf("targets.list[0].dynamics.A"), 10);
  EXPECT_EQ(s.LineOf("communication.failures[0].robot"), 13);
  EXPECT_EQ(s.LineOf("policy.name"), 15);
  EXPECT_EQ(s.LineOf("policy.model"), 16);
  // Keys not in the file fall back to their nearest parent, or 0.
  EXPECT_EQ(s.LineOf("robots.radius"), 1);
  EXPECT_EQ(s.LineOf("targets.list[0].dynamics.b"), 10);
  EXPECT_EQ(s.LineOf("targets.list[0].dynamics.A[1]"), 10);
  EXPECT_EQ(s.LineOf("robots.start[7]"), 3);
  EXPECT_EQ(s.LineOf("mission.eps"), 0);
  EXPECT_EQ(s.LineOf(""), 0);
  EXPECT_EQ(Scenario().LineOf("robots.count"), 0);
}

// The loader keeps a policy's parameters as written, with their lines; the
// policy registry reads them against the policy's declaration
// (tests/planning/policy_test.cc).
// A key given a value that nothing reads where it stands is run, with a
// warning at its line; the same key at its default (as effective.yaml
// writes every key), or where it is read, is no warning.
TEST(LoaderTest, KeysThatChangeNothingAreWarnedOfAtTheirLine) {
  const std::string yaml =
      "robots: {count: 2}\n"                                  // 1
      "targets:\n"                                            // 2
      "  prior_offset: 2\n"                                   // 3
      "  list:\n"                                             // 4
      "    - {position: [3, 3], prior_mean: [3, 4]}\n"        // 5
      "communication:\n"                                      // 6
      "  range: 6\n"                                          // 7
      "workspace:\n"                                          // 8
      "  obstacles:\n"                                        // 9
      "    map_threshold: 0.3\n"                              // 10
      "    random: {count: 0}\n"                              // 11
      "    generator: {type: cave, loops: 0.5, fill: 0.4}\n"  // 12
      "physics: {robot_mass: 0.25}\n";                        // 13
  const Scenario s = ParseScenario(yaml, "w.yaml", "");
  EXPECT_EQ(s.warnings,
            (std::vector<std::string>{
                "w.yaml:12: workspace.obstacles.generator.loops: applies to "
                "a maze only; a cave changes nothing by it",
                "w.yaml:10: workspace.obstacles.map_threshold: applies to "
                "workspace.obstacles.map only, and no map is given: it "
                "changes nothing",
                "w.yaml:3: targets.prior_offset: every target of "
                "targets.list gives its prior_mean, so no prior mean is "
                "drawn: it changes nothing",
                "w.yaml:7: communication.range: applies to "
                "communication.mode range only; with mode full every pair "
                "of active robots talks, so it changes nothing"}));
  // Where they are read: none.
  const Scenario read = ParseScenario(
      "robots: {count: 2, model: diff_drive, diff_drive: {max_speed: 1}}\n"
      "targets: {count: 2, prior_offset: 2}\n"
      "communication: {mode: range, range: 6}\n"
      "physics: {robot_mass: 0.25}\n",
      "r.yaml", "");
  EXPECT_TRUE(read.warnings.empty()) << read.warnings.front();
  // Point robots given diff_drive keys; diff_drive robots given kp.
  const Scenario point = ParseScenario(
      "robots: {count: 2, diff_drive: {track: 0.2, max_speed: 1}}\n"
      "targets: {count: 2}\n",
      "p.yaml", "");
  EXPECT_EQ(point.warnings,
            (std::vector<std::string>{
                "p.yaml:1: robots.diff_drive: sets track, max_speed, which "
                "only robots.model diff_drive reads: point robots change "
                "nothing by them"}));
  const Scenario wheeled = ParseScenario(
      "robots: {count: 2, model: diff_drive}\ntargets: {count: 2}\n"
      "physics: {kp: 50}\n",
      "d.yaml", "");
  ASSERT_EQ(wheeled.warnings.size(), 1u);
  EXPECT_EQ(wheeled.warnings[0].rfind("d.yaml:3: physics.kp: applies to "
                                      "point robots only",
                                      0),
            0u)
      << wheeled.warnings[0];
  // effective.yaml writes every key at its value: no new warning.
  EXPECT_TRUE(
      ParseScenario(EffectiveYaml(read, ""), "e.yaml", "").warnings.empty());
}

TEST(LoaderTest, OtherPolicyKeysAreKeptForThePolicy) {
  const Scenario s = testing::ScenarioFromYaml(
      std::string(kMinimal) +
      "policy:\n  name: expert\n  horizon: 8\n  lambda: [1, 2]\n");
  EXPECT_EQ(s.policy.name, "expert");
  ASSERT_EQ(s.policy.params.entries.size(), 2u);
  EXPECT_EQ(s.policy.params.Find("horizon")->scalar, "8");
  EXPECT_TRUE(s.policy.params.Find("lambda")->IsList());
  EXPECT_EQ(s.policy.params.Find("horizon")->line, 5);
  EXPECT_EQ(s.LineOf("policy.horizon"), 5);
}

TEST(LoaderTest, ListTargetsWithTwoAndFourDimensionalDynamics) {
  const Scenario s = testing::ScenarioFromYaml(R"(robots: {count: 1}
targets:
  list:
    - position: [1, 2]
      dynamics: {A: [[1, 0], [0, 1]], b: [0.1, -0.2], q: 0.01}
    - position: [3, 4]
      velocity: [0.5, -0.25]
      dynamics:
        A: [[1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1]]
        q: 0.0
    - position: [5, 6]
      dynamics:
        A: [[1, 0, 0.5, 0], [0, 1, 0, 0.5], [0, 0, 1, 0], [0, 0, 0, 1]]
        b: [0, 0, 0.1, 0]
)");
  ASSERT_EQ(s.NumTargets(), 3);
  const TargetModel& d0 = s.targets.list[0].dynamics;
  EXPECT_EQ(d0.dim(), 2);
  EXPECT_EQ(d0.b, Eigen::Vector2d(0.1, -0.2));
  EXPECT_EQ(d0.q, 0.01);
  EXPECT_EQ(s.targets.list[0].velocity, Vec2(0.0, 0.0));

  const TargetModel& d1 = s.targets.list[1].dynamics;
  EXPECT_EQ(d1.dim(), 4);
  Eigen::MatrixXd a(4, 4);
  a << 1, 0, 1, 0, 0, 1, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_EQ(d1.A, a);
  EXPECT_EQ(d1.b, Eigen::VectorXd::Zero(4));  // b defaults to zeros of A's size
  EXPECT_EQ(s.targets.list[1].velocity, Vec2(0.5, -0.25));
  EXPECT_FALSE(d1.IsStatic());

  const TargetModel& d2 = s.targets.list[2].dynamics;
  EXPECT_EQ(d2.dim(), 4);
  EXPECT_EQ(d2.A(0, 2), 0.5);
  EXPECT_EQ(d2.b, Eigen::Vector4d(0, 0, 0.1, 0));

  // A 4x4 A with a 2-vector b, and the other way round.
  EXPECT_EQ(
      ErrorOf(
          "robots: {count: 1}\ntargets: {list: [{position: [1, 1], dynamics: "
          "{A: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], b: [0, 0]}}]}\n")
          .message(),
      "must be four numbers (one per row of A), got [0, 0]");
  EXPECT_EQ(
      ErrorOf(
          "robots: {count: 1}\ntargets: {list: [{position: [1, 1], dynamics: "
          "{b: [0, 0, 0, 0]}}]}\n")
          .key(),
      "targets.list[0].dynamics.b");
}

TEST(LoaderTest, IsStaticOnlyForIdentityWithoutDriftOrNoise) {
  TargetModel d;
  EXPECT_TRUE(d.IsStatic());
  d.q = 1e-6;
  EXPECT_FALSE(d.IsStatic());
  d.q = 0.0;
  d.b = Eigen::Vector2d(0.0, 1e-9);
  EXPECT_FALSE(d.IsStatic());
  d.A = Eigen::MatrixXd::Identity(4, 4);
  d.b = Eigen::VectorXd::Zero(4);
  EXPECT_TRUE(d.IsStatic());
  d.A(0, 2) = 1.0;
  EXPECT_FALSE(d.IsStatic());
}

TEST(LoaderTest, TargetCountAndListMustAgree) {
  const std::string list =
      "  list:\n    - {position: [1, 1]}\n    - {position: [2, 2]}\n";
  const std::string robots = "robots: {count: 1}\n";

  const Scenario both =
      testing::ScenarioFromYaml(robots + "targets:\n  count: 2\n" + list);
  EXPECT_EQ(both.NumTargets(), 2);
  const Scenario only_list =
      testing::ScenarioFromYaml(robots + "targets:\n" + list);
  EXPECT_EQ(only_list.NumTargets(), 2);
  const Scenario only_count =
      testing::ScenarioFromYaml(robots + "targets: {count: 5}\n");
  EXPECT_EQ(only_count.NumTargets(), 5);
  EXPECT_TRUE(only_count.targets.list.empty());

  const InputError e = ErrorOf(robots + "targets:\n  count: 3\n" + list);
  EXPECT_EQ(e.key(), "targets.count");
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.message().find("is 3 but targets.list has 2 targets"),
            std::string::npos);

  EXPECT_EQ(ErrorOf(robots + "targets: {list: []}\n").key(), "targets.list");
}

TEST(LoaderTest, IntegersAreNotFloats) {
  EXPECT_EQ(ErrorOf("robots: {count: 2.0}\ntargets: {count: 1}\n").message(),
            "must be an integer in [1, 5000], got 2.0");
  EXPECT_EQ(ErrorOf("robots: {count: 1e1}\ntargets: {count: 1}\n").key(),
            "robots.count");
  EXPECT_EQ(ErrorOf("robots: {count: 0x10}\ntargets: {count: 1}\n").key(),
            "robots.count");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "seed: 1.5\n").key(), "seed");
  EXPECT_EQ(
      ErrorOf(std::string(kMinimal) + "seed: 18446744073709551616\n").key(),
      "seed");
  EXPECT_EQ(testing::ScenarioFromYaml(std::string(kMinimal) +
                                      "seed: 18446744073709551615\n")
                .seed,
            18446744073709551615u);
  // Whole numbers are fine where reals are expected.
  EXPECT_EQ(
      testing::ScenarioFromYaml(std::string(kMinimal) + "mission: {eps: 1}\n")
          .mission.eps,
      1.0);
  EXPECT_EQ(testing::ScenarioFromYaml(std::string(kMinimal) +
                                      "mission: {eps: +.5e-1}\n")
                .mission.eps,
            0.05);
}

TEST(LoaderTest, FailuresAndFollowRobotIndexRobots) {
  const Scenario s = testing::ScenarioFromYaml(
      "robots: {count: 3}\ntargets: {count: 1}\n"
      "communication: {mode: range, failures: [{robot: 2, step: 0}, {step: "
      "4}]}\n"
      "render: {follow_robot: -1}\n");
  EXPECT_EQ(s.communication.mode, CommMode::kRange);
  ASSERT_EQ(s.communication.failures.size(), 2u);
  EXPECT_EQ(s.communication.failures[0].robot, 2);
  EXPECT_EQ(s.communication.failures[1].robot, -1);
  EXPECT_EQ(s.communication.failures[1].step, 4);
  EXPECT_EQ(s.render.follow_robot, -1);
  EXPECT_EQ(ErrorOf("robots: {count: 3}\ntargets: {count: 1}\n"
                    "communication: {failures: [{robot: -1}]}\n")
                .key(),
            "communication.failures[0].robot");
}

TEST(LoaderTest, EmptySectionMeansDefaults) {
  const Scenario s =
      testing::ScenarioFromYaml(std::string(kMinimal) +
                                "workspace:\n  obstacles:\n    random:\n"
                                "sensor:\n");
  ASSERT_TRUE(s.workspace.obstacles.random.has_value());
  EXPECT_EQ(s.workspace.obstacles.random->count, RandomObstaclesConfig().count);
  EXPECT_EQ(s.sensor.range, SensorModel().range);
}

TEST(LoaderTest, UnknownKeySuggestsTheNearestValidKey) {
  const InputError e = ErrorOf(std::string(kMinimal) + "sensor: {rnage: 2}\n");
  EXPECT_EQ(e.key(), "sensor.rnage");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.message(),
            "unknown key (did you mean `range`?); valid keys under sensor: "
            "range, eta, "
            "sigma0, line_of_sight, rate");
  EXPECT_EQ(ErrorOf(std::string(kMinimal) + "zzz: 1\n")
                .message()
                .find("did you mean"),
            std::string::npos);
}

TEST(LoaderTest, TargetPriorOffsetIsReadable) {
  EXPECT_EQ(testing::ScenarioFromYaml(
                "robots: {count: 1}\ntargets: {count: 1, prior_offset: 0}\n")
                .targets.prior_offset,
            0.0);
  EXPECT_EQ(
      ErrorOf("robots: {count: 1}\ntargets: {count: 1, prior_offset: -1}\n")
          .key(),
      "targets.prior_offset");
}

}  // namespace
}  // namespace aia

namespace aia {
namespace {

// Every scenario written back as its effective YAML reads back to the same
// scenario (the same YAML again), defaults and all.
TEST(EffectiveYamlTest, ReadsBackToTheSameScenario) {
  const std::string dir = testing::MakeTempDir("aia_effective_");
  std::vector<std::string> files;
  for (const auto& entry :
       fs::directory_iterator(testing::SourcePath("scenarios")))
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  WriteFile(dir, "maps/maze.pgm", "P2\n1 1\n255\n0\n");
  files.push_back(WriteFile(dir, "demo.yaml", kFullExample));
  ASSERT_GE(files.size(), 6u);
  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    const Scenario s = LoadScenario(file);
    const std::string yaml = EffectiveYaml(s, "# header\n");
    EXPECT_EQ(yaml.rfind("# header\nname: ", 0), 0u);
    const std::string path = WriteFile(dir, "effective.yaml", yaml);
    const Scenario back = LoadScenario(path);
    EXPECT_EQ(EffectiveYaml(back, "# header\n"), yaml);
    EXPECT_EQ(back.seed, s.seed);
    EXPECT_EQ(back.NumTargets(), s.NumTargets());
  }
  fs::remove_all(dir);
}

InputError OverrideError(const std::vector<Override>& overrides) {
  try {
    ParseScenario(kMinimal, "m.yaml", ".", overrides);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return InputError("", 0, "", "");
}

TEST(OverrideTest, SetChangesKeysAtAnyDepth) {
  const Scenario s = ParseScenario(
      kMinimal, "m.yaml", ".",
      {ParseSetFlag("mission.eps=0.05"),
       ParseSetFlag("workspace.size=[30, 25]"),
       ParseSetFlag("communication.failures=[{robot: 1, step: 4}]"),
       ParseSetFlag("communication.failures[0].step=6"),
       {"--seed", "seed", "42"}});
  EXPECT_EQ(s.mission.eps, 0.05);
  EXPECT_EQ(s.workspace.size, Vec2(30, 25));
  ASSERT_EQ(s.communication.failures.size(), 1u);
  EXPECT_EQ(s.communication.failures[0].step, 6);
  EXPECT_EQ(s.seed, 42u);
  EXPECT_EQ(s.robots.count, 2);  // the file's
}

TEST(OverrideTest, BadOverridesNameTheirFlag) {
  EXPECT_EQ(OverrideError({ParseSetFlag("robots.cuont=3")}).Format(),
            "command line: --set robots.cuont: unknown key (did you mean "
            "`count`?); valid keys under robots: count, radius, step, start, "
            "model, diff_drive");
  EXPECT_EQ(OverrideError({ParseSetFlag("mission.eps=-1")}).Format(),
            "command line: --set mission.eps: must be a number in [1e-30, "
            "1e+30], got -1");
  EXPECT_EQ(OverrideError({{"--max-steps", "mission.max_steps", "0"}}).Format(),
            "command line: --max-steps: must be an integer in [1, 1000000], "
            "got 0");
  EXPECT_EQ(
      OverrideError({ParseSetFlag("targets.list[2].position=[1, 1]")}).Format(),
      "command line: --set targets.list[2].position: targets.list is "
      "not given, so it has no targets.list[2]");
  EXPECT_EQ(OverrideError({ParseSetFlag("robots.count.x=1")}).message(),
            "robots.count is not a mapping, so it has no key `x`");
  // A key path that the file does not give yet is made, then checked.
  EXPECT_EQ(OverrideError({ParseSetFlag("mission.eps.x=1")}).message(),
            "must be a number in [1e-30, 1e+30], got {x: 1}");
  // A start outside the workspace set on the command line.
  EXPECT_EQ(
      OverrideError({ParseSetFlag("robots.start=[[1, 1], [50, 1]]")}).Format(),
      "command line: --set robots.start[1]: must lie inside the "
      "workspace [0, 20] x [0, 20], got [50, 1]");
  for (const char* bad : {"novalue", "=3", "a..b=1", "a.[1]=2", "a b=1"}) {
    try {
      ParseSetFlag(bad);
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.Format().rfind("command line: --set: ", 0), 0u) << e.Format();
    }
  }
}

// Key paths are scanned by hand (a std::regex overflowed the stack on a
// path of some 30 000 characters) and accept what the expression did:
// dot-separated ([A-Za-z_][A-Za-z0-9_]*)((\[[0-9]{1,9}\])*).
TEST(OverrideTest, KeyPathsAreWhatTheFormerRegexAccepted) {
  const auto accepted = [](const std::string& path) {
    try {
      ParseSetFlag(path + "=1");
      return true;
    } catch (const InputError& e) {
      EXPECT_EQ(e.Format().rfind("command line: --set: ", 0), 0u) << e.Format();
      return false;
    }
  };
  const std::regex segment(R"(([A-Za-z_][A-Za-z0-9_]*)((\[[0-9]{1,9}\])*))");
  const auto by_regex = [&segment](const std::string& path) {
    std::size_t begin = 0;
    while (true) {
      const std::size_t dot = path.find('.', begin);
      if (!std::regex_match(
              path.substr(begin, dot == std::string::npos ? std::string::npos
                                                          : dot - begin),
              segment))
        return false;
      if (dot == std::string::npos) return true;
      begin = dot + 1;
    }
  };
  for (const char* good :
       {"a", "_", "_a9", "mission.eps", "targets.list[0].position", "a[1][22]",
        "a[123456789]", "A.b_C.d9", "a[0].b[1].c"}) {
    EXPECT_TRUE(accepted(good)) << good;
    EXPECT_TRUE(by_regex(good)) << good;
  }
  for (const char* bad :
       {".a", "a.", "a..b", "9a", "a[]", "a[1234567890]", "a[-1]", "a[1]b",
        "a b", "a-b", "[0]", "a.[0]", "a[0", "a]", "a[x]", "\xc3\xa9"}) {
    EXPECT_FALSE(accepted(bad)) << bad;
    EXPECT_FALSE(by_regex(bad)) << bad;
  }
  // Every path of up to 5 characters over "a9_.[]".
  const std::string alphabet = "a9_.[]";
  std::vector<std::string> paths = {""};
  for (std::size_t begin = 0, length = 0; length < 5; ++length) {
    const std::size_t end = paths.size();
    for (std::size_t i = begin; i < end; ++i)
      for (const char c : alphabet) paths.push_back(paths[i] + c);
    begin = end;
  }
  for (std::size_t i = 1; i < paths.size(); ++i)
    EXPECT_EQ(accepted(paths[i]), by_regex(paths[i])) << "'" << paths[i] << "'";
  // A path of 100 000 characters is scanned, not recursed into.
  EXPECT_TRUE(accepted(std::string(100000, 'a')));
  EXPECT_FALSE(accepted(std::string(100000, 'a') + "-"));
}

// A --set value is one YAML document in UTF-8 (yaml-cpp read a second
// document as nothing and bytes that are not UTF-8 as nothing).
TEST(OverrideTest, SetValueIsOneDocumentInUtf8) {
  EXPECT_EQ(OverrideError({ParseSetFlag("seed=1\n---\n2")}).Format(),
            "command line: --set seed: the value holds 2 YAML documents "
            "(separated by ---), not one: '1\\n---\\n2'");
  EXPECT_EQ(OverrideError({ParseSetFlag("name=\xff")}).Format(),
            "command line: --set name: the value is not UTF-8 text");
  EXPECT_EQ(OverrideError({ParseSetFlag("mission.eps=\xff\xfe")}).Format(),
            "command line: --set mission.eps: the value is not UTF-8 text");
  EXPECT_EQ(ParseYamlValue("[1, 2]", "--set").items.size(), 2u);
  EXPECT_TRUE(ParseYamlValue("", "--set").IsNull());
}

// A quoted value ends on the line it starts on: YAML would let a missing
// closing quote take the lines after it (keys and all) into one string,
// which yaml-cpp accepts wherever the text ends with a newline.
TEST(YamlTest, AQuotedValueEndsOnItsLine) {
  const std::string open = "a: 1\nname: \"abc\nb: {c: -5}\n";
  try {
    ParseYaml(open, "f.yaml");
    FAIL() << "read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Format(),
              "f.yaml:2: (yaml): the quoted value at column 7 does not end on "
              "its line (a missing closing quote?); a quoted value must end on "
              "the line it starts on");
  }
  EXPECT_EQ(OverrideError({ParseSetFlag("name='abc\nx\n")}).Format(),
            "command line: --set name: the quoted value at column 1 does not "
            "end on its line (a missing closing quote?); a quoted value must "
            "end on the line it starts on");
  // Escapes and doubled quotes do not end a value; quoted keys are values.
  const ConfigNode ok =
      ParseYaml("\"a\": \"x \\\" y\"\nb: 'it''s'\nc: [\"p\", 'q']\n", "f.yaml");
  EXPECT_EQ(ok.Find("a")->scalar, "x \" y");
  EXPECT_EQ(ok.Find("b")->scalar, "it's");
}

// Two documents hold the same value whatever their layout and key order; a
// scalar's text, style and the order of a list count.
TEST(YamlTest, SameValueIgnoresLayoutAndKeyOrderOnly) {
  const auto same = [](const std::string& a, const std::string& b) {
    return SameValue(ParseYaml(a, "a"), ParseYaml(b, "b"));
  };
  EXPECT_TRUE(
      same("a: 1\nb: {c: [1, 2]}\n", "b:\n    c:\n    - 1\n    - 2\na: 1\n"));
  EXPECT_FALSE(same("a: 1\n", "a: \"1\"\n"));
  EXPECT_FALSE(same("a: 1\n", "a: 1.0\n"));
  EXPECT_FALSE(same("a: [1, 2]\n", "a: [2, 1]\n"));
  EXPECT_FALSE(same("a: 1\n", "a: 1\nb: 2\n"));
  EXPECT_FALSE(same("a: {}\n", "a: []\n"));
}

// Issue 37: 100 000 keys under one mapping took 12 s and a flow mapping of
// 1.2 million keys 83 s and 1.2 GB (each key was compared with every key
// before it, and yaml-cpp built its whole tree before the value cap was
// counted). Keys are now found in a hash map, and the cap is counted while
// the parser reads. (Times are not asserted: ctest's timeout catches a
// quadratic parse.)
TEST(YamlTest, ManyKeysParseLinearlyAndTheCapStopsTheParserEarly) {
  std::string flow = "policy: {";
  for (int i = 0; i < 1200000; ++i)
    flow += (i ? ", k" : "k") + std::to_string(i) + ": 1";
  flow += "}\n";
  try {
    ParseYaml(flow, "flow.yaml");
    ADD_FAILURE() << "1.2 million keys were read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_EQ(e.key(), "(yaml)");
    EXPECT_NE(e.message().find("more than 200000 values"), std::string::npos)
        << e.message();
  }
  // Below the cap, a duplicate at the end of 90 000 keys is found, with the
  // line of its first use.
  std::string block = "policy:\n";
  for (int i = 0; i < 90000; ++i) block += "  k" + std::to_string(i) + ": 1\n";
  EXPECT_EQ(ParseYaml(block, "b.yaml").Find("policy")->entries.size(), 90000u);
  block += "  k17: 2\n";
  try {
    ParseYaml(block, "b.yaml");
    ADD_FAILURE() << "the duplicate was not found";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 90002);
    EXPECT_EQ(e.key(), "policy.k17");
    EXPECT_NE(e.message().find("first given at line 19"), std::string::npos)
        << e.message();
  }
}

// Issue 37: a custom tag was silently dropped; yaml-cpp's own depth limit
// said "bad file".
TEST(YamlTest, CustomTagsAndDeepNestingAreNamed) {
  for (const char* text : {"a: !foo 1\n", "a: !foo {b: 1}\n", "a: !foo [1]\n",
                           "a: !!seq {b: 1}\n", "!foo a: 1\n"}) {
    try {
      ParseYaml(text, "t.yaml");
      ADD_FAILURE() << text << " was read";
    } catch (const InputError& e) {
      EXPECT_EQ(e.key(), "a") << text;
      EXPECT_NE(e.message().find("is not one aia reads"), std::string::npos)
          << e.message();
    }
  }
  EXPECT_EQ(
      ParseYaml("a: !!str 5\nb: !!map {c: 1}\n", "t.yaml").Find("a")->scalar,
      "5");
  for (const int depth : {70, 600, 3000}) {
    const std::string text =
        "a: " + std::string(depth, '[') + std::string(depth, ']') + "\n";
    try {
      ParseYaml(text, "t.yaml");
      ADD_FAILURE() << depth << " levels were read";
    } catch (const InputError& e) {
      EXPECT_NE(e.message().find("nests deeper than 64 levels"),
                std::string::npos)
          << depth << ": " << e.message();
    }
    EXPECT_THROW(ParseYamlValue(text.substr(3), "--set", "--set a"),
                 InputError);
  }
}

// YAML's own scalar tags give their value (scenarios.md): `!!int 3` is the
// integer 3, as the plain 3 is; a text the tag does not fit is refused at
// its key, and `!!str 3` stays a string (not a seed).
TEST(YamlTest, CoreTagsAreReadAsTheirValues) {
  const Scenario tagged = ParseScenario(
      "seed: !!int 3\nmission: {eps: !!float 0.25}\nsensor: {range: !!float "
      "3, line_of_sight: !!bool false}\nrobots: {count: 2}\ntargets: {count: "
      "2}\n",
      "t.yaml", ".");
  const Scenario plain = ParseScenario(
      "seed: 3\nmission: {eps: 0.25}\nsensor: {range: 3.0, line_of_sight: "
      "false}\n"
      "robots: {count: 2}\ntargets: {count: 2}\n",
      "t.yaml", ".");
  EXPECT_EQ(EffectiveYaml(tagged, ""), EffectiveYaml(plain, ""));
  const std::pair<const char*, const char*> bad[] = {
      {"seed: !!int 0.5\n",
       "seed: '0.5' is not an integer, as its tag !!int "
       "says"},
      {"mission: {eps: !!float abc}\n",
       "mission.eps: 'abc' is not a decimal number, as its tag !!float says"},
      {"sensor: {line_of_sight: !!bool 1}\n",
       "sensor.line_of_sight: '1' is not true or false, as its tag !!bool "
       "says"},
      {"seed: !!str 3\n", "seed: must be an integer >= 0, got !!str 3"},
      // `!!float 12` is the decimal 12.0, refused as 12.0 is.
      {"seed: !!float 12\n", "seed: must be an integer >= 0, got 12.0"}};
  for (const auto& [text, message] : bad) {
    try {
      ParseScenario(text, "t.yaml", ".");
      ADD_FAILURE() << text << " was read";
    } catch (const InputError& e) {
      EXPECT_EQ(e.Format(), std::string("t.yaml:1: ") + message) << text;
    }
  }
}

// Seeds take the whole unsigned 64-bit range and nothing beyond it.
TEST(OverrideTest, SeedsBeyond64BitsAreRefusedAtTheirLine) {
  const std::string yaml =
      std::string(kMinimal) + "seed: 18446744073709551615\n";
  EXPECT_EQ(ParseScenario(yaml, "m.yaml", ".").seed, 18446744073709551615u);
  try {
    ParseScenario(
        std::string(kMinimal) + "seed: " + std::string(30, '9') + "\n",
        "m.yaml", ".");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.Format(),
              "m.yaml:3: seed: must be an integer >= 0 that fits in 64 bits "
              "(at most 18446744073709551615), got " +
                  std::string(30, '9'));
  }
  EXPECT_EQ(OverrideError({ParseSetFlag("seed=18446744073709551616")}).Format(),
            "command line: --set seed: must be an integer >= 0 that fits in "
            "64 bits (at most 18446744073709551615), got "
            "18446744073709551616");
}

// Names that look like numbers, however long, are written quoted and read
// back as themselves (the writer asked a std::regex, which overflowed the
// stack on 30 000 digits).
TEST(OverrideTest, LongNumericNamesAreQuotedInTheEffectiveScenario) {
  const std::string digits(100000, '1');
  const Scenario s = ParseScenario(
      std::string(kMinimal) + "name: \"" + digits + "\"\n", "m.yaml", ".");
  EXPECT_EQ(s.name, digits);
  const std::string yaml = EffectiveYaml(s, "");
  EXPECT_NE(yaml.find("name: \"" + digits + "\"\n"), std::string::npos);
  EXPECT_EQ(ParseScenario(yaml, "e.yaml", ".").name, digits);
}

TEST(OverrideTest, ANewPolicyDropsTheFilesParametersButKeepsSetOnes) {
  const std::string yaml =
      std::string(kMinimal) + "policy: {name: expert, p_v: 0.3}\n";
  const Scenario same = ParseScenario(yaml, "m.yaml", ".",
                                      {{"--policy", "policy.name", "expert"}});
  ASSERT_NE(same.policy.params.Find("p_v"), nullptr);
  const Scenario other = ParseScenario(
      yaml, "m.yaml", ".",
      {{"--policy", "policy.name", "decsb"}, ParseSetFlag("policy.horizon=4")});
  EXPECT_EQ(other.policy.name, "decsb");
  EXPECT_EQ(other.policy.params.Find("p_v"), nullptr);
  ASSERT_NE(other.policy.params.Find("horizon"), nullptr);
  EXPECT_EQ(other.policy.params.Find("horizon")->origin, "--set");
}

TEST(OverrideTest, WithOverridesRereadsACodeBuiltScenario) {
  Scenario s;
  s.robots.count = 3;
  s.targets.count = 2;
  const Scenario t = WithOverrides(s, {ParseSetFlag("sensor.range=3.5")});
  EXPECT_EQ(t.sensor.range, 3.5);
  EXPECT_EQ(t.robots.count, 3);
  EXPECT_EQ(EffectiveYaml(WithOverrides(s, {}), ""), EffectiveYaml(s, ""));
}

TEST(SchemaTest, EveryKeyIsDocumented) {
  const std::vector<FieldDoc> rows = ScenarioKeys();
  ASSERT_GT(rows.size(), 40u);
  bool has_nested = false;
  for (const FieldDoc& r : rows) {
    EXPECT_FALSE(r.doc.empty()) << r.key;
    EXPECT_FALSE(r.type.empty()) << r.key;
    has_nested = has_nested || r.key == "targets.list[i].dynamics.q";
  }
  EXPECT_TRUE(has_nested);
}

}  // namespace
}  // namespace aia
