// The paper's Random-Walker: a uniformly random valid move per robot.
#ifndef AIA_PLANNING_RANDOM_POLICY_H_
#define AIA_PLANNING_RANDOM_POLICY_H_

#include <vector>

#include "aia/core/rng.h"
#include "aia/planning/policy.h"

namespace aia {

class RandomPolicy : public NamedPolicy<RandomPolicy> {
 public:
  static constexpr std::string_view kName = "random";
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

 private:
  std::vector<Rng> rngs_;  // one stream per robot
};

}  // namespace aia

#endif  // AIA_PLANNING_RANDOM_POLICY_H_
