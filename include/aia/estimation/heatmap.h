// The uncertainty heatmap (docs/rendering.md, The heatmap) (channel 3, heat, of
// I-GBNet's input, and the translucent layer of `aia render --heatmap`): robot
// i's fused belief projected onto a grid over the workspace,
//   H(c) = sum_k w_k exp(-1/2 (c - mu_k)' (Sigma_k + s^2 I)^-1 (c - mu_k)),
//   w_k  = clamp(log(det Sigma_k / eps) / log(det Sigma_0^k / eps), 0, 1),
// with mu_k and Sigma_k the position part of robot i's belief about target k
// and Sigma_0^k its prior. A localized target (det Sigma_k <= eps) leaves no
// heat, an unexplored one (det Sigma_k = det Sigma_0^k) full heat: a peak of
// height 1 at its mean. s (about half the sensor range) widens every Gaussian
// so that a sharp but not yet localized estimate still covers a few cells.
#ifndef AIA_ESTIMATION_HEATMAP_H_
#define AIA_ESTIMATION_HEATMAP_H_

#include <cstdint>
#include <functional>
#include <vector>

#include "aia/core/grid.h"
#include "aia/core/thread_pool.h"
#include "aia/core/types.h"
#include "aia/estimation/belief.h"

namespace aia {

struct HeatmapParams {
  double eps = 0.1;   // the mission's threshold on det Sigma
  double blur = 1.0;  // s, metres (about half the sensor range)
  // Each Gaussian is evaluated only where its exponent is above
  // -cutoff^2 / 2 (inside `cutoff` standard deviations of Sigma + s^2 I):
  // 4 drops terms below exp(-8) = 3.4e-4 of the peak.
  double cutoff = 4.0;
};

// w_k from log det Sigma_k and log det Sigma_0^k (logs keep it finite where
// det itself under- or overflows). If the prior is itself at or below eps,
// the weight is 1 above eps and 0 at or below it.
double HeatWeight(double log_det, double log_det_prior, double eps);
// The same from log(eps), for loops over many targets.
double HeatWeightOfLog(double log_det, double log_det_prior, double log_eps);

// A grid of `cell`-metre cells covering a workspace of the given size
// (ceil(size / cell) cells per axis), zero-filled.
Grid<float> MakeHeatmapGrid(const Vec2& size, double cell);

// Adds weight * exp(-1/2 (c - mu)' (sigma + s^2 I)^-1 (c - mu)) to each cell
// centre c within the cut-off window.
void AddGaussianHeat(const Vec2& mu, const Mat2& sigma, double weight,
                     double blur, double cutoff, Grid<float>* out);

// One target's heat on a grid, kept to be added (or taken away) many times:
// the cells of its cut-off window, row-major, 0 beyond the cut-off ellipse.
struct HeatStamp {
  int x0 = 0, y0 = 0;  // first cell
  int nx = 0, ny = 0;  // window size in cells (0: no heat)
  std::vector<float> values;
};
// The stamp of AddGaussianHeat on grids shaped like `grid` (its values are
// the ones AddGaussianHeat adds, to the bit).
void MakeHeatStamp(const Vec2& mu, const Mat2& sigma, double weight,
                   double blur, double cutoff, const Grid<float>& grid,
                   HeatStamp* out);
// out += stamp (or -= with subtract).
void AddHeatStamp(const HeatStamp& stamp, bool subtract, Grid<float>* out);
// One stamp added to (or taken from) a heatmap.
struct HeatEdit {
  const HeatStamp* stamp = nullptr;
  bool subtract = false;
};

// What the heatmap needs of one target in one belief: the position mean and
// covariance, and log det Sigma of the whole block (what eps judges). Also
// what the learning dataset stores per sample and target.
struct HeatSource {
  Vec2 mean{0.0, 0.0};
  Mat2 cov = Mat2::Identity();
  double log_det = 0.0;
};

// The heat sources of row `row` of `beliefs`, one per target, into `out`
// (resized); means and log dets from `digest` where given (of `beliefs`).
// Without `covariance` the covariances are left as they were (for readers
// of the means and log dets only: a 2 x 2 inverse per robot and target).
void HeatSources(const BeliefSet& beliefs, int row,
                 std::vector<HeatSource>* out,
                 const BeliefDigest* digest = nullptr, bool covariance = true);

// H of these sources into `out` (zeroed first, sized by the caller).
// log_det_prior[k] is log det Sigma_0^k of target k's whole prior block.
void ProjectHeatmap(const std::vector<HeatSource>& sources,
                    const std::vector<double>& log_det_prior,
                    const HeatmapParams& params, Grid<float>* out);

// H for row `row` of `beliefs` into `out`, which must already be sized (its
// cells are those of the projection; see MakeHeatmapGrid). log_det_prior[k]
// is log det Sigma_0^k of target k's whole prior block. The weight uses the
// det of the whole block (what the mission judges against eps), the shape
// the position marginal. Allocates nothing.
void ProjectHeatmap(const BeliefSet& beliefs, int row,
                    const std::vector<double>& log_det_prior,
                    const HeatmapParams& params, Grid<float>* out);

// The heatmaps of many robots of one team at one step (I-GBNet renders one
// per robot). Most robots hold the same belief about most targets (the
// prior, or what a full graph shares), so each target's heat is computed
// once for the block more than half the robots hold (to 2^-40 of its scale:
// float rounding drifts the DKF's copies of one belief apart), into a base
// heatmap, and a robot's heatmap is the base with its own stamp in place of
// that one for each target where its block differs (all robots' own stamps
// for a target without such a majority). A robot's heatmap is a function of
// its own belief and the majority's, so relabelling the robots permutes
// them; it differs from its own ProjectHeatmap only in float rounding. Cost:
// M stamps plus, per robot, the grid and its differing targets, instead of
// N * M stamps.
class TeamHeatmap {
 public:
  // For rows `rows` of `beliefs`, on grids shaped like `grid`; targets, then
  // rows, split over `run`'s `workers` threads when given (the result does
  // not depend on them).
  void Prepare(const BeliefSet& beliefs, const std::vector<int>& rows,
               const std::vector<double>& log_det_prior,
               const HeatmapParams& params, const Grid<float>& grid,
               const RangeRunner& run = {}, int workers = 1);
  // The heatmap of rows[b]: the base itself when the robot holds the
  // majority's belief of every target, else built in `scratch` (shaped like
  // the grid). Thread-safe for distinct scratches once prepared.
  const Grid<float>& Robot(int b, Grid<float>* scratch) const;
  // The heatmap of rows[b] over the targets k with keep[k] set only, built
  // in `scratch` (the same stamps as Robot's, added to zero).
  const Grid<float>& Robot(int b, const std::vector<std::uint8_t>& keep,
                           Grid<float>* scratch) const;
  // The common heatmap: what Robot returns for a robot that holds the
  // majority's belief of every target.
  const Grid<float>& base() const { return base_; }
  // What Robot(b, scratch) applies to a copy of the base, in its order:
  // each of the robot's own targets' common stamp taken away and its own
  // stamp added (empty when Robot returns the base itself).
  void Edits(int b, std::vector<HeatEdit>* out) const;
  // Robot-target pairs whose heat was not the common one (a measure of the
  // work saved).
  long own_stamps() const { return static_cast<long>(own_used_); }

