// mission.decisions: async (SPEC 14): each robot decides when its own move
// ends, sensing ticks on the physics clock, and reserved lattice points keep
// robots apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "aia/learning/igbnet_policy.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/observers.h"
#include "aia/runtime/policies.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

// A crowd: many robots on few lattice points, so that they meet.
std::string Crowd(const std::string& model, const std::string& avoidance) {
  return "seed: 4\nworkspace: {size: [5, 5], obstacles: {random: {count: "
         "2}}}\nrobots: {count: 24, model: " +
         model +
         "}\ntargets: {count: 6}\nmission: {max_steps: 12, "
         "stop_at_success: false, decisions: async, avoidance: " +
         avoidance + "}\npolicy: {name: random}\n";
}

// What the rounds looked like: who decided, and the clock at each tick.
class RoundObserver : public StepObserver {
 public:
  ObserverStatus OnDecision(const Episode& e, const DecisionContext& ctx,
                            const Decision& d) override {
    EXPECT_NE(d.ready, nullptr);
    EXPECT_EQ(ctx.ready, d.ready);
    int ready = 0;
    for (std::uint8_t r : *d.ready) ready += r;
    if (ready < e.world().NumRobots()) ++partial_rounds;
    // One round per decision, whether the step moved on or not.
    EXPECT_EQ(ctx.round, rounds);
    ++rounds;
    return ObserverStatus::kContinue;
  }
  ObserverStatus OnStep(const Episode& e) override {
    ++ticks;
    EXPECT_EQ(e.filter_step(), ticks);
    tick_seconds.push_back(e.clock_seconds());
    return ObserverStatus::kContinue;
  }
  int rounds = 0, partial_rounds = 0, ticks = 0;
  std::vector<double> tick_seconds;
};

TEST(AsyncTest, WheeledRobotsDecideAloneAndNeverWait) {
  Scenario s = ScenarioFromYaml(
      "seed: 3\nworkspace: {size: [10, 10], obstacles: {random: {count: "
      "6}}}\nrobots: {count: 4, model: diff_drive}\ntargets: {count: 4}\n"
      "mission: {max_steps: 20, stop_at_success: false, decisions: async}\n"
      "sensor: {rate: 2}\npolicy: {name: greedy}\n");
  auto e = MakeEpisode(s, AllPolicies());
  RoundObserver rounds;
  e->AddObserver(&rounds);
  e->Run();
  // Robots turn and drive for different times: most rounds are some robots'.
  EXPECT_GT(rounds.partial_rounds, rounds.rounds / 2);
  // Steps are the slowest robot's decisions; the others made more.
  const std::vector<long>& made = e->decisions();
  EXPECT_EQ(*std::min_element(made.begin(), made.end()), e->step());
  EXPECT_EQ(e->step(), 20);
  EXPECT_GT(*std::max_element(made.begin(), made.end()), e->step())
      << made[0] << " " << made[1] << " " << made[2] << " " << made[3];
  // Nobody waits for anybody: no time is spent arrived (no robot failed).
  EXPECT_EQ(e->sim().time_use().arrived, 0.0);
  EXPECT_GT(e->sim().time_use().driving, 0.0);
  // Ticks at 2 Hz on the physics clock: 0.5 s, 1.0 s, ..., and a last one
  // when the mission ends (its 20th step) between two, so that the moves
  // that complete it are sensed.
  ASSERT_GT(rounds.ticks, 4);
  const int on_grid = static_cast<int>(e->clock_seconds() / 0.5 + 1e-9);
  for (int t = 0; t < on_grid; ++t)
    EXPECT_NEAR(rounds.tick_seconds[t], 0.5 * (t + 1), 1e-9);
  const bool between = std::abs(e->clock_seconds() - 0.5 * on_grid) > 1e-9;
  EXPECT_EQ(rounds.ticks, on_grid + (between ? 1 : 0));
  EXPECT_NEAR(rounds.tick_seconds.back(), e->clock_seconds(), 1e-9);
}

