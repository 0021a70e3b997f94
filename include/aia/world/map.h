// The map the robots know (the paper's environment T and its obstacles):
// the workspace, its obstacle boxes, the occupancy grid and the motion
// lattice, with the exact geometric queries planners need. It holds nothing
// about the targets or who will fail: that is the ground truth
// (world/world.h), which policies never see.
#ifndef AIA_WORLD_MAP_H_
#define AIA_WORLD_MAP_H_

#include <cstdint>
#include <vector>

#include "aia/core/box_buckets.h"
#include "aia/core/geometry.h"
#include "aia/core/grid.h"
#include "aia/core/types.h"
#include "aia/world/lattice.h"

namespace aia {

class Map {
 public:
  Map() = default;
  // The map of a workspace [0, size] with these obstacles (border walls are
  // implicit): occupancy cells of `cell` metres, lattice of `step` metres for
  // a robot disc of `robot_radius`.
  Map(const Vec2& size, std::vector<Box> obstacles, double cell, double step,
      double robot_radius);

  const Vec2& size() const { return size_; }
  const std::vector<Box>& obstacles() const { return obstacles_; }
  // 1 where a cell overlaps an obstacle.
  const Grid<std::uint8_t>& occupancy() const { return occupancy_; }
  const Lattice& lattice() const { return lattice_; }
  double robot_radius() const { return robot_radius_; }

  // Whether the segment a-b crosses no obstacle (what mj_ray sees, computed
  // exactly on the boxes; planners use this to predict measurements).
  bool LineOfSight(const Vec2& a, const Vec2& b) const;
  // Whether the point lies in no obstacle and inside the workspace.
  bool PointFree(const Vec2& p) const;

 private:
  Vec2 size_{20.0, 20.0};
  std::vector<Box> obstacles_;
  Grid<std::uint8_t> occupancy_;
  Lattice lattice_;
  double robot_radius_ = 0.15;
  // The boxes in 1 m buckets for LineOfSight and PointFree.
  BoxBuckets buckets_;
};

}  // namespace aia

#endif  // AIA_WORLD_MAP_H_
