// One mission instance built from a scenario, split by who may know what:
// the map (world/map.h) and the targets' priors and models are what the
// robots know; the ground truth (the targets' true states, which robot fails
// when) is seen only by the episode that simulates it, the scoring and the
// video. Every random choice is drawn from named streams of the scenario
// seed.
#ifndef AIA_WORLD_WORLD_H_
#define AIA_WORLD_WORLD_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/core/geometry.h"
#include "aia/estimation/target_model.h"
#include "aia/scenario/config.h"
#include "aia/world/map.h"

namespace aia {

// What the robots know of a target before the mission: its model and the
// prior N(mean, cov) of its state.
struct TargetPrior {
  TargetModel model;
  Eigen::VectorXd mean;  // mu_0
  Eigen::MatrixXd cov;   // Sigma_0
};

// What only the simulation knows.
struct GroundTruth {
  // True initial state of each target (position, or position and velocity).
  std::vector<Eigen::VectorXd> targets;
  // Resolved failures: every robot index given.
  std::vector<RobotFailure> failures;
};

// Robots, targets and obstacle boxes together, at most (MuJoCo's memory for
// its broad phase grows with the square of this).
inline constexpr int kMaxBodies = 5000;

struct World {
  // Builds and validates the instance; throws InputError (with the
  // scenario's file and line) for starts or targets in obstacles, too many
  // robots, an unreadable map, and similar.
  static World Build(const Scenario& scenario);

  Map map;
  std::vector<int> robot_starts;  // lattice indices
  std::vector<TargetPrior> priors;
  GroundTruth truth;

  int NumRobots() const { return static_cast<int>(robot_starts.size()); }
  int NumTargets() const { return static_cast<int>(priors.size()); }
  // The true initial position of target k.
  Vec2 TargetStart(int k) const { return truth.targets[k].head<2>(); }
};

// Merges the dark pixels of a grayscale image into axis-aligned boxes scaled
// to the workspace (row 0 of the image is the top, y = size.y()). Pixels
// darker than threshold * 255 are occupied.
std::vector<Box> BoxesFromImage(const std::vector<std::uint8_t>& gray, int cols,
                                int rows, const Vec2& size, double threshold);

}  // namespace aia

#endif  // AIA_WORLD_WORLD_H_
