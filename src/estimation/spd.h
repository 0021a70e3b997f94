// Inverses of small symmetric positive definite blocks, shared by the filter
// and the belief queries (internal to estimation/).
#ifndef AIA_ESTIMATION_SPD_H_
#define AIA_ESTIMATION_SPD_H_

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "aia/estimation/filter.h"

namespace aia::internal {

template <int D>
using MatD = Eigen::Matrix<double, D, D>;
template <int D>
using VecD = Eigen::Matrix<double, D, 1>;

// Sigma^-1 of an SPD block. For D = 2 the closed form is exact enough and
// several times cheaper than a factorization; for D = 4 the Cholesky solve
// avoids the cofactor formula's cancellation when Omega is badly scaled
// (position precision ~1e4 / sigma0^2 next to a loosely known velocity).
// A block that round-off has left barely indefinite (condition numbers near
// 1/eps under extreme settings) is inverted through its eigenvalues, each
// kept at least 1e-15 of the largest; a non-finite block is a divergence.
template <int D>
MatD<D> InverseSpd(const MatD<D>& m) {
  if constexpr (D == 2) {
    const double det = m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
    if (det > 0.0 && m(0, 0) > 0.0 && std::isfinite(det)) {
      MatD<2> inv;
      inv << m(1, 1), -m(0, 1), -m(1, 0), m(0, 0);
      return inv / det;
    }
  } else {
    const Eigen::LLT<MatD<D>> llt(m);
    if (llt.info() == Eigen::Success && m.allFinite())
      return llt.solve(MatD<D>::Identity());
  }
  if (!m.allFinite())
    throw ::aia::EstimateDiverged(-1, "a covariance block is not finite");
  const Eigen::SelfAdjointEigenSolver<MatD<D>> eig(0.5 * (m + m.transpose()));
  const double top = eig.eigenvalues().maxCoeff();
  if (!(top > 0.0))
    throw ::aia::EstimateDiverged(
        -1, "a covariance block is not positive definite");
  const VecD<D> inv = eig.eigenvalues().cwiseMax(1e-15 * top).cwiseInverse();
  return eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}

}  // namespace aia::internal

#endif  // AIA_ESTIMATION_SPD_H_
