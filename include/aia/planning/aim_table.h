// Where the sampling tree (planning/sampling_tree.h) plans each target to be
// seen: its aim (the predicted mean, or, for a static target searched in
// vain, the nearest point of its likely area not yet searched: SearchAim in
// search.h), the observation region around the aim (the lattice points
// that measure it there, with the precision r each gives) and the BFS field
// toward that region. A static target has one slot; a moving one a slot per
// span of depths (its predicted mean at the span's middle), made when first
// asked for. A static target's field is kept for the next solve on the same
// lattice and made again only when its observation region has changed (the
// field is a function of the region alone): Dec-SB solves for each robot
// each step, and its robots mostly aim at the same regions.
#ifndef AIA_PLANNING_AIM_TABLE_H_
#define AIA_PLANNING_AIM_TABLE_H_

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"
#include "aia/world/map.h"

namespace aia {

class AimTable {
 public:
  // For the targets of `belief`'s row `row` (`missed`: per static target,
  // the lattice points where it was predicted to be measured and was not;
  // may be shorter than the targets), over the lattice points the active
  // robots reach from their starts. The references are kept.
  void Reset(const Map& map, const SensorModel& sensor, const BeliefSet& belief,
             int row, const std::vector<std::vector<int>>& missed,
             const std::vector<int>& start,
             const std::vector<std::uint8_t>& active);

  // The predicted position mean of target k at `depth`.
  const Vec2& MeanAt(int depth, int k);
  // The BFS distance field toward target k's observation region as planned
  // at `depth` (-1 where it cannot be reached).
  const std::vector<int>& FieldAt(int depth, int k) {
    return SlotAt(depth, k).field;
  }
  // Where target k is planned to be measured at `depth`.
  Vec2 MeasurePoint(int depth, int k);
  // The observation region of the slot made last: (lattice point, r).
  const std::vector<std::pair<int, double>>& last_region() const {
    return region_;
  }

 private:
  struct Slot {
    bool ready = false;
    bool at_mean = true;  // the predicted mean itself (else `point`)
    Vec2 point{0.0, 0.0};
    std::vector<int> field;
    // What `field` was made from: the region's points, on lattice `made_on`.
    std::vector<int> sources;
    std::uint64_t made_on = 0;
  };
  Slot& SlotAt(int depth, int k);
  int Bucket(int depth, int k) const;
  bool FindAim(const Vec2& mean, const Eigen::Matrix2d& cov,
               const std::vector<int>* missed, Vec2* aim,
               std::vector<std::pair<int, double>>* region);
  void RegionOf(const Vec2& x, std::vector<std::pair<int, double>>* region);

  const Map* map_ = nullptr;
  const SensorModel* sensor_ = nullptr;
  const BeliefSet* belief_ = nullptr;
  int row_ = 0;
  const std::vector<std::vector<int>>* missed_ = nullptr;
  std::vector<std::uint8_t> is_static_;
  std::vector<const TargetModel*> models_;
  std::vector<std::vector<Vec2>> means_;    // [depth][k] position means
  std::vector<Eigen::VectorXd> full_mean_;  // mean propagation's state
  std::vector<std::vector<Slot>> slots_;    // [k][bucket]
  std::vector<int> reach_;  // BFS distance from the nearest active robot
  int buckets_ = 1;  // a moving target's spans (the last: every depth on)
  // Scratch.
  std::vector<std::pair<int, double>> region_, trial_region_;
  std::vector<int> bfs_queue_, sources_;
};

}  // namespace aia

#endif  // AIA_PLANNING_AIM_TABLE_H_
