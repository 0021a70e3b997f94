#include "aia/planning/sampling_tree.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <mutex>
#include <new>

#include "aia/core/check.h"
#include "aia/core/clock.h"
#include "aia/estimation/filter.h"
#include "aia/planning/information.h"
#include "aia/planning/search.h"
#include "aia/world/lattice.h"
#include "sampling_tree_internal.h"

namespace aia {

namespace {

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

// What a node keeps resident: its rows of the arena (reserved, so not
// grown by copies) and its entries in levels_ and goals_ (std::vectors,
// counted twice for their growth).
double ResidentNodeBytes(int n, int stride) {
  return 4.0 * n + 8.0 * stride + 36.0 + 16.0;
}

// The process's budget of tree memory (TreeBudgetBytes()) for all the
// large solves running at once. A solve takes all it may need before it starts
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
  double budget() {
    const std::lock_guard<std::mutex> lock(mu_);
    return budget_;
  }
  void SetBudget(double bytes) {
    {
      const std::lock_guard<std::mutex> lock(mu_);
      AIA_CHECK(free_ == budget_);  // no solve holds a part of it
      budget_ = free_ = bytes;
    }
    ready_.notify_all();
  }

 private:
  std::mutex mu_;
  std::condition_variable ready_;
  double budget_ = kMaxTreeBytes;
  double free_ = kMaxTreeBytes;
};

double TreeBudgetBytes() { return TreeMemory::Get().budget(); }

void SetTreeBudgetBytes(double bytes) {
  AIA_CHECK(bytes >= 64.0 * (1 << 20));
  TreeMemory::Get().SetBudget(bytes);
}

// A solve's share of the budget. Solves whose arena stays below
// kSmallTreeBytes (planning/node_arena.h) take none (the ordinary ones:
// Dec-SB's 300 iterations, the expert's default budget on small teams);
// their memory is kept for the next solve.
class TreeMemoryLease {
 public:
  explicit TreeMemoryLease(double bytes)
      : bytes_(bytes > static_cast<double>(kSmallTreeBytes)
                   ? std::min(bytes, TreeBudgetBytes())
                   : 0.0) {
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

void SamplingTree::Prepare(const SamplingProblem& p) {
  problem_ = &p;
  const BeliefSet& belief = *p.belief;
  const BeliefLayout& layout = belief.layout();
  const Lattice& lattice = p.map->lattice();
  n_ = static_cast<int>(p.start.size());
  m_ = layout.num_targets();
  targets_.assign(m_, {});
  models_.assign(m_, nullptr);
  stride_ = 0;
  any_moving_ = false;
  for (int k = 0; k < m_; ++k) {
    targets_[k] = {layout.dim(k), stride_, layout.is_static(k)};
    stride_ += PackedSize(layout.dim(k));
    models_[k] = &layout.model(k);
    any_moving_ = any_moving_ || !layout.is_static(k);
  }
  // Aims, observation regions and fields of the static targets now; moving
  // targets' per span of depths, when first asked for.
  aims_.Reset(*p.map, *p.sensor, belief, p.belief_row, p.missed, p.start,
              p.active);
  // Each static target's observation region, as (point, target, r) in
  // target order, then as obs_: per lattice point, its (target, r) in
  // target order (a counting sort by point).
  observed_.clear();
  region_box_.assign(m_, LatticeRect{});
  static_field_.assign(m_, nullptr);
  for (int k = 0; k < m_; ++k) {
    if (!targets_[k].is_static) continue;
    static_field_[k] = aims_.FieldAt(0, k).data();
    for (const auto& [q, r] : aims_.last_region()) {
      observed_.push_back({q, k, r});
      region_box_[k].Add(lattice.Ix(q), lattice.Iy(q));
    }
  }
  indexed_ = !any_moving_ && use_index_;
  pad_ = 0;
  for (const LatticeRect& b : region_box_) {
    if (b.empty()) continue;
    const int cx = (b.x0 + b.x1) / 2, cy = (b.y0 + b.y1) / 2;
    pad_ = std::max({pad_, cx - b.x0, b.x1 - cx, cy - b.y0, b.y1 - cy});
  }
  obs_begin_.assign(lattice.size() + 1, 0);
  for (const Observed& o : observed_) ++obs_begin_[o.q + 1];
  for (int q = 0; q < lattice.size(); ++q) obs_begin_[q + 1] += obs_begin_[q];
  obs_.resize(observed_.size());
  obs_fill_.assign(obs_begin_.begin(), obs_begin_.end() - 1);
  for (const Observed& o : observed_) obs_[obs_fill_[o.q]++] = {o.k, o.r};

  arena_.Reset(n_, stride_);
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

int SamplingTree::AddNode(int parent, const int* positions) {
  const SamplingProblem& p = *problem_;
  const int id = arena_.size();
  const int depth = parent < 0 ? 0 : arena_.depth(parent) + 1;
  double* info = arena_.Open(positions);
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
    const double* from = arena_.Info(parent);
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
                                              aims_.MeasurePoint(depth, k));
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
  const double cost = parent < 0 ? 0.0 : arena_.cost(parent) + sum;
  arena_.Close(parent, depth, unloc, sum, cost, cost + ahead);
  return id;
}

void SamplingTree::MarkOpen(int node) {
  const double* info = arena_.Info(node);
  open_list_.clear();
  for (int k = 0; k < m_; ++k) {
    open_[k] = BlockDet(info, k) > problem_->eps ? 1 : 0;
    if (open_[k]) open_list_.push_back(k);
  }
  BuildOpenIndex();
}

bool SamplingTree::Expandable(int v, const SamplingParams& params) const {
  if (arena_.unloc(v) == 0) return false;
  if (params.max_depth > 0 && arena_.depth(v) >= params.max_depth) return false;
  if (best_ < 0) return true;
  // A descendant must beat j_min_ by more than the tolerance, or come within
  // it at a shorter horizon than the selected goal's.
  if (arena_.lower(v) >= j_min_ + tol_) return false;
  return arena_.lower(v) < j_min_ - tol_ ||
         arena_.depth(v) + 1 < arena_.depth(best_);
}

void SamplingTree::Select() {
  // The shortest goal within the tolerance of the cheapest (then the
  // cheaper); goals beyond it can never be selected again.
  size_t kept = 0;
  best_ = -1;
  for (int g : goals_) {
    if (arena_.cost(g) > j_min_ + tol_) continue;
    goals_[kept++] = g;
    if (best_ < 0 || arena_.depth(g) < arena_.depth(best_) ||
        (arena_.depth(g) == arena_.depth(best_) &&
         arena_.cost(g) < arena_.cost(best_)))
      best_ = g;
  }
  goals_.resize(kept);
}

void SamplingTree::Register(int child, const SamplingParams& params) {
  last_ = child;
  if (arena_.unloc(child) < arena_.unloc(best_partial_) ||
      (arena_.unloc(child) == arena_.unloc(best_partial_) &&
       arena_.det_sum(child) < arena_.det_sum(best_partial_)))
    best_partial_ = child;
  if (arena_.unloc(child) == 0) {
    if (best_ < 0) first_goal_iteration_ = iteration_;
    if (arena_.cost(child) <= j_min_ + tol_) {
      j_min_ = std::min(j_min_, arena_.cost(child));
      goals_.push_back(child);
      Select();
    }
  } else if (Expandable(child, params)) {
    const int d = arena_.depth(child);
    if (static_cast<int>(levels_.size()) <= d) levels_.resize(d + 1);
    levels_[d].push_back(child);
  }
}

int SamplingTree::StartRoot(const SamplingProblem& problem, int* bound) {
  const int root = AddNode(-1, problem.start.data());
  if (levels_.empty()) levels_.resize(1);
  levels_[0].push_back(root);
  best_partial_ = root;
  last_ = root;
  if (arena_.unloc(root) == 0) {
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
            problem.active[i] ? aims_.FieldAt(0, k)[problem.start[i]] : -1;
        if (f >= 0 && (nearest < 0 || f < nearest)) nearest = f;
      }
    }
    *bound = std::max(*bound, std::max(nearest, 1));
  }
  return root;
}

double SamplingTree::MostNodes(const SamplingParams& params) const {
  const Lattice& lattice = problem_->map->lattice();
  // One node per iteration (before a first goal and after it, all within
  // node_cap_) and the idle rewrite's path, which adds at most the returned
  // path's depth: no deeper than the deepest node now plus one per node
  // still to come.
  const double grown = std::min(
      static_cast<double>(node_cap_),
      static_cast<double>(arena_.size()) + static_cast<double>(params.anytime) +
          (best_ >= 0 ? 0.0 : static_cast<double>(params.max_iterations)));
  const double deepest =
      arena_.MaxDepth() +
      std::max(0.0, grown - static_cast<double>(arena_.size()));
  const double rewrite_cap =
      !params.routing ? 0.0
      : params.max_depth > 0
          ? params.max_depth
          : std::min(deepest,
                     2.0 * (lattice.nx() + lattice.ny()) * std::max(1, m_));
  return grown + rewrite_cap;
}

void SamplingTree::ReserveArena(double nodes) {
  arena_.Reserve(static_cast<std::size_t>(nodes));
}

void SamplingTree::ReleaseArena() {
  const auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  arena_.Release();
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
        assigned_[i] = NearestOpen(arena_.Pos(node)[i], arena_.depth(node) + 1);
    }
  } else {
    Assign(node, rng.Uniform() < params.p_sorted, rng);
  }
  const int* from = arena_.Pos(node);
  for (int i = 0; i < n_; ++i) {
    const int q = from[i];
    child_pos_[i] = q;
    if (!problem.active[i]) continue;
    const int k = assigned_[i];
    const Move move = (k >= 0 && rng.Uniform() < params.p_u)
                          ? StepToward(q, k, arena_.depth(node) + 1, &rng)
                          : RandomValidMove(lattice, q, rng);
    child_pos_[i] = lattice.Next(q, move);
    if (child_pos_[i] < 0) child_pos_[i] = q;
  }
  Register(AddNode(node, child_pos_.data()), params);
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
                             static_cast<long>(TreeBudgetBytes() / node_bytes));
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
    if (static_cast<long>(arena_.size()) >= node_cap_) break;
    ++iteration_;
    if (best_ >= 0) ++since_goal;
    const int node = SelectNode(params, rng);
    if (node == kNothingToExpand) break;
    if (node >= 0) Expand(node, params, rng);
  }

  ExtractPlan(params, &plan);
  if (lease.large()) ReleaseArena();  // the memory goes back to the kernel
  plan.seconds = SecondsSince(t0);
  return plan;
}

}  // namespace aia