// A failure's step is a decision step: the robot stops when the slowest
// robot's decisions reach it, not at the next sensing tick (at 0.5 Hz it
// went on for 5 more moves). And a mission that ends on max_steps between
// two ticks senses its last moves: max_steps = F succeeds (it never did).
TEST(AsyncTest, FailuresAndTheLastStepTakeEffectBetweenTicks) {
  const std::string base =
      "seed: 3\nworkspace: {size: [10, 10], obstacles: {random: {count: "
      "4}}}\nrobots: {count: 3}\ntargets: {count: 3}\nsensor: {rate: 0.5}\n";
  Scenario failing = ScenarioFromYaml(
      base +
      "mission: {max_steps: 30, stop_at_success: false, decisions: async}\n"
      "communication: {failures: [{robot: 1, step: 5}]}\n"
      "policy: {name: random}\n");
  auto e = MakeEpisode(failing, AllPolicies());
  e->Run();
  EXPECT_EQ(e->decisions()[1], 5);
  EXPECT_EQ(e->step(), 30);

  Scenario greedy = ScenarioFromYaml(
      base +
      "mission: {eps: 0.01, decisions: async}\npolicy: {name: greedy}\n");
  auto first = MakeEpisode(greedy, AllPolicies());
  first->Run();
  ASSERT_TRUE(first->success());
  const int f = first->flowtime();
  greedy.mission.max_steps = f;
  auto again = MakeEpisode(greedy, AllPolicies());
  again->Run();
  EXPECT_TRUE(again->success()) << "flowtime " << f;
  EXPECT_EQ(again->flowtime(), f);
}

TEST(AsyncTest, TheSameRunTwice) {
  auto run = [] {
    Scenario s = ScenarioFromYaml(Crowd("diff_drive", "reserve"));
    s.policy.name = "greedy";
    s.robots.count = 8;
    auto e = MakeEpisode(s, AllPolicies());
    e->Run();
    std::vector<double> out = {static_cast<double>(e->step()),
                               e->clock_seconds()};
    for (const Vec2& p : e->robot_positions()) {
      out.push_back(p.x());
      out.push_back(p.y());
    }
    for (int k = 0; k < e->world().NumTargets(); ++k)
      out.push_back(e->MinDet(k));
    for (long d : e->decisions()) out.push_back(static_cast<double>(d));
    return out;
  };
  EXPECT_EQ(run(), run());
}

// The smallest distance between two robots' centres over every substep.
class Closest : public StepObserver {
 public:
  void OnSubstep(const Episode& e, double) override {
    const Simulation& sim = e.sim();
    for (int i = 0; i < sim.num_robots(); ++i)
      for (int j = i + 1; j < sim.num_robots(); ++j)
        closest = std::min(
            closest, (sim.RobotPosition(i) - sim.RobotPosition(j)).norm());
  }
  double closest = 1e9;
};

TEST(AsyncTest, ReservedPointsKeepRobotsApart) {
  for (const std::string model : {"point", "diff_drive"}) {
    Scenario s = ScenarioFromYaml(Crowd(model, "reserve"));
    auto e = MakeEpisode(s, AllPolicies());
    Closest closest;
    e->AddObserver(&closest);
    e->Run();
    // Two discs of radius 0.15 touch at 0.3 m: no robot through another,
    // hardly a touch.
    EXPECT_GT(closest.closest, 2 * s.robots.radius - 0.02) << model;
    long stalls = 0;
    for (long n : e->sim().robot_stalls()) stalls += n;
    EXPECT_EQ(stalls, 0) << model;
    EXPECT_GT(e->sim().time_use().yielding, 0.0) << model;

    // Without reservations the same crowd pushes and stalls.
    Scenario none = ScenarioFromYaml(Crowd(model, "none"));
    auto f = MakeEpisode(none, AllPolicies());
    Closest pushed;
    f->AddObserver(&pushed);
    f->Run();
    long pushes = 0;
    for (long n : f->sim().robot_stalls()) pushes += n;
    EXPECT_LT(pushed.closest, closest.closest) << model;
    EXPECT_GT(pushes, 0) << model << " " << pushed.closest;
    EXPECT_EQ(f->sim().time_use().yielding, 0.0) << model;
  }
}

