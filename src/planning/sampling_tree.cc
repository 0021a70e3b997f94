#include "aia/planning/sampling_tree.h"

#include <sys/mman.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <functional>
#include <limits>
#include <mutex>
#include <new>
#include <type_traits>

#include "aia/core/check.h"
#include "aia/estimation/filter.h"
#include "aia/planning/information.h"
#include "aia/planning/search.h"
#include "aia/world/lattice.h"

namespace aia {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

int PackedSize(int dim) { return dim * (dim + 1) / 2; }

// Packed upper triangle, row by row.
template <int D>
void Pack(const Eigen::Matrix<double, D, D>& m, double* out) {
  int c = 0;
  for (int i = 0; i < D; ++i)
    for (int j = i; j < D; ++j) out[c++] = m(i, j);
}

template <int D>
Eigen::Matrix<double, D, D> Unpack(const double* in) {
  Eigen::Matrix<double, D, D> m;
  int c = 0;
  for (int i = 0; i < D; ++i)
    for (int j = i; j < D; ++j) m(i, j) = m(j, i) = in[c++];
  return m;
}

// Adds r to the position diagonal of a packed block (indices of (0,0) and
// (1,1) in the packed upper triangle: 0 and dim).
inline void AddPositionPrecision(double* block, int dim, double r) {
  block[0] += r;
  block[dim] += r;
}

}  // namespace

Move MoveBetween(const Lattice& lattice, int a, int b) {
  for (Move m : kMoves)
    if (lattice.Next(a, m) == b) return m;
  return Move::kStay;
}

namespace {

// det Sigma of one packed information block.
double PackedDet(const double* p, int dim) {
  if (dim == 2) return 1.0 / (p[0] * p[2] - p[1] * p[1]);
  return 1.0 / Unpack<4>(p).determinant();
}

}  // namespace

double SamplingTree::BlockDet(const double* packed, int k) const {
  return PackedDet(packed + targets_[k].offset, targets_[k].dim);
}

double SamplingTree::BlockDetAfter(const double* packed, int k,
                                   double r) const {
  const TargetInfo& t = targets_[k];
  double block[10];  // the largest packed block, 4 x 4
  std::copy(packed + t.offset, packed + t.offset + PackedSize(t.dim), block);
  AddPositionPrecision(block, t.dim, r);
  return PackedDet(block, t.dim);
}

// Moving targets' aims and fields are kept per span of this many depths (the
// predicted mean at the span's middle), for at most kMaxBuckets spans.
constexpr int kBucket = 4;
// What a node keeps resident: its rows of the arena (reserved, so not
// grown by copies) and its entries in levels_ and goals_ (std::vectors,
// counted twice for their growth).
double ResidentNodeBytes(int n, int stride) {
  return 4.0 * n + 8.0 * stride + 36.0 + 16.0;
}

// Solves whose arena stays below this take no part of the budget (the
// ordinary ones: Dec-SB's 300 iterations, the expert's default budget on
// small teams); their memory is kept for the next solve.
constexpr double kSmallTreeBytes = 32.0 * (1 << 20);

// The process's budget of tree memory, kMaxTreeBytes for all the large
// solves running at once. A solve takes all it may need before it starts
// and holds nothing else meanwhile, and one solve never needs more than the
// whole budget, so waiting cannot deadlock.
class TreeMemory {
 public:
  static TreeMemory& Get() {
    static TreeMemory memory;
    return memory;
  }
  void Take(double bytes) {
    std::unique_lock<std::mutex> lock(mu_);
    ready_.wait(lock, [&] { return free_ >= bytes; });
    free_ -= bytes;
  }
  void Give(double bytes) {
    {
      const std::lock_guard<std::mutex> lock(mu_);
      free_ += bytes;
    }
    ready_.notify_all();
  }

 private:
  std::mutex mu_;
  std::condition_variable ready_;
  double free_ = kMaxTreeBytes;
};

class TreeMemoryLease {
 public:
  explicit TreeMemoryLease(double bytes)
      : bytes_(bytes > kSmallTreeBytes ? std::min(bytes, kMaxTreeBytes) : 0.0) {
    if (bytes_ > 0.0) TreeMemory::Get().Take(bytes_);
  }
  ~TreeMemoryLease() {
    if (bytes_ > 0.0) TreeMemory::Get().Give(bytes_);
  }
  TreeMemoryLease(const TreeMemoryLease&) = delete;
  TreeMemoryLease& operator=(const TreeMemoryLease&) = delete;
  bool large() const { return bytes_ > 0.0; }

 private:
  double bytes_;
};

// Blocks from this size on are mapped (ArenaAllocator).
constexpr std::size_t kMappedBytes = std::size_t{1} << 20;

constexpr int kMaxBuckets = 64;

// Below these sizes the spatial indexes are not worth their upkeep: a linear
// scan of the open targets, of the robots. Either way the result is the
// same.
constexpr int kLinearTargets = 32;
constexpr int kLinearRobots = 32;

// The tours' legs are the tree's own fields, walked.
class SamplingTree::Legs : public LegOracle {
 public:
  explicit Legs(SamplingTree* tree) : tree_(tree) {}
  Leg Compute(int from, int t, int k) override {
    return tree_->ComputeLeg(from, t, k);
  }
  bool TimeVarying(int k) const override {
    return !tree_->targets_[k].is_static;
  }
  int Distance(int from, int k) override { return tree_->FieldAt(0, k)[from]; }

 private:
  SamplingTree* tree_;
};

const Vec2& SamplingTree::MeanAt(int depth, int k) {
  while (static_cast<int>(means_.size()) <= depth) {
    std::vector<Vec2> next(m_);
    for (int j = 0; j < m_; ++j) {
      if (!targets_[j].is_static)
        full_mean_[j] = models_[j]->A * full_mean_[j] + models_[j]->b;
      next[j] = full_mean_[j].head<2>();
    }
    means_.push_back(std::move(next));
  }
  return means_[depth][k];
}

int SamplingTree::Bucket(int depth, int k) const {
  if (targets_[k].is_static) return 0;
  return std::min(depth / kBucket, kMaxBuckets - 1);
}

