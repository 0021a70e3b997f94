#include "aia/planning/information.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>

#include "aia/estimation/filter.h"

namespace aia {

void PredictBlock(const BeliefSet& beliefs, int row, int k,
                  PredictedBlock* out) {
  const TargetModel& model = beliefs.layout().model(k);
  const int d = model.dim();
  // The filter's own time update, on a copy of the block.
  double block[4 * 4 + 4];
  const double* from = beliefs.Block(row, k);
  std::copy(from, from + d * d + d, block);
  if (!beliefs.layout().is_static(k)) PredictInformationBlock(model, block);
  out->dim = d;
  out->omega.setIdentity();
  if (d == 2) {
    const Eigen::Map<const Eigen::Matrix2d> om(block);
    out->omega.topLeftCorner<2, 2>() = om;
    out->mu = om.inverse() * Eigen::Map<const Eigen::Vector2d>(block + 4);
  } else {
    const Eigen::Map<const Eigen::Matrix4d> om(block);
    out->omega = om;
    out->mu =
        om.llt().solve(Eigen::Map<const Eigen::Vector4d>(block + 16)).head<2>();
  }
  out->logdet_sigma = LogDetSigmaAfter(*out, 0.0);
}

double LogDetSigmaAfter(const PredictedBlock& block, double r) {
  const Eigen::Matrix4d& o = block.omega;
  if (block.dim == 2) return LogDetSigma2(o(0, 0), o(0, 1), o(1, 1), r);
  Eigen::Matrix4d m = o;
  m(0, 0) += r;
  m(1, 1) += r;
  Eigen::LLT<Eigen::Matrix4d> llt(m);
  const Eigen::Matrix4d l = llt.matrixL();
  double logdet = 0.0;
  for (int i = 0; i < 4; ++i) logdet += 2.0 * std::log(l(i, i));
  return -logdet;
}

}  // namespace aia
