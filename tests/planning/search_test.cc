#include "aia/planning/search.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "aia/core/rng.h"
#include "aia/world/lattice.h"
#include "support/team_fixture.h"

namespace aia {
namespace {

using Team = testing::TeamFixture;

// One robot 1.85 m west of a target's prior mean (sigma 1 m, sensor 2 m, an
// empty 10 x 10 m world).
const char* kOneRobot =
    "workspace: {size: [10.0, 10.0]}\n"
    "robots: {count: 1, start: [[4.25, 5.25]]}\n"
    "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25], "
    "prior_sigma: 1.0}]}\n";

void SetCovariance(Team* team, double sigma) {
  std::vector<Eigen::VectorXd> means;
  std::vector<Eigen::MatrixXd> covs;
  for (const TargetPrior& p : team->world.priors) {
    means.push_back(p.mean);
    covs.push_back(sigma * sigma * Eigen::MatrixXd::Identity(2, 2));
  }
  team->beliefs.SetPrior(means, covs);
}

// Three threads over [0, n), split unevenly.
RangeRunner ThreeThreads() {
  return [](int n, const RangeTask& f) {
    std::vector<std::thread> pool;
    const int cut[4] = {0, n / 5, n / 2, n};
    for (int w = 0; w < 3; ++w) pool.emplace_back(f, cut[w], cut[w + 1], w);
    for (std::thread& th : pool) th.join();
  };
}

// Nine robots and `targets` targets at random in a 10 m world for trial t
// (seed seed_base + t): a full graph on even trials, a 3 m range graph on
// odd ones, packet loss lambda 0, 4 or 8 by t; the graph of step 1.
std::unique_ptr<Team> GraphTrial(int trial, int targets, int seed_base) {
  CommParams cp;
  cp.mode = trial % 2 ? CommMode::kRange : CommMode::kFull;
  cp.range = 3.0;
  cp.packet_loss_lambda = trial % 3 == 0 ? 0.0 : 4.0 * (trial % 3);
  auto team = std::make_unique<Team>(
      "workspace: {size: [10.0, 10.0]}\nrobots: {count: 9}\ntargets: "
      "{count: " +
          std::to_string(targets) +
          "}\nseed: " + std::to_string(seed_base + trial) + "\n",
      cp);
  std::vector<Vec2> p;
  for (int idx : team->positions)
    p.push_back(team->world.map.lattice().Point(idx));
  team->comm.Update(1, p);
  return team;
}

// The nearest observer of x read in order of distance is the one a scan of
// the whole window finds: the same distance, on random points of worlds
// with boxes and walls, sensors with and without line of sight, robots in
// other components; with a bound, the distance where it is below the bound.
TEST(SearchMemoryTest, NearestObserverDistanceIsTheWindowsNearest) {
  int found = 0, bounded = 0;
  for (int trial = 0; trial < 8; ++trial) {
    Team team("workspace: {size: [14.0, 11.0], obstacles: {random: {count: " +
              std::to_string(6 + 3 * trial) +
              "}}}\nseed: " + std::to_string(50 + trial) +
              "\nsensor: {range: " + std::to_string(1.0 + 0.5 * (trial % 4)) +
              ", line_of_sight: " + (trial % 3 ? "true" : "false") +
              "}\nrobots: {count: 2}\ntargets: {count: 2}\n");
    const Map& map = team.world.map;
    const Lattice& lattice = map.lattice();
    const int span =
        static_cast<int>(std::ceil(team.sensor.range / lattice.step())) + 1;
    Rng rng(7, "nearest_observer", trial);
    for (int probe = 0; probe < 300; ++probe) {
      const int here = static_cast<int>(rng.UniformInt(lattice.size()));
      const Vec2 x(rng.Uniform(0.0, 14.0), rng.Uniform(0.0, 11.0));
      // The reference: every point of the window.
      const int c = lattice.NearestPoint(x);
      int want = -1;
      for (int iy = std::max(0, lattice.Iy(c) - span);
           iy <= std::min(lattice.ny() - 1, lattice.Iy(c) + span); ++iy)
        for (int ix = std::max(0, lattice.Ix(c) - span);
             ix <= std::min(lattice.nx() - 1, lattice.Ix(c) + span); ++ix) {
          const int q = lattice.Index(ix, iy);
          if (!lattice.Free(q) ||
              lattice.components()[q] != lattice.components()[here] ||
              PredictedPrecision(map, team.sensor, lattice.Point(q), x) <= 0.0)
            continue;
          const int d =
              std::abs(ix - lattice.Ix(here)) + std::abs(iy - lattice.Iy(here));
          if (want < 0 || d < want) want = d;
        }
      EXPECT_EQ(NearestObserverDistance(map, team.sensor, here, x, span), want)
          << "trial " << trial << " probe " << probe;
      found += want >= 0;
      const int bound = static_cast<int>(rng.UniformInt(40));
      const int got =
          NearestObserverDistance(map, team.sensor, here, x, span, bound);
      if (want >= 0 && want < bound) {
        EXPECT_EQ(got, want);
      } else {
        EXPECT_TRUE(got == -1 || got == bound) << got;
        bounded += got == bound;
      }
    }
  }
  EXPECT_GT(found, 500);  // most points are seen from somewhere
  EXPECT_GT(bounded, 50);
}

TEST(SearchMemoryTest, AMissMovesTheAimToTheNearestRingNotRuledOut) {
  Team team(kOneRobot);
  ASSERT_TRUE(team.world.map.lattice().Free(team.positions[0]));
  SearchMemory memory;
  memory.Reset(1, 1);
  const DecisionContext ctx = team.Context();
  memory.Update(ctx, 0);  // the first call only records the belief
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  EXPECT_NEAR((memory.Aim(0, 0) - Vec2(6.1, 5.25)).norm(), 0.0, 1e-12);
  // The robot sees the mean (1.85 m) and the belief did not shrink: its
  // point is missed. Every point of the prior within 2 m of (4.25, 5.25) is
  // ruled out, the mean among them; on the first ring (0.25 sigma) the
  // points at angles 0 and +-45 degrees lie beyond it (2.1 and 2.04 m),
  // each seen from (4.75, 5.25), one lattice step from the robot; the
  // tie goes to angle 0: (6.35, 5.25).
  memory.Update(ctx, 0);
  ASSERT_EQ(memory.Missed(0, 0).size(), 1u);
  EXPECT_EQ(memory.Missed(0, 0)[0], team.positions[0]);
  EXPECT_NEAR(memory.Aim(0, 0).x(), 6.35, 1e-12);
  EXPECT_NEAR(memory.Aim(0, 0).y(), 5.25, 1e-12);
  // The same point again adds nothing; the aim stays.
  memory.Update(ctx, 0);
  EXPECT_EQ(memory.Missed(0, 0).size(), 1u);
  EXPECT_NEAR(memory.Aim(0, 0).x(), 6.35, 1e-12);
  // A belief that shrank (someone measured): the search is over.
  SetCovariance(&team, 0.5);
  memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  EXPECT_NEAR((memory.Aim(0, 0) - Vec2(6.1, 5.25)).norm(), 0.0, 1e-12);
}

// With the robots' own measurements in the context, a belief that shrank
// because a neighbour's measurement spread through the consensus is no
// measurement of the robot's own: the miss stays, and the point is missed
// again. Its own measurement of the target ends the search.
TEST(SearchMemoryTest, OnlyTheRobotsOwnMeasurementEndsTheSearch) {
  Team team(kOneRobot);
  SearchMemory memory;
  memory.Reset(1, 1);
  std::vector<std::vector<Measurement>> z(1);
  DecisionContext ctx = team.Context();
  ctx.measurements = &z;
  memory.Update(ctx, 0);
  memory.Update(ctx, 0);
  ASSERT_EQ(memory.Missed(0, 0).size(), 1u);
  SetCovariance(&team, 0.9);  // shrank, nothing measured
  memory.Update(ctx, 0);
  EXPECT_EQ(memory.Missed(0, 0).size(), 1u);
  EXPECT_NEAR(memory.Aim(0, 0).x(), 6.35, 1e-12);
  Measurement seen;
  seen.target = 0;
  z[0].push_back(seen);
  memory.Update(ctx, 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  // Without measurements in the context (a hand-made one) a shrink is
  // taken for one.
  z[0].clear();
  memory.Update(ctx, 0);
  memory.Update(ctx, 0);
  ASSERT_EQ(memory.Missed(0, 0).size(), 1u);
  ctx.measurements = nullptr;
  SetCovariance(&team, 0.8);
  memory.Update(ctx, 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
}

TEST(SearchMemoryTest, APointThatDoesNotSeeTheAimMissesNothing) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n");
  SearchMemory memory;
  memory.Reset(1, 1);
  for (int step = 0; step < 3; ++step) memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  EXPECT_NEAR((memory.Aim(0, 0) - Vec2(6.1, 5.25)).norm(), 0.0, 1e-12);
}

// A prior mean that no point of the robot's component would measure (inside
// a box): the aim is not the mean, which nothing could ever see or rule out
// (the default policy's robots froze beside it for a whole mission), but the
// nearest point of the prior that a point would measure, as a miss of the
// mean would have made it.
TEST(SearchMemoryTest, AMeanNoPointSeesIsNotTheAim) {
  Team team(
      "workspace: {size: [10.0, 10.0], obstacles: {boxes: [{center: [6.0, "
      "5.25], size: [2.0, 2.0]}]}}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.5, 8.0], prior_mean: [6.0, 5.25], "
      "prior_sigma: 1.0}]}\n");
  const Map& map = team.world.map;
  const SensorModel& sensor = team.sensor;
  const int span = SensorSpan(map.lattice(), sensor);
  const Vec2 mean(6.0, 5.25);
  ASSERT_LT(NearestObserverDistance(map, sensor, team.positions[0], mean, span),
            0);
  SearchMemory memory;
  memory.Reset(1, 1);
  for (int step = 0; step < 3; ++step) memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
  const Vec2 aim = memory.Aim(0, 0);
  EXPECT_GT((aim - mean).norm(), 0.2);
  EXPECT_LE((aim - mean).norm(), 4.0 + 1e-9);
  EXPECT_TRUE(map.PointFree(aim));
  EXPECT_GE(NearestObserverDistance(map, sensor, team.positions[0], aim, span),
            0);
}

TEST(SearchMemoryTest, MovingTargetsAreNotSearched) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 1, start: [[4.25, 5.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25], "
      "dynamics: {A: [[1.0, 0.0], [0.0, 1.0]], b: [0.0, 0.0], q: 0.01}}]}\n");
  SearchMemory memory;
  memory.Reset(1, 1);
  for (int step = 0; step < 3; ++step) memory.Update(team.Context(), 0);
  EXPECT_TRUE(memory.Missed(0, 0).empty());
}

TEST(SearchMemoryTest,
     RelabellingRobotsPermutesTheMemoryAndTheStepDoesNotEnter) {
  // Robot A sees the mean, robot B (far away) does not. The same team with
  // the labels swapped remembers the same, swapped; the step number given
  // in the context changes nothing.
  const std::string tail =
      "]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n";
  Team ab(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 2, start: [[4.25, 5.25], [1.25, 1.25]" +
      tail);
  Team ba(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 2, start: [[1.25, 1.25], [4.25, 5.25]" +
      tail);
  SearchMemory mab, mba;
  mab.Reset(2, 1);
  mba.Reset(2, 1);
  for (int step = 0; step < 3; ++step) {
    DecisionContext cab = ab.Context(), cba = ba.Context();
    cab.step = step;
    cba.step = 100 + 7 * step;
    for (int i = 0; i < 2; ++i) {
      mab.Update(cab, i);
      mba.Update(cba, 1 - i);
    }
  }
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(mab.Missed(i, 0), mba.Missed(1 - i, 0)) << "robot " << i;
    EXPECT_EQ(mab.Aim(i, 0), mba.Aim(1 - i, 0)) << "robot " << i;
  }
  EXPECT_EQ(mab.Missed(0, 0).size(), 1u);
  EXPECT_TRUE(mab.Missed(1, 0).empty());
}

// TargetClaims: lattice points of 0.5 m (centres at 0.25 + 0.5 k), sensor
// range 2 m (a point 2 m away measures) with line of sight.
const char* kEmptyWorld =
    "workspace: {size: [10.0, 10.0]}\n"
    "robots: {count: 1, start: [[1.25, 1.25]]}\n"
    "targets: {list: [{position: [8.0, 8.0]}]}\n";

int PointAt(const Team& team, double x, double y) {
  return team.world.map.lattice().NearestPoint(Vec2(x, y));
}

// The set the network is shown (SearchPoints): after the same miss as
// above, every point of the first ring (0.25 sigma, 8 points) that the
// missed point (4.25, 5.25) does not measure: angles 0, 45 and 315 degrees
// (2.1, 2.04 and 2.04 m away; the others within 2 m), in angle order; none
// chosen for the robot. A second miss, one step east, rules out every point
// within 2 m of either point; a belief that shrank clears it all.
TEST(SearchPointsTest, AMissLeavesTheFirstRingNotRuledOut) {
  Team team(kOneRobot);
  SearchPoints points;
  points.Reset(1, 1);
  points.Update(team.Context(), 0);
  EXPECT_TRUE(points.Points(0, 0).empty());  // the mean
  points.Update(team.Context(), 0);
  ASSERT_EQ(points.Missed(0, 0).size(), 1u);
  const double r = 0.25 / std::sqrt(2.0);
  const std::vector<Vec2> ring = {
      {6.35, 5.25}, {6.1 + r, 5.25 + r}, {6.1 + r, 5.25 - r}};
  ASSERT_EQ(points.Points(0, 0).size(), 3u);
  for (int a = 0; a < 3; ++a)
    EXPECT_NEAR((points.Points(0, 0)[a] - ring[a]).norm(), 0.0, 1e-12) << a;
  EXPECT_EQ(points.misses(), 1);
  // One step east sees (6.35, 5.25) from 1.6 m and measures nothing.
  team.positions[0] =
      team.world.map.lattice().Next(team.positions[0], Move::kRight);
  points.Update(team.Context(), 0);
  ASSERT_EQ(points.Missed(0, 0).size(), 2u);
  ASSERT_FALSE(points.Points(0, 0).empty());
  for (const Vec2& x : points.Points(0, 0)) {
    EXPECT_GT((x - Vec2(4.25, 5.25)).norm(), 2.0);
    EXPECT_GT((x - Vec2(4.75, 5.25)).norm(), 2.0);
  }
  SetCovariance(&team, 0.5);
  points.Update(team.Context(), 0);
  EXPECT_TRUE(points.Missed(0, 0).empty());
  EXPECT_TRUE(points.Points(0, 0).empty());
}

// A neighbour's miss is a fact about the target: robot B, far away, takes
// A's missed point in and has A's search points.
TEST(SearchPointsTest, NeighboursShareTheirMisses) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 2, start: [[4.25, 5.25], [1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n");
  SearchPoints points;
  points.Reset(2, 1);
  for (int step = 0; step < 2; ++step) {
    for (int i = 0; i < 2; ++i) points.Update(team.Context(), i);
    points.Share(team.Context(), {0, 1});
  }
  ASSERT_EQ(points.Missed(0, 0).size(), 1u);
  EXPECT_EQ(points.Missed(1, 0), points.Missed(0, 0));
  EXPECT_EQ(points.Points(1, 0), points.Points(0, 0));
  EXPECT_EQ(points.Points(0, 0).size(), 3u);
}

// Robots that decide on arrival share in turns: a robot that sat out the
// last call shares the miss it records now with the robots deciding with it
// (the lists read again are those their own calls changed since).
TEST(SearchPointsTest, AMissRecordedAfterSittingOutACallIsShared) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 3, start: [[4.25, 5.25], [1.25, 1.25], [1.25, "
      "8.75]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n");
  SearchPoints points;
  points.Reset(3, 1);
  const DecisionContext ctx = team.Context();
  for (int i = 0; i < 3; ++i) points.Update(ctx, i);  // the beliefs
  points.Share(ctx, {0, 1, 2});
  points.Update(ctx, 1);
  points.Share(ctx, {1});
  points.Update(ctx, 0);  // robot 0's miss
  points.Update(ctx, 2);
  points.Share(ctx, {0, 2});
  ASSERT_EQ(points.Missed(0, 0).size(), 1u);
  EXPECT_EQ(points.Missed(2, 0), points.Missed(0, 0));
  EXPECT_TRUE(points.Missed(1, 0).empty());  // it did not decide
  points.Share(ctx, {1});
  EXPECT_EQ(points.Missed(1, 0), points.Missed(0, 0));
}

// NeighbourMisses against the rule read directly: robot i's list for target
// k becomes its own list, then every point a neighbour's list (as it was
// before the call) holds and its own does not, ascending; only where its
// belief is open and the target static; then(i, k) once per (robot,
// target) that took a point, in ascending order. Random lists on full and
// range graphs with lost edges (so neighbourhoods repeat and differ).
struct MissSlot {
  double log_det = 0.0;
  MissList missed;
};

// A team without targets (a hand-made context, or a library's own
// mission) shares nothing and stops nothing: its slots are empty, its
// robots still counted.
TEST(NeighbourMissesTest, NoTargetsNoWork) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 3, start: [[4.25, 5.25], [1.25, 1.25], [1.25, "
      "8.75]]}\n"
      "targets: {list: [{position: [8.0, 8.0], prior_mean: [6.1, 5.25]}]}\n");
  NeighbourMisses sharing;
  std::vector<MissSlot> slots;
  std::vector<std::uint8_t> touched(3, 1);
  int calls = 0;
  for (int call = 0; call < 2; ++call)
    sharing.Share(
        team.Context(), {0, 2}, 0, &slots, [&](int, int, int, int) { ++calls; },
        &touched);
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(touched, (std::vector<std::uint8_t>{1, 0, 1}));
}

// The rule read directly (above): robot i's expected lists and the
// expected then(i, k) calls of one Share over `robots`.
void ShareByTheRule(const Team& team, const std::vector<MissSlot>& slots,
                    const std::vector<int>& robots, int m, double log_eps,
                    std::vector<MissSlot>* expected,
                    std::vector<std::pair<int, int>>* calls) {
  *expected = slots;
  calls->clear();
  std::vector<int> sorted = robots;
  std::sort(sorted.begin(), sorted.end());
  for (int i : sorted)
    for (int k = 0; k < m; ++k) {
      const MissSlot& own = slots[i * m + k];
      if (!(own.log_det > log_eps)) continue;
      std::vector<int> taken;
      for (int j : team.comm.Neighbors(i))
        for (int q : slots[j * m + k].missed)
          if (std::find(own.missed.begin(), own.missed.end(), q) ==
              own.missed.end())
            taken.push_back(q);
      std::sort(taken.begin(), taken.end());
      taken.erase(std::unique(taken.begin(), taken.end()), taken.end());
      if (taken.empty()) continue;
      for (int q : taken) (*expected)[i * m + k].missed.push_back(q);
      calls->push_back({i, k});
    }
}

// A point in 0, 7, ..., 35 not in the list yet, or -1 (few distinct points,
// so that lists overlap).
int NewPoint(const MissList& list, Rng* rng) {
  const int q = static_cast<int>(rng->Uniform() * 6) * 7;
  return std::find(list.begin(), list.end(), q) == list.end() ? q : -1;
}

TEST(NeighbourMissesTest, EachRobotTakesItsNeighboursPointsOnce) {
  for (int trial = 0; trial < 24; ++trial) {
    const std::unique_ptr<Team> made = GraphTrial(trial, 5, 100);
    Team& team = *made;
    const int n = 9, m = 5;
    Rng rng(7, "neighbour_misses_test", static_cast<std::uint64_t>(trial));
    std::vector<MissSlot> slots(n * m);
    const double log_eps = std::log(team.scenario.mission.eps);
    for (MissSlot& s : slots) {
      s.log_det = rng.Uniform() < 0.2 ? log_eps - 1.0 : log_eps + 1.0;
      const int count = static_cast<int>(rng.Uniform() * 4);
      for (int c = 0; c < count; ++c) {
        const int q = NewPoint(s.missed, &rng);
        if (q >= 0) s.missed.push_back(q);
      }
    }
    std::vector<int> robots;
    for (int i = 0; i < n; ++i)
      if (rng.Uniform() < 0.8) robots.push_back(i);
    std::vector<MissSlot> expected;
    std::vector<std::pair<int, int>> expected_calls;
    ShareByTheRule(team, slots, robots, m, log_eps, &expected, &expected_calls);
    NeighbourMisses sharing;
    std::vector<std::pair<int, int>> calls;
    std::vector<int> shuffled(robots.rbegin(), robots.rend());
    // What SearchMemory::RecomputeShared relies on: the robots of a group that
    // took points of a target hold the same set of them.
    std::map<std::pair<int, int>, std::vector<int>> held;
    int shared = 0;
    std::vector<std::uint8_t> touched(n, 1);
    sharing.Share(
        team.Context(), shuffled, m, &slots,
        [&](int i, int k, int group, int worker) {
          calls.push_back({i, k});
          EXPECT_EQ(worker, 0);
          std::vector<int> set = slots[i * m + k].missed.points();
          std::sort(set.begin(), set.end());
          const auto [it, fresh] = held.insert({{group, k}, set});
          if (!fresh) {
            EXPECT_EQ(set, it->second) << "robot " << i;
            ++shared;
          }
        },
        &touched);
    for (int s = 0; s < n * m; ++s)
      EXPECT_EQ(slots[s].missed.points(), expected[s].missed.points())
          << "trial " << trial << ", robot " << s / m << ", target " << s % m;
    EXPECT_EQ(calls, expected_calls) << "trial " << trial;
    if (trial % 2 == 0) EXPECT_GT(shared, 0) << "trial " << trial;
  }
}

// The unions a call makes from what the last call shared (a list that call
// made equal to a union reads that union once) match the rule call after
// call: lists appended to and cleared between calls, robots that skip a
// call, open and closed beliefs, and a graph that loses other edges every
// step (so a robot's neighbourhood changes under its shared list).
TEST(NeighbourMissesTest, CallAfterCallMatchesTheRule) {
  long reused = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const std::unique_ptr<Team> made = GraphTrial(trial, 4, 300);
    Team& team = *made;
    const int n = 9, m = 4;
    Rng rng(7, "neighbour_misses_calls", static_cast<std::uint64_t>(trial));
    std::vector<MissSlot> slots(n * m);
    const double log_eps = std::log(team.scenario.mission.eps);
    NeighbourMisses sharing;
    // Only the robots whose lists changed are marked (as MissSlots marks
    // them): the others' targets are the last call's.
    std::vector<std::uint8_t> touched(n, 1);
    std::vector<Vec2> p;
    for (int idx : team.positions)
      p.push_back(team.world.map.lattice().Point(idx));
    for (int call = 0; call < 8; ++call) {
      team.comm.Update(call + 2, p);
      for (int at = 0; at < n * m; ++at) {
        MissSlot& s = slots[at];
        s.log_det = rng.Uniform() < 0.15 ? log_eps - 1.0 : log_eps + 1.0;
        const double u = rng.Uniform();
        if (u < 0.1) {
          if (!s.missed.empty()) touched[at / m] = 1;
          s.missed.clear();
        }
        if (u > 0.7) {
          const int q = NewPoint(s.missed, &rng);
          if (q >= 0) {
            s.missed.push_back(q);
            touched[at / m] = 1;
          }
        }
      }
      for (const MissSlot& s : slots)
        reused += s.missed.SharedGroup(call) >= 0 ? 1 : 0;
      std::vector<int> robots;
      for (int i = 0; i < n; ++i)
        if (rng.Uniform() < 0.85) robots.push_back(i);
      std::vector<MissSlot> expected;
      std::vector<std::pair<int, int>> expected_calls;
      ShareByTheRule(team, slots, robots, m, log_eps, &expected,
                     &expected_calls);
      std::vector<std::pair<int, int>> calls;
      sharing.Share(
          team.Context(), robots, m, &slots,
          [&](int i, int k, int, int) {
            calls.push_back({i, k});
          },
          &touched);
      for (int s = 0; s < n * m; ++s) {
        std::vector<int> got = slots[s].missed.points();
        std::vector<int> want = expected[s].missed.points();
        // The rule's order: the own list, then what it took, ascending.
        EXPECT_EQ(got, want) << "trial " << trial << ", call " << call
                             << ", robot " << s / m << ", target " << s % m;
      }
      EXPECT_EQ(calls, expected_calls)
          << "trial " << trial << ", call " << call;
    }
  }
  // The shortcut was taken (lists shared by the call before).
  EXPECT_GT(reused, 100);
}

// Each robot's block of the first target: det Sigma = d (Omega = I / sqrt(d)).
void SetDet(Team* team, int robot, int k, double d) {
  team->beliefs.Omega(robot, k) =
      Eigen::MatrixXd::Identity(2, 2) / std::sqrt(d);
}

// Known answers, three robots in a full graph (eps 0.1, refresh 0.003). A
// robot holding the target at det 1e-4 (below 3e-4) closes it for all. At
// det 0.05 with the others at the prior (det 1), the pooled level is
// -2 log((sqrt(20) + 2) / 3) = log 0.215: above eps, so the lone holder's
// share would ebb away and the target stays open. At det 1e-3 it is
// log(1 / ((sqrt(1000) + 2) / 3)^2) = log 0.008: below eps, closed.
TEST(NeighbourhoodHoldsTest, KnownAnswersInAFullGraph) {
  Team team(
      "workspace: {size: [10.0, 10.0]}\n"
      "robots: {count: 3}\n"
      "targets: {count: 1}\n"
      "mission: {eps: 0.1}\n");
  SetCovariance(&team, 1.0);
  NeighbourhoodHolds holds;
  const std::vector<int> robots = {0, 1, 2};
  const auto open_for_all = [&](bool expected) {
    holds.Compute(team.Context(), robots, 0.003);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(holds.Open(i, 0), expected) << i;
  };
  open_for_all(true);  // nobody holds it
  SetDet(&team, 1, 0, 1e-4);
  open_for_all(false);
  EXPECT_NEAR(holds.Best(2, 0), std::log(1e-4), 1e-12);
  SetDet(&team, 1, 0, 0.05);
  open_for_all(true);
  EXPECT_NEAR(holds.Pooled(0, 0),
              -2.0 * std::log((std::sqrt(20.0) + 2.0) / 3.0), 1e-12);
  SetDet(&team, 1, 0, 1e-3);
  open_for_all(false);
  // Refresh 1: held below eps is closed, whatever the pooled level.
  SetDet(&team, 1, 0, 0.05);
  holds.Compute(team.Context(), robots, 1.0);
  EXPECT_FALSE(holds.Open(0, 0));
  EXPECT_FALSE(holds.Has(-1));
}

// One ClosedNeighbourhoods over steps whose graph stays or changes (range
// graphs with lost edges, robots that move): each step's groups are the
// robots asked with equal closed neighbourhoods, numbered in the order the
// step first asks for them, each led by its first robot asked, as a fresh
// grouping of that step gives them.
TEST(ClosedNeighbourhoodsTest, KeptClassesGroupAsAFreshGrouping) {
  const std::unique_ptr<Team> made = GraphTrial(1, 3, 900);
  Team& team = *made;
  const int n = 9;
  Rng rng(9, "closed_neighbourhoods_test");
  ClosedNeighbourhoods kept;
  const auto closed = [&](int i) {
    std::vector<int> c;
    ClosedNeighbourhoods::ForClosed(team.Context(), i,
                                    [&](int j) { c.push_back(j); });
    return c;
  };
  for (int step = 0; step < 12; ++step) {
    if (step % 3 == 2) {  // a new graph: the robots move
      std::vector<Vec2> p;
      for (int i = 0; i < n; ++i)
        p.push_back(Vec2(rng.Uniform() * 10.0, rng.Uniform() * 10.0));
      team.comm.Update(step + 2, p);
    }
    std::vector<int> asked;
    for (int i = 0; i < n; ++i)
      if (rng.Uniform() < 0.7) asked.push_back(i);
    std::shuffle(asked.begin(), asked.end(), std::mt19937(step));
    const DecisionContext ctx = team.Context();
    kept.Clear();
    ClosedNeighbourhoods fresh_grouping;
    std::vector<std::vector<int>> leaders;  // per group: its closed set
    for (int i : asked) {
      bool fresh = false, fresh_new = false;
      const int g = kept.Of(ctx, i, &fresh);
      EXPECT_EQ(g, fresh_grouping.Of(ctx, i, &fresh_new)) << step << " " << i;
      EXPECT_EQ(fresh, fresh_new);
      // The expected group: the first one with robot i's closed set.
      const auto at = std::find(leaders.begin(), leaders.end(), closed(i));
      EXPECT_EQ(g, static_cast<int>(at - leaders.begin())) << step;
      EXPECT_EQ(fresh, at == leaders.end());
      if (at == leaders.end()) leaders.push_back(closed(i));
      EXPECT_EQ(closed(kept.robot(g)), closed(i));
    }
    EXPECT_EQ(kept.size(), static_cast<int>(leaders.size()));
  }
}

// NeighbourhoodHolds against the rule read directly, robot by robot: random
// beliefs on full and range graphs with lost edges (neighbourhoods repeat
// and differ), some robots left out, the targets split over three threads.
TEST(NeighbourhoodHoldsTest, EachRobotReadsItsClosedNeighbourhood) {
  const RangeRunner three = ThreeThreads();
  for (int trial = 0; trial < 12; ++trial) {
    const std::unique_ptr<Team> made = GraphTrial(trial, 7, 300);
    Team& team = *made;
    const int n = 9, m = 7;
    Rng rng(7, "neighbourhood_holds_test", static_cast<std::uint64_t>(trial));
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < m; ++k)
        SetDet(&team, i, k, std::exp(-12.0 * rng.Uniform() + 1.0));
    std::vector<int> robots;
    for (int i = 0; i < n; ++i)
      if (rng.Uniform() < 0.8) robots.push_back(i);
    const DecisionContext ctx = team.Context();
    const double refresh = 0.01;
    NeighbourhoodHolds holds;
    holds.Compute(ctx, robots, refresh, trial % 4 == 0 ? RangeRunner{} : three);
    const double log_eps = std::log(ctx.eps);
    for (int i = 0; i < n; ++i) {
      const bool in =
          std::find(robots.begin(), robots.end(), i) != robots.end();
      ASSERT_EQ(holds.Has(i), in) << i;
      if (!in) continue;
      std::vector<int> closed = {i};
      for (int j : team.comm.Neighbors(i))
        if (j != i) closed.push_back(j);
      for (int k = 0; k < m; ++k) {
        double best = std::numeric_limits<double>::infinity(), sum = 0.0;
        for (int j : closed)
          best = std::min(best, team.beliefs.LogDetCovariance(j, k));
        for (int j : closed)
          sum += std::exp(-0.5 * team.beliefs.LogDetCovariance(j, k));
        const double pooled = -2.0 * std::log(sum / closed.size());
        const bool open = best > log_eps + std::log(refresh) &&
                          (best > log_eps || pooled > log_eps);
        EXPECT_EQ(holds.Best(i, k), best) << trial << " " << i << " " << k;
        EXPECT_NEAR(holds.Pooled(i, k), pooled, 1e-9)
            << trial << " " << i << " " << k;
        EXPECT_EQ(holds.Open(i, k), open) << trial << " " << i << " " << k;
      }
    }
  }
}

// Update and Share split over threads (three, unevenly) leave every
// robot's misses and aims as one thread does.
TEST(SearchMemoryTest, ThreadsDoNotChangeTheMemory) {
  Team team(
      "workspace: {size: [12.0, 12.0]}\n"
      "robots: {count: 7}\n"
      "targets: {list: [{position: [1.0, 11.0], prior_mean: [6.1, 6.2]}, "
      "{position: [11.0, 1.0], prior_mean: [4.3, 7.9]}, {position: [1.0, "
      "1.0], prior_mean: [8.2, 4.4], prior_sigma: 2.0}]}\n");
  const RangeRunner three = ThreeThreads();
  SearchMemory serial, threaded;
  serial.Reset(7, 3);
  threaded.Reset(7, 3);
  const std::vector<int> robots = {0, 1, 2, 3, 4, 5, 6};
  const Lattice& lattice = team.world.map.lattice();
  for (int step = 0; step < 6; ++step) {
    // Each robot on a walk around the middle of the world.
    for (int i = 0; i < 7; ++i) {
      const double a = 0.9 * i + 0.7 * step;
      team.positions[i] =
          lattice.NearestPoint(Vec2(6.0 + (1.0 + 0.4 * i) * std::cos(a),
                                    6.0 + (1.0 + 0.4 * i) * std::sin(a)));
    }
    const DecisionContext ctx = team.Context();
    for (int i : robots) serial.Update(ctx, i);
    serial.Share(ctx, robots);
    threaded.Update(ctx, robots, three, 3);
    threaded.Share(ctx, robots, three, 3);
  }
  EXPECT_GT(serial.misses(), 5);
  EXPECT_EQ(threaded.misses(), serial.misses());
  for (int i = 0; i < 7; ++i)
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(threaded.Missed(i, k), serial.Missed(i, k));
      EXPECT_EQ(threaded.Aim(i, k), serial.Aim(i, k));
    }
}

// The worlds of the shared-search tests: 12 x 12 m with 8 boxes, 9 robots,
// three targets in the corners whose priors lie in the middle and `more`
// of them, a full graph in trials 0 and 2 and a 4 m range graph in 1 and
// 3, a 2 m sensor in trials 0 and 1 and 1.5 m after.
Team SharedSearchTeam(int seed, int trial, const std::string& more = "") {
  CommParams cp;
  cp.mode = trial % 2 ? CommMode::kRange : CommMode::kFull;
  cp.range = 4.0;
  return Team(
      "workspace: {size: [12.0, 12.0], obstacles: {random: {count: 8}}}\n"
      "seed: " +
          std::to_string(seed) +
          "\nsensor: {range: " + (trial < 2 ? "2.0" : "1.5") +
          "}\nrobots: {count: 9}\n"
          "targets: {list: [{position: [1.0, 11.0], prior_mean: [6.1, "
          "6.2], prior_sigma: 2.0}, {position: [11.0, 1.0], prior_mean: "
          "[4.3, 7.9], prior_sigma: 1.5}, {position: [1.0, 1.0], "
          "prior_mean: [8.2, 4.4], prior_sigma: 2.5}" +
          more + "]}\n",
      cp);
}

// Each robot of SharedSearchTeam at `step` of a walk around the middle of
// the world (where the point is free), and the graph of those positions.
void WalkAroundTheMiddle(int step, Team* team) {
  const Lattice& lattice = team->world.map.lattice();
  for (int i = 0; i < 9; ++i) {
    const double a = 0.9 * i + 0.7 * step;
    const int q =
        lattice.NearestPoint(Vec2(6.0 + (1.0 + 0.4 * i) * std::cos(a),
                                  6.0 + (1.0 + 0.4 * i) * std::sin(a)));
    if (lattice.Free(q)) team->positions[i] = q;
  }
  std::vector<Vec2> p;
  for (int idx : team->positions) p.push_back(lattice.Point(idx));
  team->comm.Update(step, p);
}

// A fourth target for SharedSearchTeam, at the middle the walks pass,
// whose belief the odd robots hold otherwise (more certain, its mean
// moved): the robots of a neighbourhood that take the same misses of it
// hold two beliefs, so what Share makes per belief is told apart.
constexpr const char* kTargetInTheMiddle =
    ", {position: [7.0, 6.0], prior_mean: [4.5, 5.0], prior_sigma: 2.0}";
void GiveTheOddRobotsAnotherBelief(Team* team) {
  for (int i = 1; i < 9; i += 2) {
    auto omega = team->beliefs.Omega(i, 3);
    omega *= 1.5;
    team->beliefs.Xi(i, 3) = omega * Eigen::Vector2d(4.8, 4.8);
  }
}

// Eight steps of WalkAroundTheMiddle with `memory` (a SearchMemory or
// SearchPoints of `targets` targets) updated and shared on three threads;
// after each, check(ctx, step, i, k, missed) for each robot i and target k
// whose misses changed in the step and are not empty.
template <typename Memory, typename Check>
void RunSharedSearch(Team* team, int targets, Memory* memory, Check check) {
  memory->Reset(9, targets);
  std::vector<int> robots(9);
  for (int i = 0; i < 9; ++i) robots[i] = i;
  for (int step = 0; step < 8; ++step) {
    WalkAroundTheMiddle(step, team);
    const DecisionContext ctx = team->Context();
    std::vector<std::vector<int>> before;
    for (int i = 0; i < 9; ++i)
      for (int k = 0; k < targets; ++k) before.push_back(memory->Missed(i, k));
    memory->Update(ctx, robots, ThreeThreads(), 3);
    memory->Share(ctx, robots, ThreeThreads(), 3);
    for (int i = 0; i < 9; ++i)
      for (int k = 0; k < targets; ++k) {
        const std::vector<int>& missed = memory->Missed(i, k);
        if (!missed.empty() && missed != before[i * targets + k])
          check(ctx, step, i, k, missed);
      }
  }
}

// Share's walks, made once per neighbourhood, target and belief, give each
// robot the aim its own walk would: wherever a robot's misses changed in a
// step, its aim is SearchAim's from its point, belief and misses, with the
// nearest observer as the cost. A full graph (robots share walks) and a
// range graph (they mostly do not), boxes, two sensor ranges, two beliefs
// of one target in a team.
TEST(SearchMemoryTest, SharedWalksGiveEachRobotItsOwnAim) {
  int checked = 0;
  for (int trial = 0; trial < 4; ++trial) {
    Team team = SharedSearchTeam(30 + trial, trial, kTargetInTheMiddle);
    GiveTheOddRobotsAnotherBelief(&team);
    const Map& map = team.world.map;
    const int span =
        static_cast<int>(std::ceil(team.sensor.range / map.lattice().step())) +
        1;
    SearchMemory memory;
    RunSharedSearch(&team, 4, &memory,
                    [&](const DecisionContext& ctx, int step, int i, int k,
                        const std::vector<int>& missed) {
                      Vec2 want;
                      const int here = team.positions[i];
                      SearchAim(
                          map, team.sensor, MeanOf(ctx, i, k),
                          ctx.beliefs->PositionCovariance(i, k), &missed,
                          [&](const Vec2& x, int bound) {
                            return NearestObserverDistance(
                                map, team.sensor, here, x, span, bound);
                          },
                          &want);
                      EXPECT_EQ(memory.Aim(i, k), want)
                          << "trial " << trial << " step " << step << " robot "
                          << i << " target " << k;
                      ++checked;
                    });
  }
  EXPECT_GT(checked, 40);
}

// Share's search points, recomputed once per neighbourhood, target,
// belief and component, give each robot the points its own recompute
// would: wherever a robot's misses changed in a step, its points are the
// first ring of the prior (WalkPriorRings) whose points are free, not
// ruled out by its misses and measurable from some point of its own
// component; none where the mean itself is such a point. Full and range
// graphs, boxes, two sensor ranges.
TEST(SearchPointsTest, SharedPointsGiveEachRobotItsOwnPoints) {
  int checked = 0, some = 0;
  for (int trial = 0; trial < 4; ++trial) {
    Team team = SharedSearchTeam(40 + trial, trial, kTargetInTheMiddle);
    const Map& map = team.world.map;
    const Lattice& lattice = map.lattice();
    const int span =
        static_cast<int>(std::ceil(team.sensor.range / lattice.step())) + 1;
    GiveTheOddRobotsAnotherBelief(&team);
    SearchPoints points;
    RunSharedSearch(
        &team, 4, &points,
        [&](const DecisionContext& ctx, int step, int i, int k,
            const std::vector<int>& missed) {
          const int here = team.positions[i];
          const std::vector<Vec2> ruled = MissedPoints(lattice, &missed);
          std::vector<Vec2> want;
          bool mean_viable = false;
          int index = 0;
          const int ring = WalkPriorRings(
              MeanOf(ctx, i, k), ctx.beliefs->PositionCovariance(i, k),
              lattice.step(),
              [&](const Vec2& x) {
                const bool first = index++ == 0;
                if (!map.PointFree(x) || RuledOut(map, team.sensor, ruled, x) ||
                    NearestObserverDistance(map, team.sensor, here, x, span) <
                        0)
                  return;
                if (first) mean_viable = true;
                want.push_back(x);
              },
              [&] { return !want.empty(); });
          ASSERT_GE(ring, 0);  // else the misses would have been forgotten
          if (mean_viable) want.clear();
          EXPECT_EQ(points.Points(i, k), want)
              << "trial " << trial << " step " << step << " robot " << i
              << " target " << k;
          ++checked;
          some += !want.empty();
        });
  }
  EXPECT_GT(checked, 40);
  EXPECT_GT(some, 20);
}

// Route plans while robots x open targets is at most 40 x 40 and the
// open targets at most 40; else Claim's answer.
TEST(TargetClaimsTest, RoutesArePlannedUpTo40By40And40Targets) {
  EXPECT_TRUE(TargetClaims::Plans(40, 39));   // 40 x 40
  EXPECT_FALSE(TargetClaims::Plans(40, 40));  // 41 x 40
  EXPECT_TRUE(TargetClaims::Plans(10, 9));
  EXPECT_TRUE(TargetClaims::Plans(40, 0));    // a robot alone, 40 targets
  EXPECT_FALSE(TargetClaims::Plans(41, 0));   // 41 targets
  EXPECT_FALSE(TargetClaims::Plans(200, 3));  // a range graph at scale
  EXPECT_TRUE(TargetClaims::Plans(0, 100));
}

TEST(TargetClaimsTest, TheRobotFewestMovesFromMeasuringClaims) {
  Team team(kEmptyWorld);
  TargetClaims claims;
  claims.Begin(team.world.map, team.sensor);
  const Vec2 aim(5.1, 5.25);
  // From (1.25, 5.25) the nearest point within 2 m of the aim is
  // (3.25, 5.25), 1.85 m away: 4 moves. From (5.25, 9.25): (5.25, 6.75),
  // 1.51 m away (7.25 is 2.005 m away): 5 moves.
  const int a = PointAt(team, 1.25, 5.25), b = PointAt(team, 5.25, 9.25);
  EXPECT_EQ(claims.Distance(aim, a), 4);
  EXPECT_EQ(claims.Distance(aim, b), 5);
  EXPECT_EQ(claims.Distance(aim, PointAt(team, 5.25, 5.25)), 0);
  std::vector<std::uint8_t> mine;
  claims.Claim(a, {b}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1}));
  claims.Claim(b, {a}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
  // A target that is not open is nobody's.
  claims.Claim(a, {b}, {aim}, {0}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
  // Equal distances (4 moves each side): the robot of the lower x, whichever
  // robot asks and in whatever order the others come.
  const Vec2 mid(5.25, 5.25);
  const int west = PointAt(team, 1.25, 5.25), east = PointAt(team, 9.25, 5.25);
  EXPECT_EQ(claims.Distance(mid, west), claims.Distance(mid, east));
  claims.Claim(west, {east, b}, {mid}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1}));
  claims.Claim(east, {b, west}, {mid}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
}