void SamplingTree::RegionOf(const Vec2& x,
                            std::vector<std::pair<int, double>>* region) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  const int span =
      static_cast<int>(std::ceil(p.sensor->range / lattice.step())) + 1;
  region->clear();
  const int c = lattice.NearestPoint(x);
  for (int iy = std::max(0, lattice.Iy(c) - span);
       iy <= std::min(lattice.ny() - 1, lattice.Iy(c) + span); ++iy) {
    for (int ix = std::max(0, lattice.Ix(c) - span);
         ix <= std::min(lattice.nx() - 1, lattice.Ix(c) + span); ++ix) {
      const int q = lattice.Index(ix, iy);
      if (!lattice.Free(q) || reach_[q] < 0) continue;
      const double r =
          PredictedPrecision(*p.map, *p.sensor, lattice.Point(q), x);
      if (r > 0.0) region->push_back({q, r});
    }
  }
}

bool SamplingTree::FindAim(const Vec2& mean, const Eigen::Matrix2d& cov,
                           const std::vector<int>* missed, Vec2* aim,
                           std::vector<std::pair<int, double>>* region) {
  // Among candidates of one ring, the one whose region is nearest to a robot.
  const SamplingProblem& p = *problem_;
  const bool found = SearchAim(
      *p.map, *p.sensor, mean, cov, missed,
      [&](const Vec2& x) {
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

SamplingTree::AimSlot& SamplingTree::Slot(int depth, int k) {
  AimSlot& slot = slots_[k][Bucket(depth, k)];
  if (slot.ready) return slot;
  const SamplingProblem& p = *problem_;
  const int b = Bucket(depth, k);
  const Vec2 mean = targets_[k].is_static
                        ? means_[0][k]
                        : MeanAt(b * kBucket + kBucket / 2, k);
  const Eigen::MatrixXd sigma =
      p.belief->Covariance(p.belief_row, k).topLeftCorner(2, 2);
  const std::vector<int>* missed =
      (targets_[k].is_static && static_cast<int>(p.missed.size()) > k)
          ? &p.missed[k]
          : nullptr;
  FindAim(mean, Eigen::Matrix2d(sigma), missed, &slot.point, &region_);
  slot.at_mean = !targets_[k].is_static && slot.point == mean;
  std::vector<int> sources;
  sources.reserve(region_.size());
  for (const auto& [q, r] : region_) sources.push_back(q);
  BfsDistances(p.map->lattice(), sources.data(),
               static_cast<int>(sources.size()), &slot.field, &bfs_queue_);
  slot.ready = true;
  return slot;
}

Vec2 SamplingTree::MeasurePoint(int depth, int k) {
  const AimSlot& slot = Slot(depth, k);
  return slot.at_mean ? MeanAt(depth, k) : slot.point;
}

void SamplingTree::Prepare(const SamplingProblem& p) {
  problem_ = &p;
  const BeliefSet& belief = *p.belief;
  const BeliefLayout& layout = belief.layout();
  const Lattice& lattice = p.map->lattice();
  n_ = static_cast<int>(p.start.size());
  m_ = layout.num_targets();
  targets_.assign(m_, {});
  models_.assign(m_, nullptr);
  full_mean_.assign(m_, {});
  stride_ = 0;
  any_moving_ = false;
  means_.assign(1, std::vector<Vec2>(m_));
  for (int k = 0; k < m_; ++k) {
    const TargetModel& model = layout.model(k);
    targets_[k] = {layout.dim(k), stride_, layout.is_static(k)};
    stride_ += PackedSize(layout.dim(k));
    models_[k] = &model;
    full_mean_[k] = belief.Mean(p.belief_row, k);
    means_[0][k] = full_mean_[k].head<2>();
    any_moving_ = any_moving_ || !layout.is_static(k);
  }
  // What the active robots can reach.
  std::vector<int> sources;
  for (int i = 0; i < n_; ++i)
    if (p.active[i]) sources.push_back(p.start[i]);
  BfsDistances(lattice, sources.data(), static_cast<int>(sources.size()),
               &reach_, &bfs_queue_);
  // Aims, observation regions and fields of the static targets now; moving
  // targets' per span of depths, when first asked for.
  slots_.assign(m_, {});
  std::vector<std::vector<std::pair<int, double>>> per_point(lattice.size());
  region_box_.assign(m_, Rect{});
  static_field_.assign(m_, nullptr);
  for (int k = 0; k < m_; ++k) {
    slots_[k].assign(targets_[k].is_static ? 1 : kMaxBuckets, AimSlot{});
    if (!targets_[k].is_static) continue;
    static_field_[k] = Slot(0, k).field.data();
    Rect& box = region_box_[k];
    for (const auto& [q, r] : region_) {
      per_point[q].push_back({k, r});
      const int x = lattice.Ix(q), y = lattice.Iy(q);
      if (box.x0 > box.x1) {
        box = {x, x, y, y};
      } else {
        box = {std::min(box.x0, x), std::max(box.x1, x), std::min(box.y0, y),
               std::max(box.y1, y)};
      }
    }
  }
  indexed_ = !any_moving_ && use_index_;
  pad_ = 0;
  for (const Rect& b : region_box_) {
    if (b.x0 > b.x1) continue;
    const int cx = (b.x0 + b.x1) / 2, cy = (b.y0 + b.y1) / 2;
    pad_ = std::max({pad_, cx - b.x0, b.x1 - cx, cy - b.y0, b.y1 - cy});
  }
  obs_begin_.assign(lattice.size() + 1, 0);
  obs_.clear();
  for (int q = 0; q < lattice.size(); ++q) {
    obs_begin_[q] = static_cast<int>(obs_.size());
    obs_.insert(obs_.end(), per_point[q].begin(), per_point[q].end());
  }
  obs_begin_[lattice.size()] = static_cast<int>(obs_.size());

  pos_.clear();
  info_.clear();
  parent_.clear();
  depth_.clear();
  unloc_.clear();
  cost_.clear();
  det_sum_.clear();
  lower_.clear();
  for (auto& level : levels_) level.clear();
  goals_.clear();
  best_ = -1;
  j_min_ = kInf;
  tol_ = kGoalTolerance * p.eps;
  first_goal_iteration_ = -1;
  iteration_ = 0;
  tours_.clear();
  makespan_tours_.clear();
  tour_makespan_ = 0;
  assigned_.assign(n_, -1);
  child_pos_.assign(n_, 0);
  open_.assign(m_, 0);
  avail_.assign(m_, 0);
  open_list_.clear();
  open_indexed_ = false;
  robots_indexed_ = false;
}

void SamplingTree::Buckets::Reset(int nx, int ny, int count) {
  const double side = std::sqrt(2.0 * nx * ny / std::max(1, count));
  cell = std::clamp(static_cast<int>(std::lround(side)), 4, 64);
  gx = (nx + cell - 1) / cell;
  gy = (ny + cell - 1) / cell;
  begin.assign(static_cast<size_t>(gx) * gy + 1, 0);
}

namespace {

// Fills a bucket grid's CSR from the bucket of each item (-1: left out).
template <typename BucketOf>
void FillBuckets(int count, BucketOf&& bucket_of, std::vector<int>* begin,
                 std::vector<int>* items, std::vector<int>* fill) {
  for (int t = 0; t < count; ++t) {
    const int b = bucket_of(t);
    if (b >= 0) ++(*begin)[b + 1];
  }
  for (size_t c = 1; c < begin->size(); ++c) (*begin)[c] += (*begin)[c - 1];
  items->resize(begin->back());
  fill->assign(begin->begin(), begin->end() - 1);
  for (int t = 0; t < count; ++t) {
    const int b = bucket_of(t);
    if (b >= 0) (*items)[(*fill)[b]++] = t;
  }
}

}  // namespace

void SamplingTree::BuildOpenIndex() {
  open_indexed_ =
      indexed_ && static_cast<int>(open_list_.size()) > kLinearTargets;
  if (!open_indexed_) return;
  const Lattice& lattice = problem_->map->lattice();
  Buckets& g = open_index_;
  g.Reset(lattice.nx(), lattice.ny(), static_cast<int>(open_list_.size()));
  // Items are positions in open_list_; the index holds target ids.
  FillBuckets(
      static_cast<int>(open_list_.size()),
      [&](int t) {
        const Rect& b = region_box_[open_list_[t]];
        if (b.x0 > b.x1) return -1;  // no region: its field is -1 everywhere
        return g.Of((b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2);
      },
      &g.begin, &g.items, &g.fill);
  for (int& t : g.items) t = open_list_[t];
}

void SamplingTree::BuildRobotIndex(const int* positions) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  robots_indexed_ = indexed_ && n_ > kLinearRobots;
  if (!robots_indexed_) return;
  Buckets& g = robot_index_;
  g.Reset(lattice.nx(), lattice.ny(), n_);
  FillBuckets(
      n_,
      [&](int i) {
        if (!p.active[i]) return -1;
        return g.Of(lattice.Ix(positions[i]), lattice.Iy(positions[i]));
      },
      &g.begin, &g.items, &g.fill);
}

namespace {

// L1 distance (lattice steps) from (x, y) to a rectangle: a lower bound of
// the BFS distance to any point in it, each move changing one coordinate by
// one.
inline int RectDistance(int x, int y, int x0, int x1, int y0, int y1) {
  return std::max({0, x0 - x, x - x1}) + std::max({0, y0 - y, y - y1});
}

// Calls visit(bucket) for the buckets at Chebyshev distance r from the bucket
// rectangle [bx0, bx1] x [by0, by1] (the rectangle itself for r = 0),
// clipped to the grid of gx x gy buckets.
template <typename Visit>
void VisitRing(int bx0, int bx1, int by0, int by1, int r, int gx, int gy,
               Visit&& visit) {
  const int x0 = bx0 - r, x1 = bx1 + r, y0 = by0 - r, y1 = by1 + r;
  for (int y = std::max(0, y0); y <= std::min(gy - 1, y1); ++y) {
    if (r == 0 || y == y0 || y == y1) {
      for (int x = std::max(0, x0); x <= std::min(gx - 1, x1); ++x)
        visit(y * gx + x);
    } else {
      if (x0 >= 0) visit(y * gx + x0);
      if (x1 < gx) visit(y * gx + x1);
    }
  }
}

}  // namespace

int SamplingTree::NearestTarget(int q, int depth, const std::vector<char>& ok,
                                int* dist) {
  int best = -1, best_d = std::numeric_limits<int>::max();
  if (indexed_ && !open_indexed_) {
    // Few open targets: in order of the L1 bound of their distance, reading
    // a field (a cache miss, likely) only while it may beat the best.
    near_.clear();
    const Lattice& lattice = problem_->map->lattice();
    const int x = lattice.Ix(q), y = lattice.Iy(q);
    for (int k : open_list_) {
      const Rect& b = region_box_[k];
      if (!ok[k] || b.x0 > b.x1) continue;
      near_.push_back({RectDistance(x, y, b.x0, b.x1, b.y0, b.y1), k});
    }
    while (!near_.empty()) {  // the least bound next, by selection
      size_t j = 0;
      for (size_t c = 1; c < near_.size(); ++c)
        if (near_[c] < near_[j]) j = c;
      const auto [lb, k] = near_[j];
      if (best >= 0 && lb > best_d) break;
      near_[j] = near_.back();
      near_.pop_back();
      const int d = static_field_[k][q];
      if (d >= 0 && (best < 0 || d < best_d || (d == best_d && k < best))) {
        best = k;
        best_d = d;
      }
    }
    *dist = best_d;
    return best;
  }
  if (!open_indexed_) {
    for (int k : open_list_) {
      if (!ok[k]) continue;
      const int d = FieldAt(depth, k)[q];
      if (d >= 0 && d < best_d) {
        best = k;
        best_d = d;
      }
    }
    *dist = best_d;
    return best;
  }
  // Best first: candidates in a heap by the L1 bound of their distance,
  // filled ring by ring around q's bucket (a target whose region's centre
  // lies in ring r >= 1 is at least (r - 1) cell + 1 - pad_ steps away) while
  // the next ring could hold a better one; a field is read (a cache miss,
  // likely) only while the bound may beat the best.
  const Lattice& lattice = problem_->map->lattice();
  const Buckets& g = open_index_;
  const int x = lattice.Ix(q), y = lattice.Iy(q);
  const int bx = x / g.cell, by = y / g.cell;
  const int rings = std::max(g.gx, g.gy);
  near_.clear();
  int r = 0;
  for (;;) {
    while (r <= rings && (near_.empty() ||
                          near_.front().first >= (r - 1) * g.cell + 1 - pad_)) {
      VisitRing(bx, bx, by, by, r, g.gx, g.gy, [&](int c) {
        for (int t = g.begin[c]; t < g.begin[c + 1]; ++t) {
          const int k = g.items[t];
          if (!ok[k]) continue;
          const Rect& b = region_box_[k];
          const int lb = RectDistance(x, y, b.x0, b.x1, b.y0, b.y1);
          if (best >= 0 && lb > best_d) continue;  // never read
          near_.push_back({lb, k});
          std::push_heap(near_.begin(), near_.end(), std::greater<>());
        }
      });
      ++r;
    }
    if (near_.empty()) break;
    std::pop_heap(near_.begin(), near_.end(), std::greater<>());
    const auto [lb, k] = near_.back();
    near_.pop_back();
    if (best >= 0 && lb > best_d) break;
    const int d = static_field_[k][q];
    if (d >= 0 && (best < 0 || d < best_d || (d == best_d && k < best))) {
      best = k;
      best_d = d;
    }
  }
  *dist = best_d;
  return best;
}

int SamplingTree::ReachOf(int k, const int* positions) const {
  const SamplingProblem& p = *problem_;
  const int* field = static_field_[k];
  int reach = std::numeric_limits<int>::max();
  if (!robots_indexed_) {
    for (int i = 0; i < n_; ++i) {
      const int f = p.active[i] ? field[positions[i]] : -1;
      if (f >= 0) reach = std::min(reach, f);
    }
    return reach;
  }
  const Rect& b = region_box_[k];
  if (b.x0 > b.x1) return reach;  // no region
  const Lattice& lattice = p.map->lattice();
  const Buckets& g = robot_index_;
  const int bx0 = b.x0 / g.cell, bx1 = b.x1 / g.cell;
  const int by0 = b.y0 / g.cell, by1 = b.y1 / g.cell;
  const int rings = std::max(g.gx, g.gy);
  // A robot in ring r >= 1 around the region's buckets is at least
  // (r - 1) cell + 1 steps away.
  for (int r = 0; r <= rings; ++r) {
    if (r > 0 && (r - 1) * g.cell + 1 >= reach) break;
    VisitRing(bx0, bx1, by0, by1, r, g.gx, g.gy, [&](int c) {
      for (int t = g.begin[c]; t < g.begin[c + 1]; ++t) {
        const int q = positions[g.items[t]];
        if (RectDistance(lattice.Ix(q), lattice.Iy(q), b.x0, b.x1, b.y0,
                         b.y1) >= reach)
          continue;
        const int f = field[q];
        if (f >= 0) reach = std::min(reach, f);
      }
    });
  }
  return reach;
}

int SamplingTree::AddNode(int parent, const int* positions) {
  const SamplingProblem& p = *problem_;
  const int id = static_cast<int>(parent_.size());
  const int depth = parent < 0 ? 0 : depth_[parent] + 1;
  pos_.insert(pos_.end(), positions, positions + n_);
  info_.resize(info_.size() + stride_);
  double* info = info_.data() + static_cast<size_t>(id) * stride_;
  if (parent < 0) {
    for (int k = 0; k < m_; ++k) {
      const auto omega = p.belief->Omega(p.belief_row, k);
      if (targets_[k].dim == 2) {
        Pack<2>(Eigen::Matrix2d(omega), info + targets_[k].offset);
      } else {
        Pack<4>(Eigen::Matrix4d(omega), info + targets_[k].offset);
      }
    }
  } else {
    const double* from = info_.data() + static_cast<size_t>(parent) * stride_;
    std::copy(from, from + stride_, info);
    // Time update of the moving targets (static ones are unchanged): the
    // filter's own, on the unpacked block.
    if (any_moving_) {
      for (int k = 0; k < m_; ++k) {
        if (targets_[k].is_static) continue;
        double* blk = info + targets_[k].offset;
        if (targets_[k].dim == 2) {
          Eigen::Matrix2d omega = Unpack<2>(blk);
          PredictInformationMatrix(*models_[k], omega.data());
          Pack<2>(omega, blk);
        } else {
          Eigen::Matrix4d omega = Unpack<4>(blk);
          PredictInformationMatrix(*models_[k], omega.data());
          Pack<4>(omega, blk);
        }
      }
    }
    // Measurement update: every active robot at its new point.
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      const int q = positions[i];
      for (int o = obs_begin_[q]; o < obs_begin_[q + 1]; ++o) {
        const auto& [k, r] = obs_[o];
        AddPositionPrecision(info + targets_[k].offset, targets_[k].dim, r);
      }
      if (any_moving_) {
        const Vec2 here = p.map->lattice().Point(q);
        for (int k = 0; k < m_; ++k) {
          if (targets_[k].is_static) continue;
          const double r = PredictedPrecision(*p.map, *p.sensor, here,
                                              MeasurePoint(depth, k));
          if (r > 0.0)
            AddPositionPrecision(info + targets_[k].offset, targets_[k].dim, r);
        }
      }
    }
    if (depth == 1 && !p.extra_at_depth1.empty()) {
      for (int k = 0; k < m_; ++k)
        if (p.extra_at_depth1[k] > 0.0)
          AddPositionPrecision(info + targets_[k].offset, targets_[k].dim,
                               p.extra_at_depth1[k]);
    }
  }
  // A static target that no robot can measure before reaching its region
  // keeps its det for at least (distance - 1) more steps: an admissible
  // bound on the cost still to come.
  double sum = 0.0, ahead = 0.0;
  int unloc = 0;
  bool grid_built = false;
  for (int k = 0; k < m_; ++k) {
    const double d = BlockDet(info, k);
    sum += d;
    if (d <= p.eps) continue;
    ++unloc;
    if (!targets_[k].is_static) continue;
    if (depth == 0 && !p.extra_at_depth1.empty() && p.extra_at_depth1[k] > 0.0)
      continue;
    if (!grid_built) {
      BuildRobotIndex(positions);
      grid_built = true;
    }
    const int reach = ReachOf(k, positions);
    if (reach != std::numeric_limits<int>::max() && reach > 1)
      ahead += d * (reach - 1);
  }
  const double cost = parent < 0 ? 0.0 : cost_[parent] + sum;
  parent_.push_back(parent);
  depth_.push_back(depth);
  unloc_.push_back(unloc);
  det_sum_.push_back(sum);
  cost_.push_back(cost);
  lower_.push_back(cost + ahead);
  return id;
}

void SamplingTree::MarkOpen(int node) {
  const double* info = Info(node);
  open_list_.clear();
  for (int k = 0; k < m_; ++k) {
    open_[k] = BlockDet(info, k) > problem_->eps ? 1 : 0;
    if (open_[k]) open_list_.push_back(k);
  }
  BuildOpenIndex();
}

int SamplingTree::NearestOpen(int q, int depth) {
  int d = 0;
  return NearestTarget(q, depth, open_, &d);
}

int SamplingTree::NextInTour(const std::vector<int>& tour) const {
  for (int k : tour)
    if (open_[k]) return k;
  return -1;
}

Move SamplingTree::StepToward(int q, int k, int depth, Rng* rng) {
  const Lattice& lattice = problem_->map->lattice();
  if (k >= 0) {
    const int* f =
        static_field_[k] ? static_field_[k] : FieldAt(depth, k).data();
    const int here = f[q];
    if (here > 0) {  // StepDownField
      for (Move m : kMoves) {
        const int v = lattice.Next(q, m);
        if (v >= 0 && f[v] == here - 1) return m;
      }
      return Move::kStay;
    }
    if (here == 0) {  // in the region already: stay inside it if possible
      for (Move m : kMoves) {
        const int v = lattice.Next(q, m);
        if (v >= 0 && f[v] == 0) return m;
      }
    }
  }
  if (rng) return RandomValidMove(lattice, q, *rng);
  for (Move m : kMoves)
    if (lattice.Valid(q, m)) return m;
  return Move::kStay;
}

void SamplingTree::Assign(int node, bool sorted, Rng& rng) {
  const SamplingProblem& p = *problem_;
  const int* pos = Pos(node);
  const int depth = depth_[node] + 1;
  MarkOpen(node);
  std::copy(open_.begin(), open_.end(), avail_.begin());  // open, not taken
  std::fill(assigned_.begin(), assigned_.end(), -1);
  if (sorted && !use_index_) {
    // The definition, for tests: all pairs, sorted.
    pairs_.clear();
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      for (int k : open_list_) {
        const int d = FieldAt(depth, k)[pos[i]];
        if (d >= 0) pairs_.push_back({d, i * m_ + k});
      }
    }
    std::sort(pairs_.begin(), pairs_.end());
    for (const auto& [d, ik] : pairs_) {
      const int i = ik / m_, k = ik % m_;
      if (assigned_[i] >= 0 || !avail_[k]) continue;
      assigned_[i] = k;
      avail_[k] = 0;
    }
  } else if (sorted) {
    // Globally nearest robot-target pairs (distance, then robot, then target)
    // first: a greedy matching. Without listing every pair: each robot's
    // nearest free target (NearestTarget) in a heap of (distance, robot * m +
    // target); an entry whose target was taken meanwhile is replaced by the
    // robot's next nearest free one. The top is then always the first pair of
    // the sorted list of all pairs whose robot and target are both free.
    pairs_.clear();
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      int d = 0;
      const int k = NearestTarget(pos[i], depth, avail_, &d);
      if (k >= 0) pairs_.push_back({d, i * m_ + k});
    }
    std::make_heap(pairs_.begin(), pairs_.end(), std::greater<>());
    int left = static_cast<int>(open_list_.size());
    while (!pairs_.empty() && left > 0) {
      std::pop_heap(pairs_.begin(), pairs_.end(), std::greater<>());
      const int i = pairs_.back().second / m_, k = pairs_.back().second % m_;
      pairs_.pop_back();
      if (!avail_[k]) {
        int d = 0;
        const int next = NearestTarget(pos[i], depth, avail_, &d);
        if (next >= 0) {
          pairs_.push_back({d, i * m_ + next});
          std::push_heap(pairs_.begin(), pairs_.end(), std::greater<>());
        }
        continue;
      }
      assigned_[i] = k;
      avail_[k] = 0;
      --left;
    }
  } else {
    // Each robot in random order takes its nearest free unlocalized target.
    order_.clear();
    for (int i = 0; i < n_; ++i)
      if (p.active[i]) order_.push_back(i);
    for (size_t a = order_.size(); a > 1; --a)
      std::swap(order_[a - 1], order_[rng.UniformInt(a)]);
    for (int i : order_) {
      int d = 0;
      const int best = NearestTarget(pos[i], depth, avail_, &d);
      if (best >= 0) {
        assigned_[i] = best;
        avail_[best] = 0;
      }
    }
  }
  // Robots left over (more robots than open targets) follow the idle rule:
  // toward the nearest unlocalized target.
  for (int i = 0; i < n_; ++i)
    if (p.active[i] && assigned_[i] < 0)
      assigned_[i] = NearestOpen(pos[i], depth);
}

