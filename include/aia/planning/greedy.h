// A myopic reference policy from the literature (docs/design.md, Policies).
// Each robot takes the move with the largest one-step drop of its own summed
// log det, predicted with the Riccati map at its current means. Only the part
// of the drop above eps counts (a target already below eps in the robot's
// belief gains nothing), so a robot does not linger at localized targets. Where
// no move gains anything, it steps along a shortest lattice path toward the
// nearest target its own belief still holds above eps.
#ifndef AIA_PLANNING_GREEDY_H_
#define AIA_PLANNING_GREEDY_H_

#include <algorithm>
#include <cstdint>
#include <vector>

#include "aia/core/rng.h"
#include "aia/planning/information.h"
#include "aia/planning/policy.h"
#include "aia/planning/search.h"
#include "aia/world/lattice.h"

namespace aia {

// One target's part of a greedy gain: its log det before a measurement less
// after, counting only the part above log eps.
inline double LogDetDrop(double log_det_before, double log_det_after,
                         double log_eps) {
  return log_det_before - std::max(log_det_after, log_eps);
}

// The greedy rule, which GreedyPolicy applies to each robot's own belief and
// the expert's greedy rollout to the team's information: the moves from
// lattice point p whose gain(q) (q the neighbour it reaches: the drop of the
// open targets' summed log det from measuring at q) is the largest and
// positive, equal within a relative 1e-12, in move order. Writes them to
// `best` (room for kNumMoves) and returns how many (0: no move gains);
// *num_valid counts the moves that stay on the lattice.
template <typename Gain>
int GreedyMoves(const Lattice& lattice, int p, Gain&& gain, Move* best,
                int* num_valid) {
  double top = 0.0;
  int n = 0;
  *num_valid = 0;
  for (Move m : kMoves) {
    const int q = lattice.Next(p, m);
    if (q < 0) continue;
    ++*num_valid;
    const double g = gain(q);
    const double tol = 1e-12 * std::max(1.0, top);
    if (g > top + tol) {
      top = g;
      n = 0;
      best[n++] = m;
    } else if (g > 0.0 && g >= top - tol) {
      best[n++] = m;
    }
  }
  return n;
}

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
