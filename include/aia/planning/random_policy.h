// The paper's Random-Walker: a uniformly random valid move per robot.
#ifndef AIA_PLANNING_RANDOM_POLICY_H_
#define AIA_PLANNING_RANDOM_POLICY_H_

#include <vector>

#include "aia/core/rng.h"
#include "aia/planning/policy.h"
#include "aia/scenario/config.h"

namespace aia {

// Throws InputError (at the key's line) for any `policy.<key>` parameter not
// in `allowed`.
void CheckPolicyParams(const Scenario& scenario,
                       const std::vector<std::string>& allowed);

class RandomPolicy : public Policy {
 public:
  explicit RandomPolicy(const Scenario& scenario);
  std::string_view name() const override { return "random"; }
  void Reset(const World& world, std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

 private:
  std::vector<Rng> rngs_;  // one stream per robot
};

}  // namespace aia

#endif  // AIA_PLANNING_RANDOM_POLICY_H_
