// Dec-SB (Tzes et al. 2021; SPEC section 7): each robot grows its own
// sampling tree over its own moves and its own DKF belief, with a receding
// horizon. Per step, neighbours exchange nothing but their beliefs (through
// the DKF) and their planned next positions: a robot counts what its
// neighbours will measure there as already gathered, so robots spread over
// the targets. It replans every step and takes the first move of its plan.
#ifndef AIA_PLANNING_DECSB_H_
#define AIA_PLANNING_DECSB_H_

#include <vector>

#include "aia/planning/policy.h"
#include "aia/planning/sampling_tree.h"
#include "aia/scenario/config.h"

namespace aia {

class DecSbPolicy : public Policy {
 public:
  explicit DecSbPolicy(const Scenario& scenario);
  std::string_view name() const override { return "decsb"; }
  void Reset(const World& world, std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

 private:
  SamplingParams params_;
  SamplingTree tree_;
  std::vector<Rng> rngs_;
  std::vector<std::vector<int>>
      plans_;              // each robot's last plan (lattice points)
  std::vector<int> next_;  // the planned next position each robot announces
  std::vector<double> extra_;
};

}  // namespace aia

#endif  // AIA_PLANNING_DECSB_H_