TEST(AsyncTest, AFailedRobotStopsMidMoveAndNeverDecidesAgain) {
  Scenario s = ScenarioFromYaml(
      "seed: 2\nrobots: {count: 3, model: diff_drive}\ntargets: {count: "
      "4}\nmission: {max_steps: 12, stop_at_success: false, decisions: "
      "async}\ncommunication: {failures: [{robot: 1, step: 3}]}\n"
      "policy: {name: random}\n");
  auto e = MakeEpisode(s, AllPolicies());
  long decided = -1;
  Vec2 at_failure;
  while (!e->done()) {
    e->Step();
    if (!e->comm().Active(1)) {
      const Vec2 p = e->sim().RobotPosition(1);
      if (decided < 0) {
        decided = e->decisions()[1];
        at_failure = p;
      }
      // Stopped where it was when it failed (a wheeled robot brakes within
      // about 10 cm from its top speed, 0.7 m/s at about 3 m/s^2, a move
      // being 50 cm), and never asked again.
      EXPECT_LT((p - at_failure).norm(), 0.15);
      EXPECT_EQ(e->decisions()[1], decided);
      EXPECT_TRUE(e->measurements()[1].empty());
    }
  }
  ASSERT_GE(decided, 0);
  EXPECT_EQ(e->step(), 12);  // the others' decisions, the failed one aside
  EXPECT_GT(std::min(e->decisions()[0], e->decisions()[2]), decided);
}

// Where the robots' time went covers every robot's every substep, in both
// modes (async left out the substep a move arrived in: 65 moves x 5 ms).
TEST(AsyncTest, TimeUseCoversEveryRobotsEverySubstep) {
  for (const std::string decisions : {"async", "lockstep"}) {
    Scenario s = ScenarioFromYaml(
        "seed: 5\nrobots: {count: 3}\ntargets: {count: 3}\n"
        "mission: {max_steps: 15, stop_at_success: false, decisions: " +
        decisions +
        "}\ncommunication: {failures: [{robot: 2, step: 6}]}\n"
        "policy: {name: random}\n");
    auto e = MakeEpisode(s, AllPolicies());
    e->Run();
    const Simulation::TimeUse& u = e->sim().time_use();
    const double total =
        u.driving + u.turning + u.blocked + u.arrived + u.staying + u.yielding;
    EXPECT_NEAR(total, 3 * e->clock_seconds(), 1e-9) << decisions;
  }
}

TEST(AsyncTest, MovesAreCountedWhenTheyEnd) {
  Scenario s = ScenarioFromYaml(Crowd("point", "reserve"));
  auto e = MakeEpisode(s, AllPolicies());
  MoveObserver moves;
  e->AddObserver(&moves);
  e->Run();
  long decisions = 0;
  for (long d : e->decisions()) decisions += d;
  EXPECT_EQ(moves.moves(), e->history().moves());
  EXPECT_GT(moves.moves(), 0);
  // Stays and waits that ended at a tick are decisions without a move, and
  // without a drive: a robot that waits for a held point drives nowhere
  // (the no-arrival warning counts drives, not decisions).
  long drives = 0;
  for (long d : e->drives()) drives += d;
  EXPECT_LE(moves.moves(), drives);
  EXPECT_LT(drives, decisions);
  EXPECT_GT(e->sim().time_use().yielding, 0.0);
}

