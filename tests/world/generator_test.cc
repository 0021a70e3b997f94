// Generated worlds (workspace.obstacles.generator): the same seed gives the
// same boxes, other seeds other boxes; the free space is connected for the
// robots on the lattice, for every type over many seeds, workspace sizes and
// parameters; maze walls really stand in the way; too many boxes, and the
// world's placement of random starts and targets.
#include "aia/world/generator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/world/lattice.h"
#include "aia/world/world.h"
#include "support/test_support.h"

namespace aia {
namespace {

using testing::ScenarioFromYaml;

const char* const kTypes[] = {"maze", "rooms", "corridors", "cave"};

// A scenario of `robots` robots and targets in a W x H workspace whose
// generator is `{type: TYPE, PARAMS}`.
Scenario Generated(const std::string& type, double w, double h,
                   std::uint64_t seed, const std::string& params = "",
                   const std::string& robots = "{count: 10}",
                   int targets = 10) {
  return ScenarioFromYaml(
      "seed: " + std::to_string(seed) + "\nworkspace:\n  size: [" +
      std::to_string(w) + ", " + std::to_string(h) +
      "]\n  obstacles:\n    generator: {type: " + type +
      (params.empty() ? "" : ", " + params) + "}\nrobots: " + robots +
      "\ntargets: {count: " + std::to_string(targets) + "}\n");
}

// Lattice points reached from the first free point by valid moves, by a
// breadth-first search of the test's own.
int Reached(const Lattice& lattice) {
  std::vector<int> seen(lattice.size(), 0), queue;
  for (int idx = 0; idx < lattice.size() && queue.empty(); ++idx)
    if (lattice.Free(idx)) queue.push_back(idx), seen[idx] = 1;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    for (Move m : kMoves) {
      const int next = lattice.Next(queue[head], m);
      if (next >= 0 && !seen[next]) seen[next] = 1, queue.push_back(next);
    }
  }
  return static_cast<int>(queue.size());
}

bool SameBoxes(const std::vector<Box>& a, const std::vector<Box>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].lo != b[i].lo || a[i].hi != b[i].hi) return false;
  return true;
}

TEST(GeneratorTest, SameSeedSameBoxesBitForBit) {
  for (const std::string type : kTypes) {
    SCOPED_TRACE(type);
    const Scenario s = Generated(type, 30, 30, 17);
    const GeneratedObstacles a = GenerateObstacles(s);
    const GeneratedObstacles b = GenerateObstacles(s);
    EXPECT_GT(a.boxes.size(), 10u);
    EXPECT_TRUE(SameBoxes(a.boxes, b.boxes));
    EXPECT_EQ(a.free_points, b.free_points);
    // The world holds exactly these boxes.
    EXPECT_TRUE(SameBoxes(World::Build(s).map.obstacles(), a.boxes));
  }
}

TEST(GeneratorTest, DifferentSeedsGiveDifferentWorlds) {
  for (const std::string type : kTypes) {
    SCOPED_TRACE(type);
    std::vector<std::vector<Box>> worlds;
    for (std::uint64_t seed = 0; seed < 8; ++seed)
      worlds.push_back(GenerateObstacles(Generated(type, 20, 20, seed)).boxes);
    for (std::size_t i = 0; i < worlds.size(); ++i)
      for (std::size_t j = i + 1; j < worlds.size(); ++j)
        EXPECT_FALSE(SameBoxes(worlds[i], worlds[j])) << i << " vs " << j;
  }
}

TEST(GeneratorTest, BoxesStayInsideTheWorkspace) {
  for (const std::string type : kTypes) {
    const Scenario s = Generated(type, 23.3, 17.8, 5);
    for (const Box& b : GenerateObstacles(s).boxes) {
      EXPECT_GE(b.lo.x(), 0.0) << type;
      EXPECT_GE(b.lo.y(), 0.0) << type;
      EXPECT_LE(b.hi.x(), 23.3) << type;
      EXPECT_LE(b.hi.y(), 17.8) << type;
      EXPECT_LT(b.lo.x(), b.hi.x()) << type;
      EXPECT_LT(b.lo.y(), b.hi.y()) << type;
    }
  }
}

