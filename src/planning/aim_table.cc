#include "aia/planning/aim_table.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "aia/planning/information.h"
#include "aia/planning/search.h"
#include "aia/world/lattice.h"

namespace aia {
namespace {

// Moving targets' aims and fields are kept per span of this many depths (the
// predicted mean at the span's middle), for at most kMaxBuckets spans, the
// last of which takes every deeper depth; where the moving targets' fields
// would pass kMovingFieldBytes (a field is an int per lattice point), fewer
// spans, the near ones as they were (10 robots, 50 moving targets, 100 m:
// 512 MB of fields before).
constexpr int kBucket = 4;
constexpr int kMaxBuckets = 64;
constexpr double kMovingFieldBytes = 128.0 * (1 << 20);

}  // namespace

void AimTable::Reset(const Map& map, const SensorModel& sensor,
                     const BeliefSet& belief, int row,
                     const std::vector<std::vector<int>>& missed,
                     const std::vector<int>& start,
                     const std::vector<std::uint8_t>& active) {
  map_ = &map;
  sensor_ = &sensor;
  belief_ = &belief;
  row_ = row;
  missed_ = &missed;
  const BeliefLayout& layout = belief.layout();
  const int m = layout.num_targets();
  is_static_.assign(m, 1);
  models_.assign(m, nullptr);
  full_mean_.assign(m, {});
  means_.assign(1, std::vector<Vec2>(m));
  int moving = 0;
  for (int k = 0; k < m; ++k) moving += layout.is_static(k) ? 0 : 1;
  const double field_bytes =
      static_cast<double>(map.lattice().size()) * sizeof(int);
  buckets_ = kMaxBuckets;
  if (moving > 0 && moving * field_bytes * kMaxBuckets > kMovingFieldBytes)
    buckets_ = std::max(
        1, static_cast<int>(kMovingFieldBytes / (moving * field_bytes)));
  slots_.resize(m);
  for (int k = 0; k < m; ++k) {
    is_static_[k] = layout.is_static(k) ? 1 : 0;
    models_[k] = &layout.model(k);
    full_mean_[k] = belief.Mean(row, k);
    means_[0][k] = full_mean_[k].head<2>();
    // A static target's slot keeps its field for SlotAt to reuse; a moving
    // target's aims move with it, so its fields are made anew.
    if (is_static_[k] && slots_[k].size() == 1) {
      slots_[k][0].ready = false;
    } else {
      slots_[k].assign(is_static_[k] ? 1 : buckets_, Slot{});
    }
  }
  // What the active robots can reach.
  std::vector<int> sources;
  for (std::size_t i = 0; i < start.size(); ++i)
    if (active[i]) sources.push_back(start[i]);
  BfsDistances(map.lattice(), sources.data(), static_cast<int>(sources.size()),
               &reach_, &bfs_queue_);
}

const Vec2& AimTable::MeanAt(int depth, int k) {
  while (static_cast<int>(means_.size()) <= depth) {
    const int m = static_cast<int>(models_.size());
    std::vector<Vec2> next(m);
    for (int j = 0; j < m; ++j) {
      if (!is_static_[j])
        full_mean_[j] = models_[j]->A * full_mean_[j] + models_[j]->b;
      next[j] = full_mean_[j].head<2>();
    }
    means_.push_back(std::move(next));
  }
  return means_[depth][k];
}

int AimTable::Bucket(int depth, int k) const {
  if (is_static_[k]) return 0;
  return std::min(depth / kBucket, buckets_ - 1);
}

void AimTable::RegionOf(const Vec2& x,
                        std::vector<std::pair<int, double>>* region) {
  const Lattice& lattice = map_->lattice();
  region->clear();
  ForEachInWindow(lattice, lattice.NearestPoint(x),
                  SensorSpan(lattice, *sensor_), [&](int q, int, int) {
                    if (!lattice.Free(q) || reach_[q] < 0) return;
                    const double r = PredictedPrecision(*map_, *sensor_,
                                                        lattice.Point(q), x);
                    if (r > 0.0) region->push_back({q, r});
                  });
}

bool AimTable::FindAim(const Vec2& mean, const Eigen::Matrix2d& cov,
                       const std::vector<int>* missed, Vec2* aim,
                       std::vector<std::pair<int, double>>* region) {
  // Among candidates of one ring, the one whose region is nearest to a robot.
  const bool found = SearchAim(
      *map_, *sensor_, mean, cov, missed,
      [&](const Vec2& x, int /*bound*/) {
        RegionOf(x, &trial_region_);
        if (trial_region_.empty()) return -1;
        int near = std::numeric_limits<int>::max();
        for (const auto& [q, r] : trial_region_)
          near = std::min(near, reach_[q]);
        return near;
      },
      aim);
  if (found) {
    RegionOf(*aim, region);
  } else {
    region->clear();
  }
  return found;
}

AimTable::Slot& AimTable::SlotAt(int depth, int k) {
  Slot& slot = slots_[k][Bucket(depth, k)];
  if (slot.ready) return slot;
  const int b = Bucket(depth, k);
  const Vec2 mean =
      is_static_[k] ? means_[0][k] : MeanAt(b * kBucket + kBucket / 2, k);
  const Eigen::MatrixXd sigma =
      belief_->Covariance(row_, k).topLeftCorner(2, 2);
  const std::vector<int>* missed =
      (is_static_[k] && static_cast<int>(missed_->size()) > k) ? &(*missed_)[k]
                                                               : nullptr;
  FindAim(mean, Eigen::Matrix2d(sigma), missed, &slot.point, &region_);
  slot.at_mean = !is_static_[k] && slot.point == mean;
  sources_.clear();
  for (const auto& [q, r] : region_) sources_.push_back(q);
  const Lattice& lattice = map_->lattice();
  if (slot.made_on != lattice.id() || slot.sources != sources_) {
    slot.sources.swap(sources_);  // sources_ is scratch
    slot.made_on = lattice.id();
    BfsDistances(lattice, slot.sources.data(),
                 static_cast<int>(slot.sources.size()), &slot.field,
                 &bfs_queue_);
  }
  slot.ready = true;
  return slot;
}

Vec2 AimTable::MeasurePoint(int depth, int k) {
  const Slot& slot = SlotAt(depth, k);
  return slot.at_mean ? MeanAt(depth, k) : slot.point;
}

}  // namespace aia
