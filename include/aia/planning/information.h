// The planners' measurement prediction (docs/design.md, Sensing): a robot at p
// is predicted to measure a target believed at mu when |mu - p| <= range and
// the line of sight is free, with precision 1 / (sigma0 + eta |mu - p|)^2.
// Measurements are not needed to predict covariance (separation principle).
#ifndef AIA_PLANNING_INFORMATION_H_
#define AIA_PLANNING_INFORMATION_H_

#include <Eigen/Core>
#include <cmath>

#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"
#include "aia/world/lattice.h"
#include "aia/world/map.h"

namespace aia {

// The half side, in lattice steps, of the window around the lattice point
// nearest a target that holds every point that can measure it: the
// sensor's range in steps, rounded up, plus one.
inline int SensorSpan(const Lattice& lattice, const SensorModel& sensor) {
  return static_cast<int>(std::ceil(sensor.range / lattice.step())) + 1;
}

// r such that Z = r M'M, or 0 when no measurement is predicted.
inline double PredictedPrecision(const Map& map, const SensorModel& sensor,
                                 const Vec2& p, const Vec2& mu) {
  const double d = (mu - p).norm();
  if (!sensor.InRange(d)) return 0.0;
  if (sensor.line_of_sight && !map.LineOfSight(p, mu)) return 0.0;
  return sensor.Precision(d);
}

// log det Sigma of a 2x2 information block Omega = [[a, b], [b, c]] after
// adding r to its diagonal: -log((a + r)(c + r) - b^2).
inline double LogDetSigma2(double a, double b, double c, double r) {
  return -std::log((a + r) * (c + r) - b * b);
}

// One target block of one belief row after the time update (the Riccati
// map's prediction): Omega^- = (A Sigma A' + Q)^-1 and mu^- = A mu + b. Fixed
// size so that planners allocate nothing per step.
struct PredictedBlock {
  int dim = 2;
  Eigen::Matrix4d omega =
      Eigen::Matrix4d::Identity();  // top-left dim x dim used
  Vec2 mu{0.0, 0.0};                // predicted position mean
  double logdet_sigma = 0.0;        // log det Sigma^-
};

// Predicts block k of `row` one step ahead (identity for static targets).
void PredictBlock(const BeliefSet& beliefs, int row, int k,
                  PredictedBlock* out);

// log det Sigma after adding r I to the position block of `block.omega`.
double LogDetSigmaAfter(const PredictedBlock& block, double r);

}  // namespace aia

#endif  // AIA_PLANNING_INFORMATION_H_
