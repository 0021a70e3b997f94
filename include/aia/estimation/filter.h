// The information filter and the distributed Kalman filter (DKF;
// docs/design.md, Estimation), written per target block:
//   predict:  Sigma^- = A Sigma A' + q I,  mu^- = A mu + b
//   fuse:     Omega_i = sum_{j in N_i + i} kappa_ij Omega_j^- + Z_i,
//             xi_i    = sum_{j in N_i + i} kappa_ij xi_j^-
//                       + M' R_i^-1 (y_i + p_i)
//   central:  Omega   = Omega^- + sum_i Z_i
// with Z_i = M' R_i^-1 M for the targets robot i sees.
#ifndef AIA_ESTIMATION_FILTER_H_
#define AIA_ESTIMATION_FILTER_H_

#include <Eigen/Core>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "aia/core/thread_pool.h"
#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"

namespace aia {

// Largest variance (m^2) a filter's prediction may reach: a standard
// deviation of 1e12 m is far beyond any workspace, and det Sigma of a 4-D
// state stays a finite double below it.
inline constexpr double kMaxVariance = 1e24;
// Smallest predicted variance: added to the diagonal of a prediction that
// falls below it, so that Omega stays finite.
inline constexpr double kMinVariance = 1e-30;
// Largest entry of a filter's predicted mean (m, or m/s for a velocity):
// as far beyond any workspace as kMaxVariance's standard deviation.
inline constexpr double kMaxMean = 1e12;

// The filter cannot go on: a target's predicted covariance grows past
// kMaxVariance (unstable dynamics and no measurements) or is not finite.
// `target` is the target's index (-1 when not known).
class EstimateDiverged : public std::runtime_error {
 public:
  EstimateDiverged(int target, const std::string& what)
      : std::runtime_error(what), target_(target) {}
  int target() const { return target_; }

 private:
  int target_;
};

// One time update of every row (identity for static targets). A row whose
// predicted variance of a target passes kMaxVariance is scaled back to it,
// and a mean entry beyond kMaxMean is held at it; when that happens to
// every row in `active` (all rows when null), no estimate of the target is
// left and EstimateDiverged is thrown for it. A failed or cut-off robot's
// own belief of an unstable target thus grows to the bounds without ending
// a mission in which other robots measure it.
// Large sets split their rows over `run` (as Fuse below), with the same
// numbers and the same error for any split.
void Predict(BeliefSet* beliefs,
             const std::vector<std::uint8_t>* active = nullptr,
             const RangeRunner& run = {});

// The time update of one target block stored as Omega (dim x dim,
// column-major) followed by xi (dim), in place. Callers skip static targets
// (BeliefLayout::is_static), whose update is the identity. For planners
// looking ahead: a variance past kMaxVariance is scaled back to it.
void PredictInformationBlock(const TargetModel& model, double* block);

// The same for Omega alone (dim x dim, column-major), for planners that
// predict covariance without means (the separation principle).
void PredictInformationMatrix(const TargetModel& model, double* omega);

// Adds one robot's measurements (taken at position p) to one row:
// Omega^k += r I on the position block, xi^k += r (y + p).
void AddMeasurements(const std::vector<Measurement>& z, const Vec2& p,
                     BeliefSet* beliefs, int row);

// DKF weights: W(i,i) = kappa_self and W(i,j) = (1 - kappa_self) / |N_i| for j
// in N_i; an isolated robot keeps W(i,i) = 1. neighbors[i] lists the robots
// whose messages robot i received this step (i itself excluded).
void FusionWeights(const std::vector<std::vector<int>>& neighbors,
                   double kappa_self, Eigen::MatrixXd* W);

// out = W * predicted, then each robot's own measurements are added.
// `out` must not alias `predicted`. A general W (any weights) for tests and
// tools; the episode fuses with DkfWeights.
void Fuse(const BeliefSet& predicted, const Eigen::MatrixXd& W,
          const std::vector<std::vector<Measurement>>& z,
          const std::vector<Vec2>& positions, BeliefSet* out);

// The DKF's weights without the N x N matrix: W(i,i) = self[i], W(i,j) =
// off[i] for j in (*neighbors)[i] (ascending, i excluded), as FusionWeights
// makes them (MakeDkfWeights checks the lists; the sums below rely on it).
// `neighbors` must outlive its use.
struct DkfWeights {
  std::vector<double> self, off;
  const std::vector<std::vector<int>>* neighbors = nullptr;
};
void MakeDkfWeights(const std::vector<std::vector<int>>& neighbors,
                    double kappa_self, DkfWeights* w);
// Fuse with these weights: the same numbers, to the bit, as Fuse with the
// FusionWeights matrix. Where most rows' neighbours are every other robot
// (a full graph, a few messages lost or robots failed) `out` comes out
// shared (BeliefSet): O(M x the blocks that differ from the common one +
// N) a step; otherwise row by row, O(N * stride) for a dense graph and
// O(edges * stride) for a sparse one, `out` sharing nothing. Large sets
// (rows x stride of 2^18 doubles or more, about 200 robots and targets)
// split their targets or rows over `run`, with the same numbers for any
// split. Row by row, `row_done(i)`, where given, is called once row i is
// final, on the thread that fused it (a reader of that row alone may run
// there); a shared `out` calls it for no row (read its common and own
// blocks).
void Fuse(const BeliefSet& predicted, const DkfWeights& w,
          const std::vector<std::vector<Measurement>>& z,
          const std::vector<Vec2>& positions, BeliefSet* out,
          const RangeRunner& run = {},
          const std::function<void(int row)>& row_done = {});

// The centralized filter: one row, every robot's measurements added.
void CentralUpdate(const std::vector<std::vector<Measurement>>& z,
                   const std::vector<Vec2>& positions, BeliefSet* central);

// Whether every block of every row is symmetric positive definite (within tol).
bool AllBlocksSpd(const BeliefSet& beliefs, double tol = 1e-9);

}  // namespace aia

#endif  // AIA_ESTIMATION_FILTER_H_
