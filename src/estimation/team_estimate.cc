#include "aia/estimation/team_estimate.h"

#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <utility>

#include "aia/core/check.h"

namespace aia {

TeamEstimate::TeamEstimate(std::vector<TargetModel> models, int robots,
                           const std::vector<Eigen::VectorXd>& means,
                           const std::vector<Eigen::MatrixXd>& covs)
    : layout_(std::move(models)) {
  const int m = layout_.num_targets();
  AIA_CHECK(robots >= 0 && static_cast<int>(means.size()) == m &&
            static_cast<int>(covs.size()) == m);
  for (const Eigen::MatrixXd& cov : covs)
    log_det_prior_.push_back(std::log(cov.determinant()));
  predicted_ = BeliefSet(&layout_, robots);
  fused_ = BeliefSet(&layout_, robots);
  central_ = BeliefSet(&layout_, 1);
  predicted_.SetPrior(means, covs);
  fused_.SetPrior(means, covs);
  central_.SetPrior(means, covs);
  det_.assign(static_cast<std::size_t>(robots) * m, 1.0);
  det_common_.assign(m, 1.0);
  min_det_.assign(m, 1.0);
  best_.assign(m, -1);
}

void TeamEstimate::Update(bool predict,
                          const std::vector<std::vector<int>>& neighbors,
                          double kappa_self,
                          const std::vector<std::vector<Measurement>>& z,
                          const std::vector<Vec2>& positions,
                          const std::vector<std::uint8_t>& active,
                          const RangeRunner& run, std::uint64_t graph_stamp) {
  // Predict, exchange over this step's graph, fuse with the robot's own
  // measurements. The step before's fused beliefs become the ones to
  // predict by a swap of the storage, not a copy of the N x M blocks (Fuse
  // writes every row of fused_).
  predicted_.Swap(fused_);
  if (predict) {
    // Only the active robots' estimates count: a failed robot's belief of
    // an unstable target may grow to the bound while others measure it.
    Predict(&predicted_, &active, run);
    Predict(&central_);
  }
  if (graph_stamp == 0 || graph_stamp != weights_stamp_ ||
      kappa_self != weights_kappa_ || weights_.neighbors != &neighbors) {
    MakeDkfWeights(neighbors, kappa_self, &weights_);
    weights_stamp_ = graph_stamp;
    weights_kappa_ = kappa_self;
  }
  // det Sigma of each row as soon as it is fused, while it is in the cache;
  // of a shared set, each common and own block's.
  const int m = num_targets();
  Fuse(predicted_, weights_, z, positions, &fused_, run, [&](int i) {
    for (int k = 0; k < m; ++k)
      det_[static_cast<std::size_t>(i) * m + k] = fused_.DetCovariance(i, k);
  });
  CentralUpdate(z, positions, &central_);
  if (fused_.sharing()) {
    det_common_.resize(m);
    for (int k = 0; k < m; ++k) {
      det_common_[k] = fused_.DetCovarianceOf(fused_.CommonBlock(k), k);
      for (int r : fused_.OwnRows(k))
        det_[static_cast<std::size_t>(r) * m + k] = fused_.DetCovariance(r, k);
    }
    SharedBestRows(active);
  } else {
    // The team's best estimate of each target over the active robots.
    TeamBestRows(det_, m, active, &best_);
  }
  for (int k = 0; k < m; ++k) {
    const int b = best_[k];
    min_det_[k] = b < 0 ? std::numeric_limits<double>::infinity() : Det(b, k);
  }
}

double TeamEstimate::Det(int robot, int target) const {
  if (fused_.Shared(robot, target)) return det_common_[target];
  return det_[static_cast<std::size_t>(robot) * num_targets() + target];
}

void TeamEstimate::SharedBestRows(const std::vector<std::uint8_t>& active) {
  // TeamBestRows' choice (the first active row, then each later one with a
  // smaller det) over the rows that can make it: the rows holding the
  // common block have one det, so only the first active one of them can.
  const int m = num_targets(), n = num_robots();
  active_rows_.clear();
  for (int r = 0; r < n; ++r)
    if (active[r]) active_rows_.push_back(r);
  best_.assign(m, -1);
  for (int k = 0; k < m; ++k) {
    const std::vector<int>& own = fused_.OwnRows(k);
    int first_shared = -1;
    std::size_t o = 0;
    for (int r : active_rows_) {
      while (o < own.size() && own[o] < r) ++o;
      if (o < own.size() && own[o] == r) continue;
      first_shared = r;
      break;
    }
    int b = -1;
    double det = 0.0;
    const auto consider = [&](int r) {
      const double d = Det(r, k);
      if (b < 0 || d < det) {
        b = r;
        det = d;
      }
    };
    bool shared_done = first_shared < 0;
    for (int r : own) {
      if (!active[r]) continue;
      if (!shared_done && first_shared < r) {
        consider(first_shared);
        shared_done = true;
      }
      consider(r);
    }
    if (!shared_done) consider(first_shared);
    best_[k] = b;
  }
}

int TeamEstimate::NumLocalized(double eps) const {
  int count = 0;
  for (double d : min_det_) count += d <= eps ? 1 : 0;
  return count;
}

}  // namespace aia
