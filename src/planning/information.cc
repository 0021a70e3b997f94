#include "aia/planning/information.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>

namespace aia {

void PredictBlock(const BeliefSet& beliefs, int row, int k,
                  PredictedBlock* out) {
  const TargetModel& model = beliefs.layout().model(k);
  const int d = model.dim;
  out->dim = d;
  const auto omega = beliefs.Omega(row, k);
  const auto xi = beliefs.Xi(row, k);
  if (d == 2) {
    Eigen::Matrix2d om = omega;
    Eigen::Vector2d x = xi;
    Eigen::Matrix2d sigma = om.inverse();
    Eigen::Vector2d mu = sigma * x;
    if (!model.is_static) {
      const Eigen::Matrix2d A = model.A;
      sigma = A * sigma * A.transpose() + Eigen::Matrix2d(model.Q);
      mu = A * mu + Eigen::Vector2d(model.b);
      om = sigma.inverse();
      om = 0.5 * (om + om.transpose()).eval();
    }
    out->omega.setIdentity();
    out->omega.topLeftCorner<2, 2>() = om;
    out->mu = mu;
    out->logdet_sigma = -std::log(om.determinant());
    return;
  }
  Eigen::Matrix4d om = omega;
  Eigen::Vector4d x = xi;
  Eigen::Matrix4d sigma = om.inverse();
  Eigen::Vector4d mu = sigma * x;
  if (!model.is_static) {
    const Eigen::Matrix4d A = model.A;
    sigma = A * sigma * A.transpose() + Eigen::Matrix4d(model.Q);
    mu = A * mu + Eigen::Vector4d(model.b);
    om = sigma.inverse();
    om = 0.5 * (om + om.transpose()).eval();
  }
  out->omega = om;
  out->mu = mu.head<2>();
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