TEST(TargetClaimsTest, WallsCountWhereAStraightLineWouldNot) {
  // A wall from y = 1 to y = 10 at x = 3..3.5: the robot west of it is
  // nearer to the aim in a straight line (3.9 m against 4.4 m) but must go
  // around the wall's south end.
  Team team(
      "workspace: {size: [10.0, 10.0], obstacles: {boxes: [{center: [3.25, "
      "5.5], size: [0.5, 9.0]}]}}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0]}]}\n");
  TargetClaims claims;
  claims.Begin(team.world.map, team.sensor);
  const Vec2 aim(5.1, 7.25);
  const int west = PointAt(team, 1.25, 7.25), south = PointAt(team, 5.25, 2.75);
  const Lattice& lattice = team.world.map.lattice();
  ASSERT_LT((lattice.Point(west) - aim).norm(),
            (lattice.Point(south) - aim).norm());
  EXPECT_GT(claims.Distance(aim, west), claims.Distance(aim, south));
  std::vector<std::uint8_t> mine;
  claims.Claim(west, {south}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
  claims.Claim(south, {west}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1}));
}

// Fields reach every point while targets x lattice points is at most 4e6;
// beyond it, the horizon: (sqrt(4e6 / m) - 1) / 2 rounded down, less the
// sensor's span (2 m / 0.5 m + 1 = 5), at least 2 spans.
TEST(TargetClaimsTest, FieldsReachAHorizonOnlyBeyondTheBudget) {
  Team team(
      "workspace: {size: [100.0, 100.0], obstacles: {random: {count: 600}}}\n"
      "robots: {count: 1}\n"
      "targets: {count: 1}\n");
  const Lattice& lattice = team.world.map.lattice();
  ASSERT_EQ(lattice.size(), 40000);
  EXPECT_EQ(TargetClaims::Horizon(10, lattice, 5), -1);
  EXPECT_EQ(TargetClaims::Horizon(100, lattice, 5), -1);  // 4e6 exactly
  // sqrt(4e6 / 101) = 199.0: 99 - 5.
  EXPECT_EQ(TargetClaims::Horizon(101, lattice, 5), 94);
  // sqrt(4000) = 63.2: 31 - 5.
  EXPECT_EQ(TargetClaims::Horizon(1000, lattice, 5), 26);
  EXPECT_EQ(TargetClaims::Horizon(1000000, lattice, 5), 10);
  // Within the horizon, the windowed field is the whole one; beyond it,
  // nothing is in reach. The same aims, near the middle and at the edges.
  TargetClaims whole, near;
  whole.Begin(team.world.map, team.sensor, 0);
  near.Begin(team.world.map, team.sensor, 1000);
  for (const Vec2 aim : {Vec2(50.1, 49.9), Vec2(0.3, 0.2), Vec2(99.8, 60.0)}) {
    int inside = 0, beyond = 0;
    for (int p = 0; p < lattice.size(); ++p) {
      const int d = whole.Distance(aim, p);
      if (d >= 0 && d <= 26) {
        ASSERT_EQ(near.Distance(aim, p), d) << "point " << p;
        ++inside;
      } else {
        ASSERT_EQ(near.Distance(aim, p), -1) << "point " << p;
        beyond += d > 26;
      }
    }
    EXPECT_GT(inside, 100);
    EXPECT_GT(beyond, 10000);
  }
  // A robot alone claims the target exactly where it is within the horizon.
  const Vec2 aim(50.1, 49.9);
  std::vector<std::uint8_t> mine;
  for (int p = 0; p < lattice.size(); ++p) {
    const int d = whole.Distance(aim, p);
    near.Claim(p, {}, {aim}, {1}, &mine);
    ASSERT_EQ(mine[0], d >= 0 && d <= 26) << "point " << p << ", " << d;
  }
  // With another robot: the nearer one within the horizon.
  int far = -1, close = -1;
  for (int p = 0; p < lattice.size() && (far < 0 || close < 0); ++p) {
    const int d = whole.Distance(aim, p);
    if (d > 26 && d < 40 && far < 0) far = p;
    if (d > 0 && d < 20 && close < 0) close = p;
  }
  ASSERT_GE(far, 0);
  ASSERT_GE(close, 0);
  near.Claim(far, {}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
  whole.Claim(far, {}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1}));
  near.Claim(far, {close}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
  near.Claim(close, {far}, {aim}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1}));
}

