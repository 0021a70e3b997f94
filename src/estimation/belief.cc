#include "aia/estimation/belief.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "aia/core/check.h"
#include "spd.h"

namespace aia {
namespace {

// Every per-block query dispatches on dim to fixed-size Eigen types, so that
// none of them touches the heap (planners call them inside their search loops).
template <int D>
using MatD = Eigen::Matrix<double, D, D>;
template <int D>
using VecD = Eigen::Matrix<double, D, 1>;

template <int D>
MatD<D> CovarianceOf(const double* block) {
  return internal::InverseSpd<D>(Eigen::Map<const MatD<D>>(block));
}

template <int D>
VecD<D> MeanOf(const double* block) {
  const Eigen::Map<const MatD<D>> omega(block);
  const Eigen::Map<const VecD<D>> xi(block + D * D);
  const Eigen::LLT<MatD<D>> llt(omega);
  if (llt.info() == Eigen::Success) return llt.solve(xi);
  return internal::InverseSpd<D>(omega) * xi;
}

// log det Sigma = -log det Omega = -2 sum log L_ii for Omega = L L'. Going
// through the Cholesky factor keeps the log finite where det Omega itself
// would overflow (Omega grows like t / sigma0^2 for a watched target).
template <int D>
double LogDetCovarianceOf(const double* block) {
  const Eigen::Map<const MatD<D>> omega(block);
  const Eigen::LLT<MatD<D>> llt(omega);
  // An Omega without full rank leaves some direction of x_k unbounded.
  if (llt.info() != Eigen::Success)
    return std::numeric_limits<double>::infinity();
  return -2.0 * llt.matrixLLT().diagonal().array().log().sum();
}

// LogDetCovarianceOf and the position part of MeanOf from one
// factorization: the same values.
template <int D>
void LogDetAndMeanOf(const double* block, double* log_det, Vec2* mean) {
  const Eigen::Map<const MatD<D>> omega(block);
  const Eigen::Map<const VecD<D>> xi(block + D * D);
  const Eigen::LLT<MatD<D>> llt(omega);
  if (llt.info() == Eigen::Success) {
    *log_det = -2.0 * llt.matrixLLT().diagonal().array().log().sum();
    const VecD<D> x = llt.solve(xi);
    *mean = x.template head<2>();
  } else {
    *log_det = std::numeric_limits<double>::infinity();
    const VecD<D> x = internal::InverseSpd<D>(omega) * xi;
    *mean = x.template head<2>();
  }
}

}  // namespace

BeliefLayout::BeliefLayout(std::vector<TargetModel> models)
    : models_(std::move(models)) {
  offsets_.reserve(models_.size());
  for (const TargetModel& m : models_) {
    const int d = m.dim();
    AIA_CHECK_MSG(d == 2 || d == 4, "target state dimension must be 2 or 4");
    AIA_CHECK(m.A.cols() == d && m.b.size() == d && m.q >= 0.0);
    offsets_.push_back(stride_);
    dims_.push_back(d);
    static_.push_back(m.IsStatic() ? 1 : 0);
    stride_ += d * d + d;
    all_static_ = all_static_ && m.IsStatic();
  }
}

BeliefSet::BeliefSet(const BeliefLayout* layout, int rows) : layout_(layout) {
  AIA_CHECK(layout != nullptr && rows >= 0);
  data_.setZero(rows, layout->stride());
  common_.setZero(layout->stride());
  own_.resize(layout->num_targets());
}

void BeliefSet::SetPrior(const std::vector<Eigen::VectorXd>& means,
                         const std::vector<Eigen::MatrixXd>& covs) {
  const BeliefLayout& lay = *layout_;
  AIA_CHECK(static_cast<int>(means.size()) == lay.num_targets());
  AIA_CHECK(static_cast<int>(covs.size()) == lay.num_targets());
  if (rows() == 0) return;
  Unshare();
  for (int k = 0; k < lay.num_targets(); ++k) {
    const int d = lay.dim(k);
    AIA_CHECK(means[k].size() == d && covs[k].rows() == d &&
              covs[k].cols() == d);
    const Eigen::LLT<Eigen::MatrixXd> llt(covs[k]);
    AIA_CHECK_MSG(llt.info() == Eigen::Success,
                  "prior covariance is not positive definite");
    const Eigen::MatrixXd omega = llt.solve(Eigen::MatrixXd::Identity(d, d));
    // Omega_0 must be exactly symmetric: fusion and prediction keep whatever
    // asymmetry it starts with.
    Omega(0, k) = 0.5 * (omega + omega.transpose());
    Xi(0, k) = Omega(0, k) * means[k];
  }
  if (rows() == 1) return;
  common_ = data_.row(0).transpose();
  StartSharing();
}

void BeliefSet::StartSharing() {
  const int m = layout_->num_targets();
  shared_.assign(static_cast<std::size_t>(rows()) * m, 1);
  for (std::vector<int>& own : own_) own.clear();
  sharing_ = true;
}

void BeliefSet::SetOwnRows(int k, const std::vector<int>& rows) {
  AIA_CHECK(sharing_);
  const std::size_t m = layout_->num_targets();
  for (int r : own_[k]) shared_[r * m + k] = 1;
  for (int r : rows) shared_[r * m + k] = 0;
  own_[k] = rows;
}

double* BeliefSet::OwnBlock(int row, int k) {
  double* own = RawBlock(row, k);
  if (!Shared(row, k)) return own;
  const int size = layout_->dim(k) * (layout_->dim(k) + 1);
  std::copy_n(CommonBlock(k), size, own);
  shared_[static_cast<std::size_t>(row) * layout_->num_targets() + k] = 0;
  std::vector<int>& list = own_[k];
  list.insert(std::lower_bound(list.begin(), list.end(), row), row);
  return own;
}

void BeliefSet::Unshare() {
  if (!sharing_) return;
  const int m = layout_->num_targets();
  for (int r = 0; r < rows(); ++r)
    for (int k = 0; k < m; ++k)
      if (Shared(r, k)) {
        const int size = layout_->dim(k) * (layout_->dim(k) + 1);
        std::copy_n(CommonBlock(k), size, RawBlock(r, k));
      }
  sharing_ = false;
  shared_.clear();
  for (std::vector<int>& own : own_) own.clear();
}

BeliefSet::Storage BeliefSet::Materialized() const {
  BeliefSet copy = *this;
  copy.Unshare();
  return std::move(copy.data_);
}

BeliefSet::Storage& BeliefSet::data() {
  Unshare();
  return data_;
}

const BeliefSet::Storage& BeliefSet::data() const {
  AIA_CHECK_MSG(!sharing_, "a shared belief set's storage is read by block");
  return data_;
}

void BeliefSet::Swap(BeliefSet& other) {
  AIA_CHECK(layout_ == other.layout_);
  data_.swap(other.data_);
  std::swap(sharing_, other.sharing_);
  common_.swap(other.common_);
  shared_.swap(other.shared_);
  own_.swap(other.own_);
}

Eigen::Map<Eigen::MatrixXd> BeliefSet::Omega(int row, int k) {
  const int d = layout_->dim(k);
  return {OwnBlock(row, k), d, d};
}

Eigen::Map<const Eigen::MatrixXd> BeliefSet::Omega(int row, int k) const {
  const int d = layout_->dim(k);
  return {Block(row, k), d, d};
}

Eigen::Map<Eigen::VectorXd> BeliefSet::Xi(int row, int k) {
  const int d = layout_->dim(k);
  return {OwnBlock(row, k) + d * d, d};
}

Eigen::Map<const Eigen::VectorXd> BeliefSet::Xi(int row, int k) const {
  const int d = layout_->dim(k);
  return {Block(row, k) + d * d, d};
}

Eigen::VectorXd BeliefSet::Mean(int row, int k) const {
  const double* block = Block(row, k);
  if (layout_->dim(k) == 2) return MeanOf<2>(block);
  return MeanOf<4>(block);
}

Eigen::MatrixXd BeliefSet::Covariance(int row, int k) const {
  const double* block = Block(row, k);
  if (layout_->dim(k) == 2) return CovarianceOf<2>(block);
  return CovarianceOf<4>(block);
}

Vec2 BeliefSet::PositionMean(int row, int k) const {
  const double* block = Block(row, k);
  if (layout_->dim(k) == 2) return MeanOf<2>(block);
  return MeanOf<4>(block).head<2>();
}

Mat2 BeliefSet::PositionCovariance(int row, int k) const {
  const double* block = Block(row, k);
  if (layout_->dim(k) == 2) return CovarianceOf<2>(block);
  return CovarianceOf<4>(block).topLeftCorner<2, 2>();
}

double BeliefSet::DetCovariance(int row, int k) const {
  return DetCovarianceOf(Block(row, k), k);
}

double BeliefSet::DetCovarianceOf(const double* block, int k) const {
  double det_omega = 0.0;
  if (layout_->dim(k) == 2) {
    // Positive definite: a positive det and a positive diagonal.
    det_omega =
        block[0] > 0.0 ? Eigen::Map<const MatD<2>>(block).determinant() : 0.0;
  } else {
    // Not the 4 x 4 cofactor formula, which cancels when Omega is badly
    // scaled (a position known to 1e-4 m beside a loosely known velocity:
    // 14.87 for 16.00, or inf): the Cholesky factor's diagonal, as
    // LogDetCovariance.
    const Eigen::LLT<MatD<4>> llt{Eigen::Map<const MatD<4>>(block)};
    if (llt.info() != Eigen::Success)
      return std::numeric_limits<double>::infinity();
    const double root = llt.matrixLLT().diagonal().prod();
    det_omega = root * root;
  }
  if (!(det_omega > 0.0)) return std::numeric_limits<double>::infinity();
  return 1.0 / det_omega;
}

double BeliefSet::LogDetCovariance(int row, int k) const {
  const double* block = Block(row, k);
  if (layout_->dim(k) == 2) return LogDetCovarianceOf<2>(block);
  return LogDetCovarianceOf<4>(block);
}

void BeliefSet::CopyRow(int row, const BeliefSet& from, int from_row) {
  AIA_CHECK(data_.cols() == from.data_.cols());
  AIA_CHECK(row >= 0 && row < rows() && from_row >= 0 &&
            from_row < from.rows());
  if (!sharing_ && !from.sharing_) {
    data_.row(row) = from.data_.row(from_row);
    return;
  }
  for (int k = 0; k < layout_->num_targets(); ++k) {
    const int size = layout_->dim(k) * (layout_->dim(k) + 1);
    std::copy_n(from.Block(from_row, k), size, OwnBlock(row, k));
  }
}

void BeliefDigest::Compute(const BeliefSet& beliefs, const RangeRunner& run) {
  m_ = beliefs.layout().num_targets();
  const std::size_t size = static_cast<std::size_t>(beliefs.rows()) * m_;
  log_det_.resize(size);
  mean_.resize(size);
  // A block equal bit for bit to the row before's (in a full graph most
  // rows hold one belief of a target) takes that row's values, the ones
  // the factorization would give; the row before is in the cache where it
  // was read last, in the same part of the split.
  const BeliefLayout& layout = beliefs.layout();
  RunRange(run, beliefs.rows(), [&](int r0, int r1, int) {
    for (int r = r0; r < r1; ++r)
      for (int k = 0; k < m_; ++k) {
        const std::size_t at = static_cast<std::size_t>(r) * m_ + k;
        const int d = layout.dim(k);
        const double* block = beliefs.Block(r, k);
        const double* before = r > r0 ? beliefs.Block(r - 1, k) : nullptr;
        if (before == block ||
            (before != nullptr &&
             std::memcmp(block, before, sizeof(double) * (d * d + d)) == 0)) {
          log_det_[at] = log_det_[at - m_];
          mean_[at] = mean_[at - m_];
        } else if (d == 2) {
          LogDetAndMeanOf<2>(block, &log_det_[at], &mean_[at]);
        } else {
          LogDetAndMeanOf<4>(block, &log_det_[at], &mean_[at]);
        }
      }
  });
}

void TeamBestRows(const std::vector<double>& det, int num_targets,
                  const std::vector<std::uint8_t>& active,
                  std::vector<int>* best) {
  const int rows = static_cast<int>(active.size());
  AIA_CHECK(static_cast<int>(det.size()) == rows * num_targets);
  best->assign(num_targets, -1);
  int* b = best->data();
  // Row by row, so that `det` is read in order (at 80 x 80 a column walk
  // misses the cache on every read and takes twice the time).
  for (int i = 0; i < rows; ++i) {
    if (!active[i]) continue;
    const double* row = det.data() + static_cast<size_t>(i) * num_targets;
    for (int k = 0; k < num_targets; ++k) {
      if (b[k] < 0 || row[k] < det[static_cast<size_t>(b[k]) * num_targets + k])
        b[k] = i;
    }
  }
}

void TeamBestRows(const BeliefSet& beliefs,
                  const std::vector<std::uint8_t>& active,
                  std::vector<int>* best) {
  const int m = beliefs.layout().num_targets();
  AIA_CHECK(static_cast<int>(active.size()) == beliefs.rows());
  std::vector<double> det(static_cast<size_t>(beliefs.rows()) * m);
  for (int i = 0; i < beliefs.rows(); ++i)
    for (int k = 0; k < m; ++k)
      det[static_cast<size_t>(i) * m + k] = beliefs.DetCovariance(i, k);
  TeamBestRows(det, m, active, best);
}

void TeamBestBelief(const BeliefSet& beliefs, const std::vector<int>& best,
                    BeliefSet* out) {
  const int m = beliefs.layout().num_targets();
  AIA_CHECK(static_cast<int>(best.size()) == m && out->rows() == 1);
  for (int k = 0; k < m; ++k) {
    const int row = best[k] < 0 ? 0 : best[k];
    out->Omega(0, k) = beliefs.Omega(row, k);
    out->Xi(0, k) = beliefs.Xi(row, k);
  }
}

}  // namespace aia
