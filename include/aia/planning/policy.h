// One interface for every decision maker (random, greedy, expert, Dec-SB,
// I-GBNet). A policy receives what the robots are entitled to see at one
// decision step and returns one move per robot plus a status; expected
// outcomes are statuses, never exceptions.
#ifndef AIA_PLANNING_POLICY_H_
#define AIA_PLANNING_POLICY_H_

#include <cstdint>
#include <string_view>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"
#include "aia/world/world.h"

namespace aia {

enum class PolicyStatus {
  kOk,
  kNoValidMove,      // some robot had no valid move and stays
  kBudgetExhausted,  // a planner ran out of budget and returned its best effort
};

// What is known at one decision step. Distributed policies (random, greedy,
// Dec-SB, I-GBNet) compute robot i's move from robot i's own row of `beliefs`,
// `comm->Neighbors(i)` and those neighbours' positions and rows only; the
// expert alone may read `central` and every robot's position.
struct DecisionContext {
  int step = 0;
  const World* world = nullptr;  // map and lattice, known to every robot
  const SensorModel* sensor = nullptr;
  double eps = 0.1;
  const std::vector<int>* positions = nullptr;  // lattice index of each robot
  const CommNetwork* comm = nullptr;  // this step's graph and the active robots
  const BeliefSet* beliefs =
      nullptr;  // robot i's fused (posterior) belief in row i
  const BeliefSet* central = nullptr;  // the centralized filter, one row
};

class Policy {
 public:
  virtual ~Policy() = default;
  virtual std::string_view name() const = 0;
  // Called once per episode, before the first decision. `seed` is the
  // episode's seed; policies derive their own named streams from it.
  virtual void Reset(const World& world, std::uint64_t seed) = 0;
  // Writes one move per robot into `moves` (size = number of robots). Moves of
  // inactive robots are ignored. A returned move may be invalid; the world
  // rule replaces it (and counts it).
  virtual PolicyStatus Decide(const DecisionContext& ctx,
                              std::vector<Move>* moves) = 0;
};

}  // namespace aia

#endif  // AIA_PLANNING_POLICY_H_