// Claims and routes asked from three threads at once give what one thread
// gets: the fields' cache and the plans are shared and locked.
TEST(TargetClaimsTest, ThreadsAskingAtOnceGetTheSameAnswers) {
  Team team(
      "workspace: {size: [30.0, 30.0], obstacles: {random: {count: 40}}}\n"
      "robots: {count: 1}\n"
      "targets: {count: 1}\n");
  const Lattice& lattice = team.world.map.lattice();
  Rng rng(5, "claims_threads_test");
  std::vector<int> points;
  while (points.size() < 24) {
    const int p =
        lattice.NearestPoint(Vec2(30.0 * rng.Uniform(), 30.0 * rng.Uniform()));
    if (lattice.Free(p)) points.push_back(p);
  }
  std::vector<Vec2> aims;
  std::vector<std::uint8_t> open;
  for (int k = 0; k < 12; ++k) {
    aims.push_back(Vec2(30.0 * rng.Uniform(), 30.0 * rng.Uniform()));
    open.push_back(k % 5 != 2);
  }
  // Groups of 4 neighbours: routes (4 x 10 pairs) and claims.
  const auto others_of = [&](int i) {
    std::vector<int> others;
    for (int j = i / 4 * 4; j < i / 4 * 4 + 4; ++j)
      if (j != i) others.push_back(points[j]);
    return others;
  };
  const int n = static_cast<int>(points.size());
  std::vector<std::vector<std::uint8_t>> serial(2 * n), threaded(2 * n);
  TargetClaims one, shared;
  one.Begin(team.world.map, team.sensor);
  shared.Begin(team.world.map, team.sensor);
  for (int i = 0; i < n; ++i) {
    one.Route(points[i], others_of(i), aims, open, &serial[i]);
    one.Claim(points[i], others_of(i), aims, open, &serial[n + i]);
  }
  std::vector<std::thread> pool;
  for (int t = 0; t < 3; ++t)
    pool.emplace_back([&, t] {
      for (int i = t; i < n; i += 3) {
        shared.Route(points[i], others_of(i), aims, open, &threaded[i]);
        shared.Claim(points[i], others_of(i), aims, open, &threaded[n + i]);
      }
    });
  for (std::thread& th : pool) th.join();
  int claimed = 0;
  for (int r = 0; r < 2 * n; ++r) {
    EXPECT_EQ(threaded[r], serial[r]) << "robot " << r % n;
    claimed += std::count(serial[r].begin(), serial[r].end(), 1);
  }
  EXPECT_GT(claimed, 10);
}

