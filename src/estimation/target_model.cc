#include "aia/estimation/target_model.h"

#include <Eigen/SVD>
#include <algorithm>
#include <string>

#include "aia/core/field_io.h"

namespace aia {

bool TargetModel::IsStatic() const {
  if (q != 0.0 || A.rows() != A.cols() || b.size() != A.rows()) return false;
  for (Eigen::Index i = 0; i < A.rows(); ++i) {
    if (b[i] != 0.0) return false;
    for (Eigen::Index j = 0; j < A.cols(); ++j)
      if (A(i, j) != (i == j ? 1.0 : 0.0)) return false;
  }
  return true;
}

TargetModel TargetModel::Static(int dim) {
  TargetModel m;
  m.A = Eigen::MatrixXd::Identity(dim, dim);
  m.b = Eigen::VectorXd::Zero(dim);
  return m;
}

void TargetModel::Validate(const FieldChecker& check) {
  const std::string got =
      std::to_string(A.rows()) + "x" + std::to_string(A.cols());
  if (A.rows() != A.cols()) {
    check.Fail(A,
               "must be a square matrix (2x2 for a state [px, py], 4x4 for "
               "[px, py, vx, vy]), got " +
                   std::to_string(A.rows()) + " rows of " +
                   std::to_string(A.cols()) + " columns");
  }
  if (dim() != 2 && dim() != 4) {
    check.Fail(A,
               "must be 2x2 (state [px, py]) or 4x4 (state [px, py, vx, vy]), "
               "got " +
                   got);
  }
  if (!check.Given(b)) {
    b = Eigen::VectorXd::Zero(dim());
  } else if (b.size() != dim()) {
    check.Fail(b, "must be " + field_text::CountWord(dim()) +
                      " numbers (one per row of A), got " + check.Shown(b));
  }
  // Without process noise the predicted covariance A Sigma A' is as singular
  // as A: the filter would have no finite information to carry.
  if (q == 0.0) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A);
    const Eigen::VectorXd& s = svd.singularValues();
    if (s.minCoeff() <= 1e-9 * std::max(1.0, s.maxCoeff())) {
      check.Fail(q,
                 "must be positive when dynamics.A is singular (its smallest "
                 "singular value is " +
                     FormatNumber(s.minCoeff()) +
                     "): the predicted covariance A Sigma A' would have no "
                     "inverse");
    }
  }
}

}  // namespace aia
