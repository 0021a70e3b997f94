// Gaussian beliefs over the hidden state x = [x_1; ...; x_M] in information
// form, block diagonal per target (docs/design.md, Estimation). All robots'
// beliefs are stored in one row-major matrix, one row per robot, so that DKF
// fusion runs over contiguous memory and never touches a 2M x 2M matrix;
// blocks that many rows hold bit for bit are kept once per target (the
// common block, BeliefSet).
#ifndef AIA_ESTIMATION_BELIEF_H_
#define AIA_ESTIMATION_BELIEF_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "aia/core/thread_pool.h"
#include "aia/core/types.h"
#include "aia/estimation/target_model.h"

namespace aia {

// Where each target's block lives inside a belief row: Omega (dim x dim,
// column-major) followed by xi (dim).
class BeliefLayout {
 public:
  BeliefLayout() = default;
  explicit BeliefLayout(std::vector<TargetModel> models);

  int num_targets() const { return static_cast<int>(models_.size()); }
  int stride() const { return stride_; }  // doubles per belief row
  const TargetModel& model(int k) const { return models_[k]; }
  int dim(int k) const { return dims_[k]; }
  int omega_offset(int k) const { return offsets_[k]; }
  int xi_offset(int k) const { return offsets_[k] + dims_[k] * dims_[k]; }
  // Whether target k is static (its time update is the identity).
  bool is_static(int k) const { return static_[k] != 0; }
  bool all_static() const { return all_static_; }

 private:
  std::vector<TargetModel> models_;
  std::vector<int> offsets_, dims_;
  std::vector<char> static_;
  int stride_ = 0;
  bool all_static_ = true;
};

// Beliefs of `rows` agents (robots, or one row for the centralized filter).
//
// A set of two rows or more may share blocks (docs/design.md, Estimation):
// in a full graph the robots that never measured a target hold one belief
// of it bit for bit, kept once as the target's common block; a row whose
// block k is its own is in OwnRows(k). Readers see the same values either
// way (Block, Omega, Xi); a non-const Omega or Xi first makes the row's
// block its own (a copy of the common one), and the non-const data() makes
// every block its own (so on a shared set they are not for several threads
// at once, as reads are). The DKF (filter.h, Fuse) keeps a full graph's set
// shared, which makes a step O(M + the blocks that differ) instead of
// O(N M).
class BeliefSet {
 public:
  using Storage =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  BeliefSet() = default;
  BeliefSet(const BeliefLayout* layout, int rows);

  // Every row gets the prior N(mean_k, cov_k) for each target k (one
  // common block per target for a set of two rows or more).
  void SetPrior(const std::vector<Eigen::VectorXd>& means,
                const std::vector<Eigen::MatrixXd>& covs);

  int rows() const { return static_cast<int>(data_.rows()); }
  const BeliefLayout& layout() const { return *layout_; }

  // Block k of a row: Omega (column-major) then xi, d * d + d doubles.
  const double* Block(int row, int k) const {
    return Shared(row, k)
               ? common_.data() + layout_->omega_offset(k)
               : data_.data() + static_cast<Eigen::Index>(row) * data_.cols() +
                     layout_->omega_offset(k);
  }
  // The same block, made the row's own first.
  double* OwnBlock(int row, int k);

  Eigen::Map<Eigen::MatrixXd> Omega(int row, int k);
  Eigen::Map<const Eigen::MatrixXd> Omega(int row, int k) const;
  Eigen::Map<Eigen::VectorXd> Xi(int row, int k);
  Eigen::Map<const Eigen::VectorXd> Xi(int row, int k) const;

  // mu = Omega^-1 xi and Sigma = Omega^-1 of one block.
  Eigen::VectorXd Mean(int row, int k) const;
  Eigen::MatrixXd Covariance(int row, int k) const;
  // Position part of the mean (first two coordinates).
  Vec2 PositionMean(int row, int k) const;
  // Position marginal of the covariance (top-left 2 x 2 of Sigma).
  Mat2 PositionCovariance(int row, int k) const;
  // det Sigma = 1 / det Omega, and its log; infinity where Omega is not
  // positive definite.
  double DetCovariance(int row, int k) const;
  double LogDetCovariance(int row, int k) const;
  // The same of a block (Block's layout) of target k.
  double DetCovarianceOf(const double* block, int k) const;