TEST(TargetClaimsTest, AnIdleRobotHelpsTheOwnerOfTwoWhereItIsTheNearestIdle) {
  Team team(kEmptyWorld);
  TargetClaims claims;
  claims.Begin(team.world.map, team.sensor);
  // A at (5.25, 5.25) sees t1 (5.25, 6.25) and is 2 moves from t2
  // (8.25, 5.25), which (6.25, 5.25) sees: it owns both. B (9.25, 9.25) is 5
  // moves from t2 and 9 from t1; C (1.25, 5.25) 5 from t1 (to (3.75, 5.25))
  // and 10 from t2.
  const std::vector<Vec2> aims = {Vec2(5.25, 6.25), Vec2(8.25, 5.25)};
  const std::vector<std::uint8_t> open = {1, 1};
  const int a = PointAt(team, 5.25, 5.25), b = PointAt(team, 9.25, 9.25),
            c = PointAt(team, 1.25, 5.25);
  EXPECT_EQ(claims.Distance(aims[0], a), 0);
  EXPECT_EQ(claims.Distance(aims[1], a), 2);
  EXPECT_EQ(claims.Distance(aims[1], b), 5);
  EXPECT_EQ(claims.Distance(aims[0], b), 9);
  EXPECT_EQ(claims.Distance(aims[0], c), 5);
  EXPECT_EQ(claims.Distance(aims[1], c), 10);
  std::vector<std::uint8_t> mine;
  claims.Claim(a, {b, c}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1, 1}));
  claims.Claim(b, {c, a}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0, 1}));
  claims.Claim(c, {a, b}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1, 0}));
  // Without C, B is the only idle robot and helps with both.
  claims.Claim(b, {a}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1, 1}));
  // An owner of one is not helped.
  claims.Claim(b, {a}, {aims[1]}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
}

