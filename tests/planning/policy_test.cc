#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/estimation/filter.h"
#include "aia/planning/decsb.h"
#include "aia/planning/expert.h"
#include "aia/planning/greedy.h"
#include "aia/planning/information.h"
#include "aia/planning/random_policy.h"
#include "aia/planning/registry.h"
#include "support/team_fixture.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

using PolicyFixture = testing::TeamFixture;

TEST(InformationTest, PredictedPrecisionHonoursRangeAndSight) {
  PolicyFixture s(
      "robots: {count: 1, start: [[1.25, 1.25]]}\ntargets: {count: 1}\n"
      "workspace: {obstacles: {boxes: [{center: [5, 5], size: [0.4, 4]}]}}\n");
  // 1.5 m in the open: 1 / (0.01 + 0.05 * 1.5)^2.
  EXPECT_NEAR(PredictedPrecision(s.world.map, s.sensor, {2, 8}, {3.5, 8}),
              1.0 / (0.085 * 0.085), 1e-9);
  EXPECT_EQ(PredictedPrecision(s.world.map, s.sensor, {2, 8}, {4.5, 8}),
            0.0);  // 2.5 m
  EXPECT_EQ(PredictedPrecision(s.world.map, s.sensor, {4.2, 5}, {5.8, 5}),
            0.0);  // behind the wall
}

TEST(InformationTest, LogDetAfterMeasurementByHand) {
  PredictedBlock b;
  b.dim = 2;
  b.omega.topLeftCorner<2, 2>() << 2, 1, 1, 3;  // det 5
  EXPECT_NEAR(LogDetSigmaAfter(b, 0.0), -std::log(5.0), 1e-12);
  EXPECT_NEAR(LogDetSigmaAfter(b, 1.0), -std::log(3 * 4 - 1.0), 1e-12);
  b.dim = 4;
  b.omega.setIdentity();
  b.omega(0, 0) = 2;
  EXPECT_NEAR(LogDetSigmaAfter(b, 1.0), -std::log(3.0 * 2.0), 1e-12);
}

// Dec-SB's sum of what the neighbours' announced positions will measure,
// by the grid of targets near each position, is the plain sum over every
// pair to the last bit: means inside and outside the workspace, on the
// sensor's range exactly, far off and not finite; ranges below a cell, of a
// cell and beyond the workspace; with boxes blocking the sight.
TEST(DecSbTest, AnnouncedPrecisionByGridIsThePlainSum) {
  PolicyFixture s(
      "workspace: {size: [30.0, 20.0], obstacles: {random: {count: 40}}}\n"
      "robots: {count: 2}\ntargets: {count: 1}\n");
  Rng rng(7, "test.decsb_grid", 0);
  const Lattice& lattice = s.world.map.lattice();
  for (const double range : {0.001, 0.3, 2.0, 5.5, 100.0}) {
    SensorModel sensor = s.sensor;
    sensor.range = range;
    std::vector<Vec2> announced, means;
    for (int j = 0; j < 60; ++j)
      announced.push_back(
          lattice.Point(static_cast<int>(rng.UniformInt(lattice.size()))));
    for (int k = 0; k < 300; ++k)
      means.push_back({rng.Uniform(-3.0, 33.0), rng.Uniform(-3.0, 23.0)});
    // On the range exactly (along an axis and a diagonal), and beyond.
    for (int j = 0; j < 10; ++j) {
      means.push_back(announced[j] + Vec2(range, 0.0));
      means.push_back(announced[j] - Vec2(0.0, range));
      means.push_back(announced[j] + Vec2(range, range) / std::sqrt(2.0));
    }
    const double inf = std::numeric_limits<double>::infinity();
    means.push_back({1e12, -1e12});
    means.push_back({std::nan(""), 3.0});
    means.push_back({inf, 5.0});
    internal::TargetGrid grid;
    std::vector<double> plain, gridded;
    internal::AnnouncedPrecision(s.world.map, sensor, announced, means,
                                 std::numeric_limits<long>::max(), &grid,
                                 &plain);
    internal::AnnouncedPrecision(s.world.map, sensor, announced, means, 0,
                                 &grid, &gridded);
    ASSERT_EQ(plain.size(), means.size());
    int measured = 0;
    for (std::size_t k = 0; k < means.size(); ++k) {
      EXPECT_EQ(std::memcmp(&plain[k], &gridded[k], sizeof(double)), 0)
          << "range " << range << " target " << k << ": " << plain[k]
          << " against " << gridded[k];
      measured += plain[k] > 0.0;
    }
    if (range >= 2.0) EXPECT_GT(measured, 20) << range;  // not all zeros
  }
}