Leg SamplingTree::ComputeLeg(int from, int t, int k) {
  const Lattice& lattice = problem_->map->lattice();
  const int cap = lattice.size();
  int cur = from;
  for (int s = 0; s <= cap; ++s) {
    const int here = FieldAt(t + s, k)[cur];
    if (here < 0) return {};
    // Arrived (at the root a robot in the region still needs a step).
    if (here == 0 && t + s > 0) return {s, cur};
    const Move m = StepToward(cur, k, t + s + 1, nullptr);
    if (m == Move::kStay) return {};
    cur = lattice.Next(cur, m);
  }
  return {};
}

void SamplingTree::PlanTours() {
  const SamplingProblem& p = *problem_;
  std::vector<int> starts(n_, -1), targets;
  for (int i = 0; i < n_; ++i)
    if (p.active[i]) starts[i] = p.start[i];
  std::vector<double> weight(m_, 0.0);
  MarkOpen(0);
  for (int k = 0; k < m_; ++k) {
    if (!open_[k]) continue;
    targets.push_back(k);
    weight[k] = BlockDet(Info(0), k);
  }
  Legs legs(this);
  TourSettings settings;
  settings.budget = tour_budget_;
  settings.objective = TourObjective::kLatency;
  const Tours latency =
      tour_planner_.Plan(starts, targets, weight, settings, legs);
  tours_ = latency.order;
  tour_makespan_ = latency.makespan;
  settings.objective = TourObjective::kMakespan;
  makespan_tours_ =
      tour_planner_.Plan(starts, targets, weight, settings, legs).order;
}

