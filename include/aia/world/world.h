// One mission instance built from a scenario: obstacles (random, explicit and
// map-made, all as boxes), the occupancy grid, the motion lattice, robot
// starts, true targets and their priors, and resolved robot failures. Every
// random choice is drawn from named streams of the scenario seed.
#ifndef AIA_WORLD_WORLD_H_
#define AIA_WORLD_WORLD_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "aia/core/geometry.h"
#include "aia/core/grid.h"
#include "aia/scenario/config.h"
#include "aia/world/lattice.h"

namespace aia {

struct TargetInstance {
  Eigen::VectorXd
      x0;  // true initial state (position, or position and velocity)
  Eigen::VectorXd prior_mean;  // mu_0
  Eigen::MatrixXd prior_cov;   // Sigma_0
  DynamicsConfig dynamics;
  Vec2 Position() const { return x0.head<2>(); }
};

// Robots, targets and obstacle boxes together, at most (MuJoCo's memory for
// its broad phase grows with the square of this).
inline constexpr int kMaxBodies = 5000;

struct RobotFailure {
  int robot = 0;
  int step = 0;
};

class World {
 public:
  // Builds and validates the instance; throws InputError (with the scenario's
  // file and line) for starts or targets in obstacles, too many robots, an
  // unreadable map, and similar.
  static World Build(const Scenario& scenario);

  Vec2 size{20.0, 20.0};
  std::vector<Box>
      obstacles;  // inside the workspace; border walls are implicit
  Grid<std::uint8_t> occupancy;  // 1 where a cell overlaps an obstacle
  Lattice lattice;
  double robot_radius = 0.15;
  std::vector<int> robot_starts;  // lattice indices
  std::vector<TargetInstance> targets;
  std::vector<RobotFailure> failures;

  int NumRobots() const { return static_cast<int>(robot_starts.size()); }
  int NumTargets() const { return static_cast<int>(targets.size()); }

  // Whether the segment a-b crosses no obstacle (what mj_ray sees, computed
  // exactly on the boxes; planners use this to predict measurements).
  bool LineOfSight(const Vec2& a, const Vec2& b) const;
  // Whether the point lies in no obstacle and inside the workspace.
  bool PointFree(const Vec2& p) const;

 private:
  // Boxes bucketed on a coarse grid for LineOfSight.
  void BuildIndex();
  double bucket_ = 1.0;
  int bx_ = 0, by_ = 0;
  std::vector<std::vector<int>> buckets_;
};

// Merges the dark pixels of a grayscale image into axis-aligned boxes scaled
// to the workspace (row 0 of the image is the top, y = size.y()). Pixels
// darker than threshold * 255 are occupied.
std::vector<Box> BoxesFromImage(const std::vector<std::uint8_t>& gray, int cols,
                                int rows, const Vec2& size, double threshold);

}  // namespace aia

#endif  // AIA_WORLD_WORLD_H_