 private:
  struct Own {
    int target;
    HeatStamp stamp;
  };
  std::vector<HeatStamp> common_;  // per target
  Grid<float> base_;
  // Per row: its own stamps (the first robot_used_[b] are this step's; the
  // rest keep their memory).
  std::vector<std::vector<Own>> robot_own_;
  std::vector<int> robot_used_;
  std::size_t own_used_ = 0;
  // Whether row b holds the majority's belief of target k (b * M + k); per
  // worker: one target's keys per row, the majority's blocks.
  std::vector<std::uint8_t> member_;
  struct Scratch {
    std::vector<std::int64_t> keys;
    BeliefSet representative;
  };
  std::vector<Scratch> scratch_;

  // base_ shaped like `grid`, all zeros (its memory kept where the shape is).
  void ResetBase(const Grid<float>& grid);
  // Target k's block that more than half of `rows` hold, if any, as
  // common_[k]'s stamp (else an empty one), its holders marked in member_;
  // w's keys and representative as scratch.
  void CommonStamp(const BeliefSet& beliefs, const std::vector<int>& rows,
                   int k, double log_det_prior, const HeatmapParams& params,
                   const Grid<float>& grid, Scratch* w);
  // The stamps of row `row` (rows[b]) for the targets where it holds another
  // block than the majority's, into robot_own_[b]; returns how many.
  int OwnStamps(const BeliefSet& beliefs, int row, int b,
                const std::vector<double>& log_det_prior,
                const HeatmapParams& params, const Grid<float>& grid);
};

}  // namespace aia

#endif  // AIA_ESTIMATION_HEATMAP_H_