void SamplingTree::RolloutMoves(int node, RolloutKind kind) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  const int* from = Pos(node);
  const int depth = depth_[node] + 1;
  const double* info = Info(node);
  if (kind == RolloutKind::kNearest) {
    Rng unused(0);
    Assign(node, /*sorted=*/true, unused);
  } else {
    MarkOpen(node);
  }
  for (int i = 0; i < n_; ++i) {
    const int q = from[i];
    child_pos_[i] = q;
    if (!p.active[i]) continue;
    int k = -1;
    if (kind == RolloutKind::kNearest) {
      k = assigned_[i];
    } else if (kind == RolloutKind::kGreedy) {
      // The neighbour that lowers the unlocalized targets' log det most, as
      // the greedy policy; else toward the nearest one.
      double best_gain = 0.0;
      int best_q = -1;
      for (Move m : kMoves) {
        const int v = lattice.Next(q, m);
        if (v < 0) continue;
        double gain = 0.0;
        const Vec2 there = lattice.Point(v);
        if (!any_moving_) {
          // The static targets seen from v, in ascending order as below.
          for (int o = obs_begin_[v]; o < obs_begin_[v + 1]; ++o) {
            const auto& [k2, r] = obs_[o];
            if (!open_[k2] || r <= 0.0) continue;
            const double after = BlockDetAfter(info, k2, r);
            gain +=
                std::log(BlockDet(info, k2)) - std::log(std::max(after, p.eps));
          }
        }
        for (int k2 = 0; k2 < m_ && any_moving_; ++k2) {
          if (!open_[k2]) continue;
          double r = 0.0;
          if (targets_[k2].is_static) {
            for (int o = obs_begin_[v]; o < obs_begin_[v + 1]; ++o)
              if (obs_[o].first == k2) r = obs_[o].second;
          } else {
            r = PredictedPrecision(*p.map, *p.sensor, there,
                                   MeasurePoint(depth, k2));
          }
          if (r <= 0.0) continue;
          const double after = BlockDetAfter(info, k2, r);
          gain +=
              std::log(BlockDet(info, k2)) - std::log(std::max(after, p.eps));
        }
        if (gain > best_gain) {
          best_gain = gain;
          best_q = v;
        }
      }
      if (best_q >= 0) {
        child_pos_[i] = best_q;
        continue;
      }
      k = NearestOpen(q, depth);
    } else {
      const auto& tours =
          kind == RolloutKind::kTours ? tours_ : makespan_tours_;
      k = NextInTour(tours[i]);
      if (k < 0) k = NearestOpen(q, depth);
    }
    const Move m = StepToward(q, k, depth, nullptr);
    if (m != Move::kStay) child_pos_[i] = lattice.Next(q, m);
  }
}