TEST(TargetClaimsTest, RoutesGiveEachRobotTheFirstTargetOfMakespanTours) {
  Team team(
      "workspace: {size: [20.0, 10.0]}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0]}]}\n");
  TargetClaims claims;
  claims.Begin(team.world.map, team.sensor);
  // On the row y = 5.25: A at x = 10.25 is 8 moves from t1 (16.25: seen
  // from 14.25) and 2 from t2 (7.25: seen from 9.25); B at 0.25 is 10 from
  // t2 (seen from 5.25) and 28 from t1. A owns both (nearest); its nearer
  // target first would end the mission at 2 + 10 = 12 moves, t1 first with
  // B on t2 at 10: A's route starts with t1, B's with t2. C, in the corner
  // above B (18 moves from t2), has no route and claims nothing; the
  // others' order and C's presence do not change A's and B's routes.
  const std::vector<Vec2> aims = {Vec2(16.25, 5.25), Vec2(7.25, 5.25)};
  const std::vector<std::uint8_t> open = {1, 1};
  const int a = PointAt(team, 10.25, 5.25), b = PointAt(team, 0.25, 5.25),
            c = PointAt(team, 0.25, 9.75);
  EXPECT_EQ(claims.Distance(aims[0], a), 8);
  EXPECT_EQ(claims.Distance(aims[1], a), 2);
  EXPECT_EQ(claims.Distance(aims[1], b), 10);
  EXPECT_EQ(claims.Distance(aims[0], b), 28);
  EXPECT_EQ(claims.Distance(aims[1], c), 18);
  std::vector<std::uint8_t> mine;
  claims.Claim(a, {b}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({1, 1}));
  for (const std::vector<int>& others :
       {std::vector<int>{b}, std::vector<int>{b, c}, std::vector<int>{c, b}}) {
    claims.Route(a, others, aims, open, &mine);
    EXPECT_EQ(mine, std::vector<std::uint8_t>({1, 0}));
  }
  claims.Route(b, {c, a}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0, 1}));
  claims.Route(c, {a, b}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0, 0}));
  // Alone, A takes its nearer target first.
  claims.Route(a, {}, aims, open, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0, 1}));
}

