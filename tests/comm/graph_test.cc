#include "aia/comm/graph.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace aia {
namespace {

TEST(CommTest, FullGraphConnectsEveryPair) {
  CommNetwork net({}, 4, {}, 1);
  net.Update(0, std::vector<Vec2>(4, Vec2(0, 0)));
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(net.Neighbors(i).size(), 3u);
    for (int j : net.Neighbors(i)) EXPECT_NE(j, i);
  }
  EXPECT_TRUE(net.Lost().empty());
}

TEST(CommTest, RangeGraphByHand) {
  CommParams p;
  p.mode = CommMode::kRange;
  p.range = 4.0;
  CommNetwork net(p, 3, {}, 1);
  // 0 -- 1 are 3 m apart, 1 -- 2 are 4 m apart (in range), 0 -- 2 are 7 m.
  net.Update(0, {{0, 0}, {3, 0}, {7, 0}});
  EXPECT_EQ(net.Neighbors(0), (std::vector<int>{1}));
  EXPECT_EQ(net.Neighbors(1), (std::vector<int>{0, 2}));
  EXPECT_EQ(net.Neighbors(2), (std::vector<int>{1}));
}

TEST(CommTest, PacketLossDeletesPoissonManyDirectedEdges) {
  CommParams p;
  p.packet_loss_lambda = 1.0;
  const int n = 6;
  CommNetwork net(p, n, {}, 7);
  const std::vector<Vec2> pos(n, Vec2(0, 0));
  double lost = 0;
  const int steps = 5000;
  for (int t = 0; t < steps; ++t) {
    net.Update(t, pos);
    int edges = 0;
    for (int i = 0; i < n; ++i)
      edges += static_cast<int>(net.Neighbors(i).size());
    EXPECT_EQ(edges + static_cast<int>(net.Lost().size()), n * (n - 1));
    for (auto [i, j] :
         net.Lost()) {  // a lost edge is really gone, one way only
      const auto& nb = net.Neighbors(i);
      EXPECT_EQ(std::count(nb.begin(), nb.end(), j), 0);
    }
    lost += static_cast<double>(net.Lost().size());
  }
  EXPECT_NEAR(lost / steps, 1.0, 0.05);
}

TEST(CommTest, FailedRobotIsIsolatedForGood) {
  CommNetwork net({}, 3, {{1, 2}}, 1);
  const std::vector<Vec2> pos(3, Vec2(0, 0));
  net.Update(0, pos);
  net.Update(1, pos);
  EXPECT_TRUE(net.Active(1));
  EXPECT_EQ(net.Neighbors(0).size(), 2u);
  for (int t = 2; t < 5; ++t) {
    net.Update(t, pos);
    EXPECT_FALSE(net.Active(1));
    EXPECT_TRUE(net.Neighbors(1).empty());
    EXPECT_EQ(net.Neighbors(0), (std::vector<int>{2}));
    EXPECT_EQ(net.NumActive(), 2);
  }
}

// The full graph kept from step to step (no loss) is the one built anew:
// robots that move, failures at Update and between Updates (decisions on
// arrival) included, against a network made fresh for each step.
TEST(CommTest, AKeptFullGraphIsTheOneBuiltAnew) {
  const std::vector<RobotFailure> failures = {{3, 2}, {0, 5}};
  CommNetwork kept({}, 5, failures, 1);
  for (int t = 0; t < 8; ++t) {
    const std::vector<Vec2> pos(5, Vec2(t, 2 * t));
    kept.Update(t, pos);
    if (t == 4) kept.ApplyFailures(5);  // robot 0 fails between two steps
    CommNetwork fresh({}, 5, failures, 1);
    fresh.Update(t == 4 ? 5 : t, pos);
    EXPECT_EQ(kept.AllNeighbors(), fresh.AllNeighbors()) << "step " << t;
    EXPECT_EQ(kept.active(), fresh.active()) << "step " << t;
  }
  EXPECT_EQ(kept.Neighbors(1), (std::vector<int>{2, 4}));
}

// The graph's stamp changes with the graph and only then: a kept full
// graph keeps it, a failure (at an Update or between two) and every range
// graph or lossy graph change it.
TEST(CommTest, TheGraphStampChangesWithTheGraph) {
  const std::vector<Vec2> pos(4, Vec2(0, 0));
  CommNetwork full({}, 4, {{2, 3}}, 1);
  full.Update(0, pos);
  const std::uint64_t first = full.graph_stamp();
  EXPECT_NE(first, 0u);
  full.Update(1, pos);
  full.Update(2, pos);
  EXPECT_EQ(full.graph_stamp(), first);
  full.Update(3, pos);  // robot 2 fails
  const std::uint64_t failed = full.graph_stamp();
  EXPECT_NE(failed, first);
  full.Update(4, pos);
  EXPECT_EQ(full.graph_stamp(), failed);
  EXPECT_FALSE(full.ApplyFailures(5));  // nobody new
  EXPECT_EQ(full.graph_stamp(), failed);

  CommNetwork other({}, 4, {}, 1);
  other.Update(0, pos);
  EXPECT_NE(other.graph_stamp(), first);  // unique in the process
  EXPECT_NE(other.graph_stamp(), failed);

  CommParams range;
  range.mode = CommMode::kRange;
  range.range = 10.0;
  CommNetwork ranged(range, 4, {}, 1);
  ranged.Update(0, pos);
  const std::uint64_t before = ranged.graph_stamp();
  ranged.Update(1, pos);
  EXPECT_NE(ranged.graph_stamp(), before);
}

TEST(CommTest, SameSeedSameLosses) {
  CommParams p;
  p.packet_loss_lambda = 2.0;
  CommNetwork a(p, 5, {}, 3), b(p, 5, {}, 3);
  const std::vector<Vec2> pos(5, Vec2(0, 0));
  for (int t = 0; t < 50; ++t) {
    a.Update(t, pos);
    b.Update(t, pos);
    EXPECT_EQ(a.Lost(), b.Lost());
  }
}

// The range graph through the grid is the all-pairs rule, for ranges from
// below the spacing to beyond the spread of the robots.
TEST(CommTest, RangeGraphIsEveryPairInRange) {
  Rng rng(4);
  const int n = 300;
  std::vector<Vec2> pos;
  for (int i = 0; i < n; ++i)
    pos.emplace_back(rng.Uniform(0.0, 60.0), rng.Uniform(0.0, 40.0));
  pos[7] = pos[8];  // two robots at one point
  for (const double range : {0.01, 1.0, 4.0, 25.0, 500.0}) {
    CommParams p;
    p.mode = CommMode::kRange;
    p.range = range;
    CommNetwork net(p, n, {{3, 0}}, 1);  // robot 3 has failed
    net.Update(0, pos);
    for (int i = 0; i < n; ++i) {
      std::vector<int> want;
      for (int j = 0; j < n; ++j)
        if (i != 3 && j != 3 && j != i &&
            (pos[i] - pos[j]).squaredNorm() <= range * range)
          want.push_back(j);
      ASSERT_EQ(net.Neighbors(i), want) << "robot " << i << ", range " << range;
    }
  }
}

}  // namespace
}  // namespace aia