bool SamplingTree::Expandable(int v, const SamplingParams& params) const {
  if (unloc_[v] == 0) return false;
  if (params.max_depth > 0 && depth_[v] >= params.max_depth) return false;
  if (best_ < 0) return true;
  // A descendant must beat j_min_ by more than the tolerance, or come within
  // it at a shorter horizon than the selected goal's.
  if (lower_[v] >= j_min_ + tol_) return false;
  return lower_[v] < j_min_ - tol_ || depth_[v] + 1 < depth_[best_];
}

void SamplingTree::Select() {
  // The shortest goal within the tolerance of the cheapest (then the
  // cheaper); goals beyond it can never be selected again.
  size_t kept = 0;
  best_ = -1;
  for (int g : goals_) {
    if (cost_[g] > j_min_ + tol_) continue;
    goals_[kept++] = g;
    if (best_ < 0 || depth_[g] < depth_[best_] ||
        (depth_[g] == depth_[best_] && cost_[g] < cost_[best_]))
      best_ = g;
  }
  goals_.resize(kept);
}

void SamplingTree::Register(int child, const SamplingParams& params) {
  last_ = child;
  if (unloc_[child] < unloc_[best_partial_] ||
      (unloc_[child] == unloc_[best_partial_] &&
       det_sum_[child] < det_sum_[best_partial_]))
    best_partial_ = child;
  if (unloc_[child] == 0) {
    if (best_ < 0) first_goal_iteration_ = iteration_;
    if (cost_[child] <= j_min_ + tol_) {
      j_min_ = std::min(j_min_, cost_[child]);
      goals_.push_back(child);
      Select();
    }
  } else if (Expandable(child, params)) {
    const int d = depth_[child];
    if (static_cast<int>(levels_.size()) <= d) levels_.resize(d + 1);
    levels_[d].push_back(child);
  }
}