// DecisionContext::knowledge: new at every sensing tick and every failure,
// the same in the rounds between (robots deciding on arrival).
class KnowledgeObserver : public StepObserver {
 public:
  ObserverStatus OnDecision(const Episode& e, const DecisionContext& ctx,
                            const Decision&) override {
    EXPECT_NE(ctx.knowledge, 0u);
    const int active = e.comm().NumActive();
    if (rounds > 0) {
      const bool changed = e.filter_step() != ticks || active != last_active;
      EXPECT_EQ(ctx.knowledge != last, changed) << "round " << rounds;
      kept += !changed;
      failed_between += active != last_active && e.filter_step() == ticks;
    }
    last = ctx.knowledge;
    ticks = e.filter_step();
    last_active = active;
    ++rounds;
    return ObserverStatus::kContinue;
  }
  std::uint64_t last = 0;
  int rounds = 0, ticks = 0, last_active = 0, kept = 0, failed_between = 0;
};

// Few ticks (0.5 Hz), robots that fail between them, a range graph that
// loses packets.
const char* kKnowledgeMission =
    "seed: 6\nworkspace: {size: [12, 12], obstacles: {random: {count: 8}}}\n"
    "robots: {count: 12}\ntargets: {count: 8}\nsensor: {rate: 0.5}\n"
    "mission: {max_steps: 14, stop_at_success: false, decisions: async}\n"
    "communication: {mode: range, range: 4, packet_loss_lambda: 2, "
    "failures: [{robot: 2, step: 3}, {robot: 5, step: 6}, {robot: 9, step: "
    "6}]}\npolicy: {name: igbnet}\n";

TEST(AsyncTest, TheKnowledgeStampIsNewAtEveryTickAndFailureOnly) {
  auto e = MakeEpisode(ScenarioFromYaml(kKnowledgeMission), AllPolicies());
  KnowledgeObserver seen;
  e->AddObserver(&seen);
  e->Run();
  EXPECT_GT(seen.kept, seen.rounds / 3);  // rounds between two ticks
  EXPECT_GT(seen.failed_between, 0);
}

// Two copies of a policy decide every round, one told the knowledge stamp
// and one not (0: it works everything out again); their moves and logits
// must agree. The first's are applied.
class KeptAgainstFresh : public Policy {
 public:
  KeptAgainstFresh(std::unique_ptr<Policy> kept, std::unique_ptr<Policy> fresh)
      : kept_(std::move(kept)), fresh_(std::move(fresh)) {}
  std::string_view name() const override { return "kept-against-fresh"; }
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override {
    kept_->Reset(map, num_robots, num_targets, seed);
    fresh_->Reset(map, num_robots, num_targets, seed);
  }
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override {
    DecisionContext unknown = ctx;
    unknown.knowledge = 0;
    std::vector<Move> other(moves->size(), Move::kStay);
    const PolicyStatus status = kept_->Decide(ctx, moves);
    EXPECT_EQ(fresh_->Decide(unknown, &other), status);
    for (std::size_t i = 0; i < moves->size(); ++i)
      if (Deciding(ctx, static_cast<int>(i)))
        EXPECT_EQ((*moves)[i], other[i])
            << "round " << ctx.round << " robot " << i;
    const auto logits = [](const Policy& p) {
      return dynamic_cast<const IgbNetPolicy&>(p).logits();
    };
    EXPECT_EQ(logits(*kept_), logits(*fresh_)) << "round " << ctx.round;
    compared += ctx.knowledge != 0;
    return status;
  }
  int compared = 0;

 private:
  std::unique_ptr<Policy> kept_, fresh_;
};

// The default policy keeps the beliefs' digest, what each neighbourhood
// holds and the team's heatmaps between ticks (about 40 % of its time at
// 1000 robots in async): the same moves as working them out every round.
TEST(AsyncTest, WhatThePolicyKeepsBetweenTicksDecidesAsWorkingItOutAgain) {
  const Scenario s = ScenarioFromYaml(kKnowledgeMission);
  const PolicyRegistry registry = AllPolicies();
  auto spec = registry.Resolve(s);
  auto pair =
      std::make_unique<KeptAgainstFresh>(spec->Create(), spec->Create());
  KeptAgainstFresh* compare = pair.get();
  Episode e(BuildInstance(s), std::move(pair));
  e.Run();
  EXPECT_GT(compare->compared, 20);
}

}  // namespace
}  // namespace aia