TEST(RandomPolicyTest, ReturnsValidMovesAndIsReproducible) {
  PolicyFixture s(
      "seed: 2\nrobots: {count: 8}\ntargets: {count: 3}\n"
      "workspace: {obstacles: {random: {count: 30}}}\n");
  RandomPolicy a, b;
  a.Reset(s.world.map, 8, s.world.NumTargets(), 5);
  b.Reset(s.world.map, 8, s.world.NumTargets(), 5);
  std::vector<Move> ma(8), mb(8);
  for (int t = 0; t < 20; ++t) {
    a.Decide(s.Context(), &ma);
    b.Decide(s.Context(), &mb);
    EXPECT_EQ(ma, mb);
    for (int i = 0; i < 8; ++i)
      EXPECT_TRUE(s.world.map.lattice().Valid(s.positions[i], ma[i]));
  }
}

// The rule that greedy and the expert's greedy rollout share, on gains set
// by hand: moves in order left, right, up, down; a wall on the left.
TEST(GreedyMovesTest, LargestPositiveGainsWithinToleranceInMoveOrder) {
  const Lattice lattice({2.0, 2.0}, 0.5, 0.1, {});
  const int p = lattice.Index(0, 1);  // no move left
  const int right = lattice.Index(1, 1), up = lattice.Index(0, 2),
            down = lattice.Index(0, 0);
  std::vector<int> asked;
  const auto gains = [&](double g_right, double g_up, double g_down) {
    return [&asked, right, up, down, g_right, g_up, g_down](int q) {
      asked.push_back(q);
      return q == right ? g_right : q == up ? g_up : q == down ? g_down : -1.0;
    };
  };
  Move best[kNumMoves];
  int valid = -1;
  EXPECT_EQ(GreedyMoves(lattice, p, gains(1.0, 3.0, 2.0), best, &valid), 1);
  EXPECT_EQ(valid, 3);
  EXPECT_EQ(best[0], Move::kUp);
  EXPECT_EQ(asked, (std::vector<int>{right, up, down}));
  // Equal within a relative 1e-12: both, in move order.
  EXPECT_EQ(GreedyMoves(lattice, p, gains(5.0, 5.0 + 1e-12, 4.0), best, &valid),
            2);
  EXPECT_EQ(best[0], Move::kRight);
  EXPECT_EQ(best[1], Move::kUp);
  // Nothing positive: no move.
  EXPECT_EQ(GreedyMoves(lattice, p, gains(0.0, 0.0, 0.0), best, &valid), 0);
  EXPECT_EQ(valid, 3);
  // Only the part above log eps counts: log det -1 to -5 with log eps -3.
  EXPECT_DOUBLE_EQ(LogDetDrop(-1.0, -5.0, -3.0), 2.0);
  EXPECT_DOUBLE_EQ(LogDetDrop(-1.0, -2.0, -3.0), 1.0);
}

TEST(GreedyPolicyTest, MovesTowardANearbyTarget) {
  // Target 2.25 m to the right of the robot, prior mean on it: only the move
  // right brings it into range.
  PolicyFixture s(
      "robots: {count: 1, start: [[5.25, 5.25]]}\n"
      "targets: {list: [{position: [7.5, 5.25], prior_mean: [7.5, 5.25]}]}\n");
  GreedyPolicy g;
  g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
  std::vector<Move> m(1);
  g.Decide(s.Context(), &m);
  EXPECT_EQ(m[0], Move::kRight);
}