int SamplingTree::Rollout(RolloutKind kind, const SamplingParams& params) {
  const Lattice& lattice = problem_->map->lattice();
  const int cap = params.max_depth > 0
                      ? params.max_depth
                      : 2 * (lattice.nx() + lattice.ny()) * std::max(1, m_);
  int v = 0;
  while (unloc_[v] > 0 && depth_[v] < cap &&
         static_cast<long>(parent_.size()) < node_cap_) {
    RolloutMoves(v, kind);
    const int child = AddNode(v, child_pos_.data());
    Register(child, params);
    v = child;
  }
  return v;
}

void SamplingTree::UsefulUntil(const std::vector<int>& path,
                               std::vector<int>* until) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  until->assign(n_, 0);
  for (size_t d = 1; d < path.size(); ++d) {
    MarkOpen(path[d - 1]);
    const int* pos = Pos(path[d]);
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      bool useful = false;
      for (int o = obs_begin_[pos[i]]; o < obs_begin_[pos[i] + 1]; ++o)
        useful = useful || open_[obs_[o].first];
      for (int k = 0; k < m_ && !useful && any_moving_; ++k)
        useful = open_[k] && !targets_[k].is_static &&
                 PredictedPrecision(*p.map, *p.sensor, lattice.Point(pos[i]),
                                    MeasurePoint(static_cast<int>(d), k)) > 0.0;
      if (useful) (*until)[i] = static_cast<int>(d);
    }
  }
}

