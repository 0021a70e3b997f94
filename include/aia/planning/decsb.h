// Dec-SB (Tzes et al. 2021; docs/design.md, Policies): each robot grows its own
// sampling tree over its own moves and its own DKF belief, with a receding
// horizon. Per step, neighbours exchange nothing but their beliefs (through
// the DKF) and their planned next positions: a robot counts what its
// neighbours will measure there as already gathered, so robots spread over
// the targets. It replans every step and takes the first move of its plan.
#ifndef AIA_PLANNING_DECSB_H_
#define AIA_PLANNING_DECSB_H_

#include <vector>

#include "aia/core/fields.h"
#include "aia/planning/policy.h"
#include "aia/planning/sampling_tree.h"

namespace aia {

// Dec-SB's declared parameters.
struct DecSbParams {
  double p_v = SamplingParams{}.p_v;
  double p_u = SamplingParams{}.p_u;
  int horizon = 15;
  long iterations = 300;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(p_v).In(kUnit).Doc(
        "f_V: probability of growing the newest branch"));
    a->Visit(AIA_FIELD(p_u).In(kUnit).Doc(
        "f_U: probability of stepping toward the assigned target"));
    a->Visit(
        AIA_FIELD(horizon).In(Between(1, 1000)).Doc("receding horizon, moves"));
    a->Visit(AIA_FIELD(iterations)
                 .In(Between(1, 1e7))
                 .Doc("sampling iterations per robot per step (a goal ends "
                      "the search early, after a quarter as many more)"));
  }

  SamplingParams Sampling() const;
};

namespace internal {

// Targets by grid cell (CSR: cell c holds items[start[c] .. start[c + 1])).
struct TargetGrid {
  std::vector<int> start, fill, items;
};

// Below this many position x target pairs AnnouncedPrecision evaluates
// every pair; above, only the targets within sensor range of each position.
constexpr long kGridPairs = 4096;

// extra[k] = the sum over `announced` (in order) of the precision a robot
// there is predicted to measure of a target at means[k]
// (PredictedPrecision): the same numbers by either way, O(|announced| x
// targets nearby) by the grid.
void AnnouncedPrecision(const Map& map, const SensorModel& sensor,
                        const std::vector<Vec2>& announced,
                        const std::vector<Vec2>& means, long grid_pairs,
                        TargetGrid* grid, std::vector<double>* extra);

}  // namespace internal

class DecSbPolicy : public NamedPolicy<DecSbPolicy> {
 public:
  explicit DecSbPolicy(const DecSbParams& params);
  static constexpr std::string_view kName = "decsb";
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

 private:
  SamplingParams params_;
  SamplingTree tree_;
  std::vector<Rng> rngs_;
  std::vector<std::vector<int>>
      plans_;              // each robot's last plan (lattice points)
  std::vector<int> next_;  // the planned next position each robot announces
  // Decide's scratch: a robot's neighbours' announced positions, its own
  // means, what those positions will measure of each target.
  std::vector<Vec2> announced_, means_;
  std::vector<double> extra_;
  internal::TargetGrid grid_;
};

}  // namespace aia

#endif  // AIA_PLANNING_DECSB_H_