TEST(GreedyPolicyTest, FallsBackToShortestPathTowardTheNearestTarget) {
  // Far from every target: no move gains, so the robot walks a shortest
  // lattice path toward the nearer target (the left one), around a wall.
  PolicyFixture s(
      "robots: {count: 1, start: [[10.25, 10.25]]}\n"
      "targets: {list: [{position: [2.0, 10.25], prior_mean: [2.0, 10.25]},"
      " {position: [19.5, 19.5], prior_mean: [19.5, 19.5]}]}\n"
      "workspace: {obstacles: {boxes: [{center: [8.0, 10.0], size: [0.4, "
      "3.0]}]}}\n");
  GreedyPolicy g;
  g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
  std::vector<Move> m(1);
  std::vector<int> dist, queue;
  // BFS distance to the points that observe the left target.
  std::vector<int> goals;
  for (int q = 0; q < s.world.map.lattice().size(); ++q)
    if (s.world.map.lattice().Free(q) &&
        PredictedPrecision(s.world.map, s.sensor,
                           s.world.map.lattice().Point(q), {2.0, 10.25}) > 0)
      goals.push_back(q);
  BfsDistances(s.world.map.lattice(), goals.data(),
               static_cast<int>(goals.size()), &dist, &queue);
  for (int step = 0; step < 40 && dist[s.positions[0]] > 0; ++step) {
    const int before = dist[s.positions[0]];
    g.Decide(s.Context(), &m);
    const int next = s.world.map.lattice().Next(s.positions[0], m[0]);
    ASSERT_GE(next, 0) << "greedy chose an invalid move";
    s.positions[0] = next;
    EXPECT_EQ(dist[next], before - 1);  // every step is on a shortest path
  }
  EXPECT_EQ(dist[s.positions[0]], 0);
}

TEST(GreedyPolicyTest, TargetsAtTheSameDistanceGoToTheLowestIndex) {
  // Two targets mirrored about the robot, far out of range: their nearest
  // observation points are equally far, and the lower target index decides
  // (what scanning the targets in order over a full BFS finds), whichever
  // side it is on.
  for (const bool right_first : {true, false}) {
    const std::string right =
        "{position: [18.25, 10.25], prior_mean: [18.25, 10.25]}";
    const std::string left =
        "{position: [2.25, 10.25], prior_mean: [2.25, 10.25]}";
    PolicyFixture s(
        "robots: {count: 1, start: [[10.25, 10.25]]}\n"
        "targets: {list: [" +
        (right_first ? right + ", " + left : left + ", " + right) + "]}\n");
    GreedyPolicy g;
    g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
    std::vector<Move> m(1);
    g.Decide(s.Context(), &m);
    EXPECT_EQ(m[0], right_first ? Move::kRight : Move::kLeft);
  }
}

TEST(GreedyPolicyTest, IgnoresTargetsAlreadyBelowEps) {
  // The near target is already localized in the robot's belief, the far one
  // is not: the robot heads for the far one (down), not the near one (right).
  PolicyFixture s(
      "robots: {count: 1, start: [[10.25, 10.25]]}\n"
      "targets: {list: [{position: [12.5, 10.25], prior_mean: [12.5, 10.25]},"
      " {position: [10.25, 2.0], prior_mean: [10.25, 2.0]}]}\n");
  s.beliefs.Omega(0, 0) *= 100.0;  // det Sigma = 1e-4 <= eps
  s.beliefs.Xi(0, 0) *= 100.0;
  GreedyPolicy g;
  g.Reset(s.world.map, 1, s.world.NumTargets(), 1);
  std::vector<Move> m(1);
  g.Decide(s.Context(), &m);
  EXPECT_EQ(m[0], Move::kDown);
}

TEST(RegistryTest, UnknownNameListsTheValidOnes) {
  const PolicyRegistry r = BuiltinPolicies();
  EXPECT_TRUE(r.Has("random"));
  EXPECT_TRUE(r.Has("greedy"));
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\npolicy: {name: nope}\n");
  try {
    r.Resolve(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "policy.name");
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(e.message().find("random"), std::string::npos);
  }
}

