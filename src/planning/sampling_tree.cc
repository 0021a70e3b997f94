#include "aia/planning/sampling_tree.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "aia/core/check.h"
#include "aia/estimation/filter.h"
#include "aia/planning/information.h"
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

double SamplingTree::BlockDet(const double* packed, int k) const {
  const TargetInfo& t = targets_[k];
  const double* p = packed + t.offset;
  if (t.dim == 2) return 1.0 / (p[0] * p[2] - p[1] * p[1]);
  return 1.0 / Unpack<4>(p).determinant();
}

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
  // Observation regions at the root means and BFS fields toward them.
  field_.assign(m_, {});
  std::vector<std::vector<std::pair<int, double>>> per_point(lattice.size());
  const int span =
      static_cast<int>(std::ceil(p.sensor->range / lattice.step())) + 1;
  std::vector<int> region;
  for (int k = 0; k < m_; ++k) {
    region.clear();
    const Vec2 mu = means_[0][k];
    const int c = lattice.NearestPoint(mu);
    for (int iy = std::max(0, lattice.Iy(c) - span);
         iy <= std::min(lattice.ny() - 1, lattice.Iy(c) + span); ++iy) {
      for (int ix = std::max(0, lattice.Ix(c) - span);
           ix <= std::min(lattice.nx() - 1, lattice.Ix(c) + span); ++ix) {
        const int q = lattice.Index(ix, iy);
        if (!lattice.Free(q)) continue;
        const double r =
            PredictedPrecision(*p.map, *p.sensor, lattice.Point(q), mu);
        if (r <= 0.0) continue;
        region.push_back(q);
        if (targets_[k].is_static) per_point[q].push_back({k, r});
      }
    }
    BfsDistances(lattice, region.data(), static_cast<int>(region.size()),
                 &field_[k], &bfs_queue_);
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
  assigned_.assign(n_, -1);
  child_pos_.assign(n_, 0);
  taken_.assign(m_, 0);
  scratch_info_.assign(stride_, 0.0);
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
          const double r =
              PredictedPrecision(*p.map, *p.sensor, here, MeanAt(depth, k));
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
  for (int k = 0; k < m_; ++k) {
    const double d = BlockDet(info, k);
    sum += d;
    if (d <= p.eps) continue;
    ++unloc;
    if (!targets_[k].is_static) continue;
    if (depth == 0 && !p.extra_at_depth1.empty() && p.extra_at_depth1[k] > 0.0)
      continue;
    int reach = std::numeric_limits<int>::max();
    for (int i = 0; i < n_; ++i) {
      const int f = p.active[i] ? field_[k][positions[i]] : -1;
      if (f >= 0) reach = std::min(reach, f);
    }
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

void SamplingTree::Assign(int node, bool sorted, Rng& rng) {
  const SamplingProblem& p = *problem_;
  const double* info = info_.data() + static_cast<size_t>(node) * stride_;
  const int* pos = pos_.data() + static_cast<size_t>(node) * n_;
  for (int k = 0; k < m_; ++k)
    taken_[k] = BlockDet(info, k) > p.eps ? 0 : 2;  // 2: localized
  std::fill(assigned_.begin(), assigned_.end(), -1);
  if (sorted) {
    // Globally nearest robot-target pairs first (greedy matching).
    pairs_.clear();
    for (int i = 0; i < n_; ++i) {
      if (!p.active[i]) continue;
      for (int k = 0; k < m_; ++k) {
        if (taken_[k] != 0) continue;
        const int d = field_[k][pos[i]];
        if (d >= 0) pairs_.push_back({d, i * m_ + k});
      }
    }
    std::sort(pairs_.begin(), pairs_.end());
    for (const auto& [d, ik] : pairs_) {
      const int i = ik / m_, k = ik % m_;
      if (assigned_[i] >= 0 || taken_[k] != 0) continue;
      assigned_[i] = k;
      taken_[k] = 1;
    }
  } else {
    // Each robot in random order takes its nearest free unlocalized target.
    order_.clear();
    for (int i = 0; i < n_; ++i)
      if (p.active[i]) order_.push_back(i);
    for (size_t a = order_.size(); a > 1; --a)
      std::swap(order_[a - 1], order_[rng.UniformInt(a)]);
    for (int i : order_) {
      int best = -1, best_d = std::numeric_limits<int>::max();
      for (int k = 0; k < m_; ++k) {
        const int d = field_[k][pos[i]];
        if (taken_[k] == 0 && d >= 0 && d < best_d) {
          best = k;
          best_d = d;
        }
      }
      if (best >= 0) {
        assigned_[i] = best;
        taken_[best] = 1;
      }
    }
  }
  // Robots left over (more robots than open targets) head for the nearest
  // unlocalized target anyway.
  for (int i = 0; i < n_; ++i) {
    if (!p.active[i] || assigned_[i] >= 0) continue;
    int any_d = std::numeric_limits<int>::max();
    for (int k = 0; k < m_; ++k) {
      const int d = taken_[k] == 2 ? -1 : field_[k][pos[i]];
      if (d >= 0 && d < any_d) {
        assigned_[i] = k;
        any_d = d;
      }
    }
  }
}

SamplingPlan SamplingTree::Solve(const SamplingProblem& problem,
                                 const SamplingParams& params, Rng& rng) {
  const auto t0 = std::chrono::steady_clock::now();
  AIA_CHECK(problem.map && problem.sensor && problem.belief);
  AIA_CHECK(problem.active.size() == problem.start.size());
  Prepare(problem);
  const Lattice& lattice = problem.map->lattice();
  SamplingPlan plan;

  const int root = AddNode(-1, problem.start.data());
  if (levels_.empty()) levels_.resize(1);
  levels_[0].push_back(root);
  int best = unloc_[root] == 0 ? root : -1;
  double best_cost = best >= 0 ? 0.0 : kInf;
  int effort = root;  // best-effort node when no goal is found
  int last = root;    // the newest node: the tip of the branch being grown
  long it = 0, since_goal = 0;
  auto expandable = [&](int v) {
    return unloc_[v] > 0 && lower_[v] < best_cost &&
           (params.max_depth <= 0 || depth_[v] < params.max_depth);
  };
  while (best != root) {
    if (best >= 0 && since_goal >= params.anytime) break;
    if (best < 0 && it >= params.max_iterations) break;
    if (static_cast<long>(parent_.size()) >= params.max_nodes) break;
    ++it;
    if (best >= 0) ++since_goal;
    // f_V: with probability p_V the deepest node of the branch being grown
    // (the newest node), so that each branch is rolled out to a goal; else a
    // node from a uniformly drawn level (shallow levels get their share, which
    // is where different plans branch off).
    int node = -1;
    if (last >= 0 && rng.Uniform() < params.p_v && expandable(last)) {
      node = last;
    } else {
      while (!levels_.empty() && levels_.back().empty()) levels_.pop_back();
      if (levels_.empty()) break;  // nothing left worth expanding
      auto& level = levels_[rng.UniformInt(levels_.size())];
      if (!level.empty()) {
        const size_t j = rng.UniformInt(level.size());
        if (expandable(level[j])) {
          node = level[j];
        } else {  // pruned for good: the bound only tightens
          level[j] = level.back();
          level.pop_back();
        }
      }
    }
    if (node < 0) continue;
    // f_U.
    Assign(node, rng.Uniform() < params.p_sorted, rng);
    const int* from = pos_.data() + static_cast<size_t>(node) * n_;
    for (int i = 0; i < n_; ++i) {
      const int q = from[i];
      child_pos_[i] = q;
      if (!problem.active[i]) continue;
      Move move = Move::kStay;
      const int k = assigned_[i];
      if (k >= 0 && rng.Uniform() < params.p_u) {
        const std::vector<int>& f = field_[k];
        if (f[q] > 0) {
          move = StepDownField(lattice, f, q);
        } else {  // in the region already: stay inside it if possible
          for (Move m : kMoves) {
            const int v = lattice.Next(q, m);
            if (v >= 0 && f[v] == 0) {
              move = m;
              break;
            }
          }
        }
      }
      if (move == Move::kStay) move = RandomValidMove(lattice, q, rng);
      child_pos_[i] = lattice.Next(q, move);
    }
    const int child = AddNode(node, child_pos_.data());
    last = child;
    if (unloc_[child] < unloc_[effort] ||
        (unloc_[child] == unloc_[effort] && det_sum_[child] < det_sum_[effort]))
      effort = child;
    if (unloc_[child] == 0) {
      if (cost_[child] < best_cost) {
        if (best < 0) plan.first_goal_iteration = it;
        best = child;
        best_cost = cost_[child];
      }
    } else if (expandable(child)) {
      const int d = depth_[child];
      if (static_cast<int>(levels_.size()) <= d) levels_.resize(d + 1);
      levels_[d].push_back(child);
    }
  }

  plan.found = best >= 0;
  const int end = plan.found ? best : effort;
  plan.status = plan.found ? PolicyStatus::kOk : PolicyStatus::kBudgetExhausted;
  plan.depth = depth_[end];
  plan.cost = cost_[end];
  plan.configs.assign(plan.depth + 1, std::vector<int>(n_));
  plan.det.assign(plan.depth + 1, std::vector<double>(m_));
  for (int v = end; v >= 0; v = parent_[v]) {
    const int d = depth_[v];
    std::copy(pos_.begin() + static_cast<size_t>(v) * n_,
              pos_.begin() + static_cast<size_t>(v + 1) * n_,
              plan.configs[d].begin());
    for (int k = 0; k < m_; ++k)
      plan.det[d][k] =
          BlockDet(info_.data() + static_cast<size_t>(v) * stride_, k);
  }
  plan.nodes = static_cast<long>(parent_.size());
  plan.iterations = it;
  plan.arena_bytes =
      pos_.capacity() * sizeof(int) + info_.capacity() * sizeof(double) +
      (parent_.capacity() + depth_.capacity() + unloc_.capacity()) *
          sizeof(int) +
      (cost_.capacity() + det_sum_.capacity()) * sizeof(double);
  plan.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0)
          .count();
  return plan;
}

}  // namespace aia
