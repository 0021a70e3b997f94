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
#include <limits>
#include <string>
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

// Robots, targets and obstacle boxes together, at most.
inline constexpr int kMaxBodies = limits::kMaxBodies;

struct World {
  // Builds and validates the instance; throws InputError (with the
  // scenario's file and line) for starts or targets in obstacles, too many
  // robots, an unreadable map, and similar.
  static World Build(const Scenario& scenario);

  Map map;
  std::vector<int> robot_starts;  // lattice indices
  // Radians from +x, counter-clockwise (0 for point robots).
  std::vector<double> robot_headings;
  std::vector<TargetPrior> priors;
  GroundTruth truth;

  int NumRobots() const { return static_cast<int>(robot_starts.size()); }
  int NumTargets() const { return static_cast<int>(priors.size()); }
  // The true initial position of target k.
  Vec2 TargetStart(int k) const { return truth.targets[k].head<2>(); }
};

// A decoded grayscale map image, row-major, row 0 at the top.
struct GrayImage {
  int cols = 0, rows = 0;
  std::vector<std::uint8_t> pixels;
};

// Map images larger than this many pixels (4096 x 4096) are refused before
// they are decoded.
inline constexpr long kMaxMapPixels = 1L << 24;

// Decodes PGM (P2, P5) or PNG bytes. Checks the header's size first (at most
// kMaxMapPixels, as the header declares it) and throws std::invalid_argument
// with a one-line reason for anything else; decoder messages never leak.
GrayImage DecodeMapImage(const std::string& bytes);

// Merges the dark pixels of a grayscale image into axis-aligned boxes scaled
// to the workspace (row 0 of the image is the top, y = size.y()). Pixels
// darker than threshold * 255 are occupied. Linear in the pixels. Stops
// early, returning more than `max_boxes` boxes, once the image is known to
// make more than that many.
std::vector<Box> BoxesFromImage(
    const std::vector<std::uint8_t>& gray, int cols, int rows, const Vec2& size,
    double threshold,
    std::size_t max_boxes = std::numeric_limits<std::size_t>::max());

}  // namespace aia

#endif  // AIA_WORLD_WORLD_H_