TEST(RegistryTest, UnknownPolicyParameterIsAnError) {
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\npolicy:\n  name: greedy\n  "
      "budget: 3\n");
  try {
    BuiltinPolicies().Resolve(s);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "policy.budget");
    EXPECT_EQ(e.line(), 5);
    EXPECT_EQ(e.message(),
              "unknown parameter for policy 'greedy' (valid: none)");
  }
}

TEST(RegistryTest, ParametersAreTypedCheckedAndWrittenBackInFull) {
  Scenario s = ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\n"
      "policy: {name: expert, p_v: 0.5, anytime: 300}\n");
  const auto spec = BuiltinPolicies().Resolve(s);
  EXPECT_EQ(spec->name(), "expert");
  EXPECT_TRUE(spec->centralized());
  const ExpertParams* p = ParamsOf<ExpertParams>(*spec);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->p_v, 0.5);
  EXPECT_EQ(p->anytime, 300);
  EXPECT_EQ(p->p_u, ExpertParams{}.p_u);  // the default
  EXPECT_EQ(ParamsOf<DecSbParams>(*spec), nullptr);
  // Every parameter, defaults included, for effective.yaml.
  const ConfigNode params = spec->Params();
  std::vector<std::string> keys;
  for (const auto& e : params.entries) keys.push_back(e.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"p_v", "p_u", "p_tour", "anytime",
                                            "max_iterations", "max_nodes",
                                            "tour_budget"}));
  EXPECT_EQ(params.Find("p_v")->scalar, "0.5");
  EXPECT_FALSE(spec->Create()->name().empty());
}