  // Copy of one row from another set with the same layout.
  void CopyRow(int row, const BeliefSet& from, int from_row);

  // Whether any block is shared, whether row's block k is, and the rows
  // whose block k is their own, ascending (while sharing()).
  bool sharing() const { return sharing_; }
  bool Shared(int row, int k) const {
    return sharing_ &&
           shared_[static_cast<std::size_t>(row) * layout_->num_targets() +
                   k] != 0;
  }
  const std::vector<int>& OwnRows(int k) const { return own_[k]; }
  const double* CommonBlock(int k) const {
    return common_.data() + layout_->omega_offset(k);
  }

  // Every block its own (the values unchanged), and the storage, row by
  // row. The const data() is for sets that share nothing (checked).
  Storage& data();
  const Storage& data() const;
  void Unshare();
  // A copy of the storage with every block in place (shared or not).
  Storage Materialized() const;

  // For the DKF, which writes a shared set target by target: `rows` (own,
  // ascending) become target k's own rows and every other row shares the
  // common block, which the caller writes (CommonBlockToWrite). The own
  // rows' blocks are written through RawBlock. StartSharing makes every
  // block shared, of unwritten common blocks, before the first.
  void StartSharing();
  void SetOwnRows(int k, const std::vector<int>& rows);
  double* CommonBlockToWrite(int k) {
    return common_.data() + layout_->omega_offset(k);
  }
  double* RawBlock(int row, int k) {
    return data_.data() + static_cast<Eigen::Index>(row) * data_.cols() +
           layout_->omega_offset(k);
  }

  // Exchanges the two sets' contents (same layout and rows).
  void Swap(BeliefSet& other);

 private:
  const BeliefLayout* layout_ = nullptr;
  Storage data_;
  // While sharing_: shared_[row * M + k] says block k of row is common_'s;
  // own_[k] lists the rows whose block k is not, ascending.
  bool sharing_ = false;
  Eigen::VectorXd common_;
  std::vector<std::uint8_t> shared_;
  std::vector<std::vector<int>> own_;
};

// What readers of every robot's belief take from it each step, worked out
// once instead of once per reader (at 1000 robots x 1000 targets the rules,
// the search memory and the channels each read a million blocks): per row
// and target, LogDetCovariance and PositionMean, the same values.
class BeliefDigest {
 public:
  // For every row of `beliefs`, the rows split over `run`.
  void Compute(const BeliefSet& beliefs, const RangeRunner& run = {});
  double LogDet(int row, int k) const {
    return log_det_[static_cast<std::size_t>(row) * m_ + k];
  }
  const Vec2& Mean(int row, int k) const {
    return mean_[static_cast<std::size_t>(row) * m_ + k];
  }

 private:
  int m_ = 0;
  std::vector<double> log_det_;
  std::vector<Vec2> mean_;
};

// The team's best estimate of each target: for target k, the active row with
// the smallest det Sigma_k (the lowest index among equals), or -1 when no row
// is active. `det` holds det Sigma of every row and target, row-major
// (rows x num_targets). One definition for the mission's success test, the
// video's estimates and the expert's team-best root.
void TeamBestRows(const std::vector<double>& det, int num_targets,
                  const std::vector<std::uint8_t>& active,
                  std::vector<int>* best);
// The same, computing det Sigma from the beliefs.
void TeamBestRows(const BeliefSet& beliefs,
                  const std::vector<std::uint8_t>& active,
                  std::vector<int>* best);
// One row holding, for each target k, the block of row best[k] (row 0 when
// best[k] is -1).
void TeamBestBelief(const BeliefSet& beliefs, const std::vector<int>& best,
                    BeliefSet* out);

}  // namespace aia

#endif  // AIA_ESTIMATION_BELIEF_H_
