// A myopic reference policy from the literature (docs/design.md, Policies).
// Each robot takes the move with the largest one-step drop of its own summed
// log det, predicted with the Riccati map at its current means. Only the part
// of the drop above eps counts (a target already below eps in the robot's
// belief gains nothing), so a robot does not linger at localized targets. Where
// no move gains anything, it steps along a shortest lattice path toward the
// nearest target its own belief still holds above eps.
#ifndef AIA_PLANNING_GREEDY_H_
#define AIA_PLANNING_GREEDY_H_

#include <cstdint>
#include <vector>

#include "aia/core/rng.h"
#include "aia/planning/information.h"
#include "aia/planning/policy.h"
#include "aia/planning/search.h"

namespace aia {

class GreedyPolicy : public NamedPolicy<GreedyPolicy> {
 public:
  static constexpr std::string_view kName = "greedy";
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

 private:
  // BFS toward the nearest observation point of an unlocalized target;
  // kStay when there is none.
  Move TowardNearestTarget(const DecisionContext& ctx, int robot);

  std::vector<Rng> rngs_;
  std::vector<PredictedBlock> blocks_;
  std::vector<Vec2> aims_;          // the targets' predicted means
  std::vector<std::uint8_t> open_;  // above eps in this robot's belief
  TowardNearestAim toward_;
};

}  // namespace aia

#endif  // AIA_PLANNING_GREEDY_H_
