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
  min_det_.assign(m, 1.0);
  best_.assign(m, -1);
}

void TeamEstimate::Update(bool predict,
                          const std::vector<std::vector<int>>& neighbors,
                          double kappa_self,
                          const std::vector<std::vector<Measurement>>& z,
                          const std::vector<Vec2>& positions,
                          const std::vector<std::uint8_t>& active,
                          const RangeRunner& run) {
  // Predict, exchange over this step's graph, fuse with the robot's own
  // measurements. The step before's fused beliefs become the ones to
  // predict by a swap of the storage, not a copy of the N x M blocks (Fuse
  // writes every row of fused_).
  predicted_.data().swap(fused_.data());
  if (predict) {
    // Only the active robots' estimates count: a failed robot's belief of
    // an unstable target may grow to the bound while others measure it.
    Predict(&predicted_, &active, run);
    Predict(&central_);
  }
  MakeDkfWeights(neighbors, kappa_self, &weights_);
  // det Sigma of each row as soon as it is fused, while it is in the cache.
  const int m = num_targets();
  Fuse(predicted_, weights_, z, positions, &fused_, run, [&](int i) {
    for (int k = 0; k < m; ++k)
      det_[static_cast<std::size_t>(i) * m + k] = fused_.DetCovariance(i, k);
  });
  CentralUpdate(z, positions, &central_);

  // The team's best estimate of each target over the active robots.
  TeamBestRows(det_, m, active, &best_);
  for (int k = 0; k < m; ++k) {
    const int b = best_[k];
    min_det_[k] = b < 0 ? std::numeric_limits<double>::infinity()
                        : det_[static_cast<std::size_t>(b) * m + k];
  }
}

int TeamEstimate::NumLocalized(double eps) const {
  int count = 0;
  for (double d : min_det_) count += d <= eps ? 1 : 0;
  return count;
}

}  // namespace aia