// Every free lattice point reaches every other: the world's own check
// passes (World::Build) and a search of the test's own agrees, for every
// type, seeds, sizes from 10 to 60 m (square or not, multiples of the step
// or not), and parameters from narrow to wide.
TEST(GeneratorTest, FreeSpaceIsConnectedForTheRobots) {
  // Narrow parameters make many boxes: those stop at 40 m.
  struct Case {
    std::string type, params, robots = "{count: 10}";
    bool narrow = false;
  };
  const std::vector<Case> cases = {
      {"maze", ""},
      {"maze", "corridor: 0.5, loops: 0", "{count: 10}", true},
      {"maze", "corridor: 3.3, loops: 0.5, wall: 0.19"},
      {"maze", "corridor: 1.2", "{count: 10, step: 0.4, radius: 0.1}"},
      {"rooms", ""},
      {"rooms", "room_size: [1, 2], door: 0.5", "{count: 10}", true},
      {"rooms", "room_size: [4, 12], door: 2.5, wall: 0.02"},
      {"rooms", "", "{count: 10, step: 1.0, radius: 0.3}"},
      {"corridors", ""},
      {"corridors", "corridor: 0.5, room_size: [1, 2], door: 0.5",
       "{count: 10}", true},
      {"corridors", "corridor: 3, room_size: [3, 10], door: 2"},
      {"corridors", "", "{count: 10, step: 0.4, radius: 0.12}"},
      {"cave", ""},
      {"cave", "cell: 0.5, fill: 0.45, smoothing: 2", "{count: 10}", true},
      {"cave", "cell: 1.6, fill: 0.35, smoothing: 6"},
      {"cave", "cell: 1.0, fill: 0.4"},
      {"cave", "fill: 0.35, smoothing: 0", "{count: 10}", true},
      {"cave", "", "{count: 10, step: 1.0, radius: 0.3}"},
  };
  const std::vector<std::pair<double, double>> sizes = {
      {10, 10}, {20, 20}, {17.3, 26.1}, {40, 12}, {40, 40}, {60, 60}};
  for (const Case& c : cases) {
    for (const auto& [w, h] : sizes) {
      if (c.narrow && w * h > 40 * 40) continue;
      // Rooms of up to 12 m in 10 x 10 m: one room and no wall, refused.
      if (c.params.find("room_size: [4, 12]") != std::string::npos && w <= 12 &&
          h <= 12) {
        EXPECT_THROW(Generated(c.type, w, h, 0, c.params, c.robots, 3),
                     InputError);
        continue;
      }
      for (std::uint64_t seed = 0; seed < 6; ++seed) {
        SCOPED_TRACE(c.type + " {" + c.params + "} " + c.robots + " in " +
                     std::to_string(w) + " x " + std::to_string(h) + ", seed " +
                     std::to_string(seed));
        const Scenario s = Generated(c.type, w, h, seed, c.params, c.robots, 3);
        const GeneratedObstacles g = GenerateObstacles(s);
        const World world = World::Build(s);
        const Lattice& lattice = world.map.lattice();
        EXPECT_EQ(lattice.NumFree(), g.free_points);
        EXPECT_EQ(lattice.NumComponents(), 1);
        EXPECT_EQ(Reached(lattice), lattice.NumFree());
        // Thin walls leave every point free.
        if (c.type != "cave") EXPECT_EQ(lattice.NumFree(), lattice.size());
      }
    }
  }
}

// The default cave keeps most of the workspace open once its small parts
// are filled.
TEST(GeneratorTest, DefaultCaveKeepsMostOfTheWorkspaceOpen) {
  for (const double side : {20.0, 30.0, 60.0}) {
    for (std::uint64_t seed = 0; seed < 20; ++seed) {
      const Scenario s = Generated("cave", side, side, seed);
      const double share =
          GenerateObstacles(s).free_points / std::pow(side / 0.5, 2);
      EXPECT_GT(share, 0.45) << side << " m, seed " << seed;
    }
  }
}