int SamplingTree::RewriteIdle(int end) {
  const SamplingProblem& p = *problem_;
  const Lattice& lattice = p.map->lattice();
  std::vector<int> path(depth_[end] + 1);
  for (int v = end; v >= 0; v = parent_[v]) path[depth_[v]] = v;
  std::vector<int> until;
  UsefulUntil(path, &until);
  bool idle = false;
  for (int i = 0; i < n_; ++i)
    idle = idle || (p.active[i] && until[i] < depth_[end]);
  if (!idle) return end;
  // Replay: robots with useful work left keep their moves, the others head
  // for the nearest target the team has not localized. Information only
  // grows, so every target is localized no later than on the original path,
  // and J is no larger.
  int v = 0;
  for (int d = 1; d <= depth_[end] && unloc_[v] > 0; ++d) {
    MarkOpen(v);
    const int* from = Pos(v);
    const int* planned = Pos(path[d]);
    for (int i = 0; i < n_; ++i) {
      child_pos_[i] = from[i];
      if (!p.active[i]) continue;
      if (d <= until[i]) {
        child_pos_[i] = planned[i];
        continue;
      }
      const Move m = StepToward(from[i], NearestOpen(from[i], d), d, nullptr);
      if (m != Move::kStay) child_pos_[i] = lattice.Next(from[i], m);
    }
    v = AddNode(v, child_pos_.data());
  }
  if (unloc_[v] != 0 || cost_[v] > cost_[end] + tol_ || depth_[v] > depth_[end])
    return end;  // cannot happen (see above); kept as a guard
  return v;
}

int SamplingTree::StartRoot(const SamplingProblem& problem, int* bound) {
  const int root = AddNode(-1, problem.start.data());
  if (levels_.empty()) levels_.resize(1);
  levels_[0].push_back(root);
  best_partial_ = root;
  last_ = root;
  if (unloc_[root] == 0) {
    goals_.push_back(root);
    j_min_ = 0.0;
    best_ = root;
  }
  // The lower bound on the horizon.
  MarkOpen(root);
  *bound = 0;
  for (int k = 0; k < m_; ++k) {
    if (!open_[k]) continue;
    int nearest = -1;
    if (targets_[k].is_static) {
      for (int i = 0; i < n_; ++i) {
        const int f =
            problem.active[i] ? slots_[k][0].field[problem.start[i]] : -1;
        if (f >= 0 && (nearest < 0 || f < nearest)) nearest = f;
      }
    }
    *bound = std::max(*bound, std::max(nearest, 1));
  }
  return root;
}

void SamplingTree::SeededRollouts(const SamplingParams& params, int root,
                                  SamplingPlan* plan) {
  PlanTours();
  const std::pair<RolloutKind, const char*> kinds[] = {
      {RolloutKind::kTours, "tours"},
      {RolloutKind::kMakespanTours, "makespan_tours"},
      {RolloutKind::kNearest, "nearest"},
      {RolloutKind::kGreedy, "greedy"}};
  for (const auto& [kind, name] : kinds) {
    const int end = Rollout(kind, params);
    plan->rollouts.push_back({name, unloc_[end] == 0, depth_[end], cost_[end]});
  }
  last_ = root;
}

double SamplingTree::MostNodes(const SamplingParams& params) const {
  const Lattice& lattice = problem_->map->lattice();
  // One node per iteration (before a first goal and after it, all within
  // node_cap_) and the idle rewrite's path, which adds at most the returned
  // path's depth: no deeper than the deepest node now plus one per node
  // still to come.
  const double grown = std::min(
      static_cast<double>(node_cap_),
      static_cast<double>(parent_.size()) +
          static_cast<double>(params.anytime) +
          (best_ >= 0 ? 0.0 : static_cast<double>(params.max_iterations)));
  const double deepest =
      *std::max_element(depth_.begin(), depth_.end()) +
      std::max(0.0, grown - static_cast<double>(parent_.size()));
  const double rewrite_cap =
      !params.routing ? 0.0
      : params.max_depth > 0
          ? params.max_depth
          : std::min(deepest,
                     2.0 * (lattice.nx() + lattice.ny()) * std::max(1, m_));
  return grown + rewrite_cap;
}

void SamplingTree::ReserveArena(double nodes) {
  const auto count = static_cast<std::size_t>(nodes);
  pos_.reserve(count * n_);
  info_.reserve(count * stride_);
  for (auto* v : {&parent_, &depth_, &unloc_}) v->reserve(count);
  for (auto* v : {&cost_, &det_sum_, &lower_}) v->reserve(count);
}

void SamplingTree::ReleaseArena() {
  const auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  release(pos_);
  release(info_);
  release(parent_);
  release(depth_);
  release(unloc_);
  release(cost_);
  release(det_sum_);
  release(lower_);
  release(levels_);
  release(goals_);
}

int SamplingTree::SelectNode(const SamplingParams& params, Rng& rng) {
  // f_V: with probability p_V the deepest node of the branch being grown (the
  // newest node), so that each branch is rolled out to a goal; else a node
  // from a uniformly drawn level (shallow levels get their share, which is
  // where different plans branch off).
  if (rng.Uniform() < params.p_v && Expandable(last_, params)) return last_;
  while (!levels_.empty() && levels_.back().empty()) levels_.pop_back();
  if (levels_.empty()) return kNothingToExpand;
  auto& level = levels_[rng.UniformInt(levels_.size())];
  if (level.empty()) return -1;
  const size_t j = rng.UniformInt(level.size());
  if (Expandable(level[j], params)) return level[j];
  level[j] = level.back();  // pruned for good: the bound only tightens
  level.pop_back();
  return -1;
}