TEST(TargetClaimsTest, LargeTeamsGetNearestClaimsInsteadOfRoutes) {
  Team team(
      "workspace: {size: [30.0, 30.0]}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [8.0, 8.0]}]}\n");
  TargetClaims claims;
  claims.Begin(team.world.map, team.sensor);
  // Robots on a grid, aims scattered: 40 robots x 40 targets = 1600 pairs
  // (routes: one target each at most), then 41 x 40 (nearest claims).
  std::vector<int> robots;
  for (int r = 0; r < 41; ++r)
    robots.push_back(PointAt(team, 1.25 + 3.5 * (r % 8), 1.25 + 5.5 * (r / 8)));
  std::vector<Vec2> aims;
  for (int k = 0; k < 40; ++k)
    aims.push_back(
        Vec2(2.1 + 0.7 * ((k * 17) % 40), 2.3 + 0.65 * ((k * 29) % 40)));
  const std::vector<std::uint8_t> open(40, 1);
  for (const int n : {40, 41}) {
    int routed = 0;
    for (int r = 0; r < n; ++r) {
      std::vector<int> others;
      for (int q = 0; q < n; ++q)
        if (q != r) others.push_back(robots[q]);
      std::vector<std::uint8_t> route, nearest;
      claims.Route(robots[r], others, aims, open, &route);
      claims.Claim(robots[r], others, aims, open, &nearest);
      const int count = std::count(route.begin(), route.end(), 1);
      if (n == 40) {
        EXPECT_LE(count, 1) << "robot " << r;
        routed += count;
      } else {
        EXPECT_EQ(route, nearest) << "robot " << r;
      }
    }
    if (n == 40) EXPECT_GT(routed, 20);  // most robots have a route
  }
}

TEST(TargetClaimsTest, ATargetNoPointMeasuresIsNobodys) {
  // The aim inside a closed box: no free point sees it.
  Team team(
      "workspace: {size: [10.0, 10.0], obstacles: {boxes: [{center: [5.0, "
      "5.0], size: [6.0, 6.0]}]}}\n"
      "robots: {count: 1, start: [[1.25, 1.25]]}\n"
      "targets: {list: [{position: [9.0, 9.0]}]}\n");
  TargetClaims claims;
  claims.Begin(team.world.map, team.sensor);
  const int a = PointAt(team, 1.25, 1.25);
  EXPECT_EQ(claims.Distance(Vec2(5.0, 5.0), a), -1);
  std::vector<std::uint8_t> mine;
  claims.Claim(a, {}, {Vec2(5.0, 5.0)}, {1}, &mine);
  EXPECT_EQ(mine, std::vector<std::uint8_t>({0}));
}

}  // namespace
}  // namespace aia