// Walls stand in the way: in a maze some points are far apart by moves and
// close by a straight line; in rooms some neighbouring points are split by
// a wall.
TEST(GeneratorTest, MazeWallsMakeDetours) {
  for (std::uint64_t seed = 0; seed < 5; ++seed) {
    const World w = World::Build(Generated("maze", 20, 20, seed));
    const Lattice& lattice = w.map.lattice();
    std::vector<int> dist, queue;
    // Path length over straight-line distance, the largest among pairs at
    // least 2 m apart (from every fifth point in each direction).
    double worst = 0.0;
    for (int sy = 0; sy < lattice.ny(); sy += 5) {
      for (int sx = 0; sx < lattice.nx(); sx += 5) {
        const int source = lattice.Index(sx, sy);
        BfsDistances(lattice, &source, 1, &dist, &queue);
        for (int idx = 0; idx < lattice.size(); ++idx) {
          const double straight =
              (lattice.Point(idx) - lattice.Point(source)).norm();
          ASSERT_GE(dist[idx], 0);
          if (straight >= 2.0)
            worst = std::max(worst, dist[idx] * lattice.step() / straight);
        }
      }
    }
    EXPECT_GT(worst, 8.0) << "seed " << seed;
  }
  for (const std::string type : {"rooms", "corridors"}) {
    const World w = World::Build(Generated(type, 20, 20, 3));
    const Lattice& lattice = w.map.lattice();
    int blocked = 0;
    for (int idx = 0; idx < lattice.size(); ++idx)
      blocked += 4 - lattice.NumValidMoves(idx);
    // Far more than the border's 4 * 40 blocked moves.
    EXPECT_GT(blocked, 400) << type;
  }
}

TEST(GeneratorTest, RandomStartsAndTargetsLandInFreeSpace) {
  for (const std::string type : kTypes) {
    for (std::uint64_t seed = 0; seed < 4; ++seed) {
      SCOPED_TRACE(type + ", seed " + std::to_string(seed));
      const World w =
          World::Build(Generated(type, 30, 30, seed, "", "{count: 20}", 20));
      const Lattice& lattice = w.map.lattice();
      std::set<int> starts(w.robot_starts.begin(), w.robot_starts.end());
      EXPECT_EQ(starts.size(), 20u);
      for (int idx : w.robot_starts) EXPECT_TRUE(lattice.Free(idx));
      for (int k = 0; k < w.NumTargets(); ++k) {
        EXPECT_TRUE(w.map.PointFree(w.TargetStart(k)));
        EXPECT_TRUE(w.map.PointFree(w.priors[k].mean.head<2>()));
      }
    }
  }
}

TEST(GeneratorTest, TooManyBoxesIsAnErrorAtTheGenerator) {
  // One-step passages in 100 x 100 m: tens of thousands of wall pieces.
  try {
    World::Build(Generated("maze", 100, 100, 1, "corridor: 0.5"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "workspace.obstacles.generator");
    EXPECT_NE(e.message().find("passes the 5000 bodies"), std::string::npos)
        << e.message();
  }
  // A small maze, but the robots and targets use up the budget.
  try {
    World::Build(Generated("maze", 60, 60, 1, "", "{count: 4000}", 990));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "workspace.obstacles.generator");
    EXPECT_NE(e.message().find("more than 10 obstacle boxes"),
              std::string::npos)
        << e.message();
  }
}

TEST(GeneratorTest, ParametersThatCannotGiveAPassableWorldAreRefused) {
  const auto error = [](const std::string& type, const std::string& params,
                        const std::string& robots = "{count: 2}") {
    try {
      Generated(type, 20, 20, 0, params, robots);
    } catch (const InputError& e) {
      return e.key() + ": " + e.message();
    }
    return std::string("no error");
  };
  EXPECT_NE(error("rooms", "door: 0.2").find("door: is narrower than a robot"),
            std::string::npos);
  EXPECT_NE(error("corridors", "door: 0.45")
                .find("door: is narrower than one lattice step"),
            std::string::npos);
  EXPECT_NE(error("maze", "corridor: 0.3")
                .find("corridor: is narrower than one lattice step"),
            std::string::npos);
  EXPECT_NE(error("maze", "wall: 0.2")
                .find("wall: must be less than robots.step - 2 robots.radius"),
            std::string::npos);
  EXPECT_NE(error("rooms", "", "{count: 2, radius: 0.21}")
                .find("wall: must be less than"),
            std::string::npos);
  // A cave cell is a resolution, not a width: at least one step.
  EXPECT_EQ(error("cave", "cell: 0.3"), "no error");
  // Parameters of other types are not checked against the robots.
  EXPECT_EQ(error("cave", "door: 0.2, corridor: 0.1, wall: 3"), "no error");
  EXPECT_EQ(error("maze", "cell: 0.1, room_size: [5, 6]"), "no error");
}

TEST(GeneratorTest, CaveWithoutOpenSpaceIsAnError) {
  try {
    World::Build(Generated("cave", 20, 20, 0, "fill: 1"));
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "workspace.obstacles.generator");
    EXPECT_NE(e.message().find("no open cell"), std::string::npos);
  }
}

}  // namespace
}  // namespace aia
