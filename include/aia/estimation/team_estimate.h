// What the team knows about the targets (docs/design.md, Estimation): every
// robot's fused belief (the DKF of filter.h over this step's graph), the
// centralized belief of the same measurements (for centralized policies and
// comparisons), and per target the team's best estimate, the active robot
// whose belief has the smallest det Sigma (TeamBestRows). The episode owns
// one and calls Update once per decision step; policies read its beliefs
// through the DecisionContext. No allocation once built.
#ifndef AIA_ESTIMATION_TEAM_ESTIMATE_H_
#define AIA_ESTIMATION_TEAM_ESTIMATE_H_

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/filter.h"
#include "aia/estimation/sensor_model.h"
#include "aia/estimation/target_model.h"

namespace aia {

class TeamEstimate {
 public:
  // `robots` rows, every one (and the centralized row) at the prior N(means,
  // covs), one entry per target model.
  TeamEstimate(std::vector<TargetModel> models, int robots,
               const std::vector<Eigen::VectorXd>& means,
               const std::vector<Eigen::MatrixXd>& covs);
  // The beliefs point into the layout: an estimate stays where it is.
  TeamEstimate(const TeamEstimate&) = delete;
  TeamEstimate& operator=(const TeamEstimate&) = delete;

  // One step of the filter: the time update (unless `predict` is false: at
  // step 0 the prior is the belief), the DKF over `neighbors` (filter.h,
  // MakeDkfWeights) with each robot's own measurements z[i] taken at
  // positions[i], the centralized update with all of them, then the team's
  // best estimates over the `active` robots. Predict's EstimateDiverged
  // passes through (the caller knows which key to blame). The fusion and
  // the dets of a large team are split over `run` (filter.h, Fuse), with the
  // same numbers for any split. `graph_stamp` (CommNetwork::graph_stamp; 0:
  // unknown) keeps the DKF's weights from the step before while it and
  // kappa_self stay (making them reads every edge).
  void Update(bool predict, const std::vector<std::vector<int>>& neighbors,
              double kappa_self, const std::vector<std::vector<Measurement>>& z,
              const std::vector<Vec2>& positions,
              const std::vector<std::uint8_t>& active,
              const RangeRunner& run = {}, std::uint64_t graph_stamp = 0);

  int num_robots() const { return fused_.rows(); }
  int num_targets() const { return layout_.num_targets(); }
  const BeliefLayout& layout() const { return layout_; }
  // Robot i's fused belief is row i.
  const BeliefSet& fused() const { return fused_; }
  const BeliefSet& central() const { return central_; }
  // det Sigma_i^k of robot i's fused belief.
  double Det(int robot, int target) const;
  // The active robot with the smallest det Sigma_k, or -1 if none is active.
  int BestRobot(int target) const { return best_[target]; }
  // det Sigma_k of that robot's belief (infinity when none is active).
  double MinDet(int target) const { return min_det_[target]; }
  // Targets whose best estimate has det Sigma <= eps.
  int NumLocalized(double eps) const;
  // log det Sigma_0^k per target (the prior the robots were told).
  const std::vector<double>& log_det_prior() const { return log_det_prior_; }

 private:
  void SharedBestRows(const std::vector<std::uint8_t>& active);

  BeliefLayout layout_;
  BeliefSet predicted_, fused_, central_;
  DkfWeights weights_;
  std::uint64_t weights_stamp_ = 0;
  double weights_kappa_ = 0.0;
  // det_: det Sigma of each row's own blocks (every block's while fused_
  // shares none); det_common_: of each target's common block.
  std::vector<double> det_, det_common_, min_det_, log_det_prior_;
  std::vector<int> best_, active_rows_;
};

}  // namespace aia

#endif  // AIA_ESTIMATION_TEAM_ESTIMATE_H_
