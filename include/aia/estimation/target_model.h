// Linear-Gaussian model of one target (docs/design.md, Sensing), declared once:
// it is both the scenario's `dynamics:` section and what the filter and the
// planners predict with.
//   x(t+1) = A x(t) + b + w,  w ~ N(0, q I),
// with the state x = [px, py] (A 2x2) or [px, py, vx, vy] (A 4x4). The
// measured part is the position, the first two coordinates (M = [I 0]).
#ifndef AIA_ESTIMATION_TARGET_MODEL_H_
#define AIA_ESTIMATION_TARGET_MODEL_H_

#include <Eigen/Core>

#include "aia/core/fields.h"

namespace aia {

struct TargetModel {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(2, 2);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(2);
  double q = 0.0;

  int dim() const { return static_cast<int>(A.rows()); }
  // A = I, b = 0, q = 0: prediction is the identity. Exact comparisons on
  // purpose: a target with A = I + 1e-12 does move, however slowly.
  bool IsStatic() const;

  // A static target of dimension 2 or 4.
  static TargetModel Static(int dim);

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(
        AIA_FIELD(A)
            .In(Between(-1e3, 1e3))
            .Doc("state transition: 2x2 for a state [px, py], 4x4 for [px, py, "
                 "vx, "
                 "vy]; the identity with b = 0 and q = 0 is a static target"));
    a->Visit(AIA_FIELD(b)
                 .In(Between(-1e4, 1e4))
                 .Doc("constant drift, one entry per row of A (zero "
                      "when not given)"));
    a->Visit(
        AIA_FIELD(q)
            .In(Between(0, 1e6))
            .Doc("process noise: w ~ N(0, q I); positive when A is singular"));
  }
  // A square, 2x2 or 4x4; b sized to A (zero when not given).
  void Validate(const FieldChecker& check);
};

}  // namespace aia

#endif  // AIA_ESTIMATION_TARGET_MODEL_H_