TEST(RegistryTest, WrongTypesAndMisspeltParametersAreInputErrors) {
  const auto error = [](const std::string& policy) {
    try {
      BuiltinPolicies().Resolve(ScenarioFromYaml(
          "robots: {count: 1}\ntargets: {count: 1}\npolicy: " + policy + "\n"));
    } catch (const InputError& e) {
      return e.Format();
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("{name: decsb, horizon: 2.5}"),
            "test.yaml:3: policy.horizon: must be an integer in [1, 1000], "
            "got 2.5");
  EXPECT_EQ(error("{name: decsb, iterations: \"300\"}"),
            "test.yaml:3: policy.iterations: must be an integer in [1, "
            "10000000], got \"300\"");
  EXPECT_EQ(error("{name: expert, p_uu: 0.5}"),
            "test.yaml:3: policy.p_uu: unknown parameter for policy 'expert' "
            "(did you mean `p_u`?) (valid: p_v, p_u, p_tour, anytime, "
            "max_iterations, max_nodes, tour_budget)");
  EXPECT_EQ(error("{name: grdy}"),
            "test.yaml:3: policy.name: unknown policy 'grdy' (did you mean "
            "`greedy`?) (valid: random, greedy, expert, decsb)");
}

TEST(RegistryTest, DescribeListsEveryPolicyWithItsParameters) {
  const std::vector<PolicyInfo> info = BuiltinPolicies().Describe();
  ASSERT_EQ(info.size(), 4u);
  EXPECT_EQ(info[2].name, "expert");
  EXPECT_TRUE(info[2].centralized);
  EXPECT_FALSE(info[3].centralized);
  ASSERT_EQ(info[3].params.size(), 4u);
  EXPECT_EQ(info[3].params[2].key, "policy.horizon");
  EXPECT_EQ(info[3].params[2].type, "integer in [1, 1000]");
  EXPECT_EQ(info[3].params[2].default_value, "15");
  EXPECT_TRUE(info[0].params.empty());
}

// A policy's name and whether it is centralized are stated once, in its
// class: the registry, its specs and the policies it makes agree.
TEST(RegistryTest, NamesAndCentralizedFlagsComeFromThePolicyClass) {
  const PolicyRegistry registry = BuiltinPolicies();
  for (const PolicyInfo& info : registry.Describe()) {
    Scenario s = ScenarioFromYaml("robots: {count: 1}\ntargets: {count: 1}\n");
    s.policy.name = info.name;
    const auto spec = registry.Resolve(s);
    const auto policy = spec->Create();
    EXPECT_EQ(spec->name(), info.name);
    EXPECT_EQ(policy->name(), info.name);
    EXPECT_EQ(spec->centralized(), info.centralized) << info.name;
    EXPECT_EQ(policy->centralized(), info.centralized) << info.name;
  }
  EXPECT_TRUE(ExpertPolicy(ExpertParams{}).centralized());
  EXPECT_FALSE(GreedyPolicy().centralized());
}

// A stand-in for a learned policy: its model is a shared resource, loaded
// once when the policy is resolved and shared by every policy made from it.
struct ToyModel {
  int weights = 0;
};
struct ToyParams {
  int scale = 2;
  template <typename A>
  void Serialize(A* a) {
    a->Visit(AIA_FIELD(scale).In(AtLeast(1)).Doc("a parameter"));
  }
};
class ToyPolicy : public NamedPolicy<ToyPolicy> {
 public:
  static constexpr std::string_view kName = "toy";
  explicit ToyPolicy(std::shared_ptr<const ToyModel> model)
      : model_(std::move(model)) {}
  void Reset(const Map&, int, int, std::uint64_t) override {}
  PolicyStatus Decide(const DecisionContext&, std::vector<Move>*) override {
    return PolicyStatus::kOk;
  }
  std::shared_ptr<const ToyModel> model_;
};

TEST(RegistryTest, SharedResourceIsLoadedOncePerResolve) {
  PolicyRegistry r;
  int loads = 0;
  r.Add<ToyPolicy, ToyParams, ToyModel>(
      "a policy with a model", "toy.pt",
      [&loads](const ToyParams& p, const Scenario& scenario) {
        ++loads;
        EXPECT_EQ(scenario.policy.name, "toy");
        return std::make_shared<const ToyModel>(ToyModel{p.scale * 10});
      },
      [](const ToyParams&, std::shared_ptr<const ToyModel> model) {
        return std::make_unique<ToyPolicy>(std::move(model));
      });
  const auto spec = r.Resolve(ScenarioFromYaml(
      "robots: {count: 1}\ntargets: {count: 1}\npolicy: {name: toy, scale: "
      "3}\n"));
  EXPECT_EQ(loads, 1);
  std::vector<std::unique_ptr<Policy>> episodes;
  for (int i = 0; i < 3; ++i) episodes.push_back(spec->Create());
  EXPECT_EQ(loads, 1);
  const auto* a = static_cast<const ToyPolicy*>(episodes[0].get());
  const auto* b = static_cast<const ToyPolicy*>(episodes[2].get());
  EXPECT_EQ(a->model_.get(), b->model_.get());
  EXPECT_EQ(a->model_->weights, 30);
  // Its model file is listed first among its parameters.
  const std::vector<FieldDoc> params = r.Describe()[0].params;
  ASSERT_EQ(params.size(), 3u);
  EXPECT_EQ(params[0].key, "policy.model");
  EXPECT_EQ(params[0].default_value, "toy.pt");
  EXPECT_EQ(params[1].key, "policy.model_sha256");
  EXPECT_EQ(params[2].key, "policy.scale");
}

TEST(TeamBestTest, ActiveRowWithTheSmallestDetLowestIndexFirst) {
  // Two targets, three robots; robot 1 has failed.
  const std::vector<double> det = {0.5, 0.2,   // robot 0
                                   0.1, 0.1,   // robot 1 (inactive)
                                   0.5, 0.3};  // robot 2
  std::vector<int> best;
  TeamBestRows(det, 2, {1, 0, 1}, &best);
  EXPECT_EQ(best, (std::vector<int>{0, 0}));  // a tie on target 0 goes to 0
  TeamBestRows(det, 2, {0, 0, 0}, &best);
  EXPECT_EQ(best, (std::vector<int>{-1, -1}));
}

}  // namespace
}  // namespace aia