void SamplingTree::Expand(int node, const SamplingParams& params, Rng& rng) {
  const SamplingProblem& problem = *problem_;
  const Lattice& lattice = problem.map->lattice();
  // f_U: the tours, or a nearest-first assignment.
  const bool follow_tours = !tours_.empty() && rng.Uniform() < params.p_tour;
  if (follow_tours) {
    MarkOpen(node);
    for (int i = 0; i < n_; ++i) {
      if (!problem.active[i]) continue;
      assigned_[i] = NextInTour(tours_[i]);
      if (assigned_[i] < 0)
        assigned_[i] = NearestOpen(Pos(node)[i], depth_[node] + 1);
    }
  } else {
    Assign(node, rng.Uniform() < params.p_sorted, rng);
  }
  const int* from = Pos(node);
  for (int i = 0; i < n_; ++i) {
    const int q = from[i];
    child_pos_[i] = q;
    if (!problem.active[i]) continue;
    const int k = assigned_[i];
    const Move move = (k >= 0 && rng.Uniform() < params.p_u)
                          ? StepToward(q, k, depth_[node] + 1, &rng)
                          : RandomValidMove(lattice, q, rng);
    child_pos_[i] = lattice.Next(q, move);
    if (child_pos_[i] < 0) child_pos_[i] = q;
  }
  Register(AddNode(node, child_pos_.data()), params);
}

void SamplingTree::ExtractPlan(const SamplingParams& params,
                               SamplingPlan* plan) {
  plan->found = best_ >= 0;
  plan->best_cost = plan->found ? j_min_ : 0.0;
  int end = plan->found ? best_ : best_partial_;
  if (plan->found && params.routing) end = RewriteIdle(end);
  plan->status =
      plan->found ? PolicyStatus::kOk : PolicyStatus::kBudgetExhausted;
  plan->depth = depth_[end];
  plan->cost = cost_[end];
  plan->configs.assign(plan->depth + 1, std::vector<int>(n_));
  plan->det.assign(plan->depth + 1, std::vector<double>(m_));
  std::vector<int> path(plan->depth + 1);
  for (int v = end; v >= 0; v = parent_[v]) {
    const int d = depth_[v];
    path[d] = v;
    std::copy(pos_.begin() + static_cast<size_t>(v) * n_,
              pos_.begin() + static_cast<size_t>(v + 1) * n_,
              plan->configs[d].begin());
    for (int k = 0; k < m_; ++k) plan->det[d][k] = BlockDet(Info(v), k);
  }
  UsefulUntil(path, &plan->useful_until);
  plan->aims.resize(m_);
  for (int k = 0; k < m_; ++k) plan->aims[k] = MeasurePoint(0, k);
  plan->tour_makespan = tour_makespan_;
  plan->nodes = static_cast<long>(parent_.size());
  plan->iterations = iteration_;
  plan->first_goal_iteration = first_goal_iteration_;
  // What the nodes fill (a reserved arena's untouched pages are not
  // resident).
  plan->arena_bytes =
      pos_.size() * sizeof(int) + info_.size() * sizeof(double) +
      (parent_.size() + depth_.size() + unloc_.size()) * sizeof(int) +
      (cost_.size() + det_sum_.size() + lower_.size()) * sizeof(double);
}

SamplingPlan SamplingTree::Solve(const SamplingProblem& problem,
                                 const SamplingParams& params, Rng& rng) {
  const auto t0 = std::chrono::steady_clock::now();
  AIA_CHECK(problem.map && problem.sensor && problem.belief);
  AIA_CHECK(problem.active.size() == problem.start.size());
  tour_budget_ = params.tour_budget;
  use_index_ = params.spatial_index;
  Prepare(problem);
  // Memory guard: a node keeps n positions, `stride_` numbers and six
  // scalars, in vectors that may hold up to twice what they use.
  const double node_bytes = 2.0 * (4.0 * n_ + 8.0 * stride_ + 40.0);
  node_cap_ = std::min<long>(params.max_nodes,
                             static_cast<long>(kMaxTreeBytes / node_bytes));
  SamplingPlan plan;
  const int root = StartRoot(problem, &plan.bound);
  if (params.routing && best_ != root) SeededRollouts(params, root, &plan);

  // A solve that may need a large arena takes that much of the process's
  // budget of tree memory first (waiting for other trees to finish if need
  // be), reserves its arena at once (no copies as it grows) and gives both
  // back at the end. Taken after the seeded rollouts, which mostly find a
  // goal and so bound what is left by the anytime budget.
  const double most_nodes = MostNodes(params);
  const TreeMemoryLease lease(most_nodes * ResidentNodeBytes(n_, stride_));
  if (lease.large()) ReserveArena(most_nodes);

  long since_goal = 0;
  while (best_ != root) {
    if (best_ >= 0 && since_goal >= params.anytime) break;
    if (best_ < 0 && iteration_ >= params.max_iterations) break;
    if (static_cast<long>(parent_.size()) >= node_cap_) break;
    ++iteration_;
    if (best_ >= 0) ++since_goal;
    const int node = SelectNode(params, rng);
    if (node == kNothingToExpand) break;
    if (node >= 0) Expand(node, params, rng);
  }

  ExtractPlan(params, &plan);
  if (lease.large()) ReleaseArena();  // the memory goes back to the kernel
  plan.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  return plan;
}

template <typename T>
T* ArenaAllocator<T>::allocate(std::size_t n) {
  const std::size_t bytes = n * sizeof(T);
  if (bytes < kMappedBytes) return static_cast<T*>(::operator new(bytes));
  void* p = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
  return static_cast<T*>(p);
}

template <typename T>
void ArenaAllocator<T>::deallocate(T* p, std::size_t n) {
  const std::size_t bytes = n * sizeof(T);
  if (bytes < kMappedBytes) {
    ::operator delete(p);
  } else {
    ::munmap(p, bytes);
  }
}

template struct ArenaAllocator<int>;
template struct ArenaAllocator<double>;

}  // namespace aia
