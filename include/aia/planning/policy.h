// One interface for every decision maker (random, greedy, expert, Dec-SB,
// I-GBNet). A policy receives what the robots are entitled to see at one
// decision step and returns one move per robot plus a status; expected
// outcomes are statuses, never exceptions.
#ifndef AIA_PLANNING_POLICY_H_
#define AIA_PLANNING_POLICY_H_

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "aia/comm/graph.h"
#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"
#include "aia/world/map.h"

namespace aia {

enum class PolicyStatus {
  kOk,
  kNoValidMove,      // some robot had no valid move and stays
  kBudgetExhausted,  // a planner ran out of budget and returned its best effort
};
inline constexpr int kNumPolicyStatuses = 3;
std::string_view PolicyStatusName(PolicyStatus status);

// A reversal: a lattice move that undoes the robot's last one. A stay is no
// lattice move: it is never a reversal and leaves the last move as it was
// (right, stay, left is a reversal). One definition for every policy and for
// the move observer (runtime/observers.h).
inline constexpr bool IsReversal(Move last, Move next) {
  return last != Move::kStay && next != Move::kStay && next == Opposite(last);
}

// Each robot's last applied lattice move (kStay: none yet) and how many
// moves in a row, ending with it, undid the one before (IsReversal). The
// episode records the moves the world applied; a policy reads them from its
// DecisionContext. Nothing in it depends on the step number.
class MoveHistory {
 public:
  void Reset(int num_robots) {
    last_.assign(num_robots, Move::kStay);
    reversals_.assign(num_robots, 0);
    moves_ = total_reversals_ = 0;
    longest_run_ = 0;
  }
  // Robot i moved by `applied` (a stay changes nothing).
  void Record(int robot, Move applied) {
    if (applied == Move::kStay) return;
    reversals_[robot] =
        IsReversal(last_[robot], applied) ? reversals_[robot] + 1 : 0;
    last_[robot] = applied;
    ++moves_;
    if (reversals_[robot] > 0) ++total_reversals_;
    longest_run_ = std::max(longest_run_, reversals_[robot]);
  }
  int num_robots() const { return static_cast<int>(last_.size()); }
  Move last(int robot) const { return last_[robot]; }
  int reversals(int robot) const { return reversals_[robot]; }
  // Over every robot so far: lattice moves, reversals among them, and the
  // longest run of back-to-back reversals of one robot.
  long moves() const { return moves_; }
  long total_reversals() const { return total_reversals_; }
  int longest_run() const { return longest_run_; }

 private:
  std::vector<Move> last_;
  std::vector<int> reversals_;
  long moves_ = 0, total_reversals_ = 0;
  int longest_run_ = 0;
};

class NeighbourhoodHolds;  // planning/search.h

// What is known at one decision step, and nothing more: the map (no target
// truth, no failure schedule: those are not in it), the sensor model, the
// robots' lattice points, this step's graph and the fused beliefs.
// Distributed policies (random, greedy, Dec-SB, I-GBNet) compute robot i's
// move from robot i's own row of `beliefs`, `comm->Neighbors(i)` and those
// neighbours' positions and rows; for them `central` is null. Only a
// centralized policy (the expert) is given the centralized filter.
struct DecisionContext {
  int step = 0;
  // The policy's decisions before this one in the mission: the step in
  // lockstep; in async one per round (the ready robots decide), while
  // `step` counts the slowest robot's decisions and may repeat. A caller
  // deciding for many missions by turns tells a continued mission by it.
  int round = 0;
  const Map* map = nullptr;
  const SensorModel* sensor = nullptr;
  double eps = 0.1;
  const std::vector<int>* robot_lattice =
      nullptr;  // lattice index of each robot
  // Each robot's position in metres, as the physics left it (it knows its
  // own pose); may be null for hand-made contexts.
  const std::vector<Vec2>* robot_positions = nullptr;
  // Each robot's heading, radians from +x (robots.model diff_drive; 0 for
  // point robots, which have none); may be null.
  const std::vector<double>* robot_headings = nullptr;
  const CommNetwork* comm = nullptr;  // this step's graph and the active robots
  const BeliefSet* beliefs = nullptr;  // robot i's fused belief in row i
  const BeliefSet* central = nullptr;  // the centralized filter; null unless
                                       // the policy is centralized
  // log det Sigma_0^k of each target's prior, what every robot was told
  // (the heatmap's weights); may be null for hand-made contexts.
  const std::vector<double>* log_det_prior = nullptr;
  // The moves the world applied to each robot so far (its last lattice
  // move and its reversals in a row); may be null for hand-made contexts
  // (then no robot has moved yet).
  const MoveHistory* history = nullptr;
  // mission.decisions async: the robots whose moves are wanted now (1: its
  // last move has ended); the others are on their way (or waiting for the
  // point to be free), and their robot_lattice entries are the points they
  // are driving to (what a teammate intends). Null: every robot decides
  // (lockstep). A policy may skip the others; what it writes for them is
  // ignored.
  const std::vector<std::uint8_t>* ready = nullptr;
  // Each robot's own measurements fused this step (what its sensor gave,
  // row i robot i's); may be null for hand-made contexts.
  const std::vector<std::vector<Measurement>>* measurements = nullptr;
  // `beliefs`' log dets and position means this step, worked out once (a
  // policy may set it for its own parts); null: read from `beliefs`.
  const BeliefDigest* digest = nullptr;
  // What each robot's closed neighbourhood holds of each target this step
  // (planning/search.h; a policy may set it for its own parts); null where
  // none was worked out.
  const NeighbourhoodHolds* holds = nullptr;
  // A stamp of what the team knows: `beliefs`, `measurements`, the graph
  // and its active robots (and the mission's eps and priors). Two contexts
  // with the same nonzero stamp have the same of these, so a policy may keep
  // what it worked out from them (in async, a round without a sensing tick
  // or a failure); a context that changes any of them takes a new one
  // (NewKnowledgeStamp). 0: unknown, work everything out.
  std::uint64_t knowledge = 0;
};

// A stamp no context of this process had before (never 0; thread-safe).
std::uint64_t NewKnowledgeStamp();

// Whether what a part worked out from a context's knowledge (the beliefs'
// digest, the heatmaps) still holds for another context: the last Set's
// had the same nonzero stamp and the same beliefs.
class KnowledgeMark {
 public:
  bool Holds(const DecisionContext& ctx) const {
    return ctx.knowledge != 0 && ctx.knowledge == stamp_ &&
           ctx.beliefs == beliefs_;
  }
  // After the work is done.
  void Set(const DecisionContext& ctx) {
    stamp_ = ctx.knowledge;
    beliefs_ = ctx.beliefs;
  }
  void Clear() { *this = KnowledgeMark{}; }

 private:
  std::uint64_t stamp_ = 0;
  const BeliefSet* beliefs_ = nullptr;
};

// Robot (row) i's log det Sigma and position mean of target k, from the
// digest where there is one.
inline double LogDetOf(const DecisionContext& ctx, int row, int k) {
  return ctx.digest ? ctx.digest->LogDet(row, k)
                    : ctx.beliefs->LogDetCovariance(row, k);
}
inline Vec2 MeanOf(const DecisionContext& ctx, int row, int k) {
  return ctx.digest ? ctx.digest->Mean(row, k)
                    : ctx.beliefs->PositionMean(row, k);
}

// Whether robot i decides now (DecisionContext::ready).
inline bool Deciding(const DecisionContext& ctx, int i) {
  return ctx.ready == nullptr || (*ctx.ready)[i] != 0;
}
// The robots of `rows` that decide now, in order (all of them in lockstep).
inline void DecidingRows(const DecisionContext& ctx,
                         const std::vector<int>& rows, std::vector<int>* out) {
  out->clear();
  for (int i : rows)
    if (Deciding(ctx, i)) out->push_back(i);
}

class Policy {
 public:
  virtual ~Policy() = default;
  virtual std::string_view name() const = 0;
  // Whether the policy decides for the whole team from the centralized
  // belief (the expert). Distributed policies are not given it.
  virtual bool centralized() const { return false; }
  // Called once per episode, before the first decision. `seed` is the
  // episode's seed; policies derive their own named streams from it.
  virtual void Reset(const Map& map, int num_robots, int num_targets,
                     std::uint64_t seed) = 0;
  // Writes one move per robot into `moves` (size = number of robots). Moves of
  // inactive robots are ignored. A returned move may be invalid; the world
  // rule replaces it (and counts it).
  virtual PolicyStatus Decide(const DecisionContext& ctx,
                              std::vector<Move>* moves) = 0;
  // Named counts the policy kept since Reset (diagnostics.json's "policy";
  // e.g. how many of igbnet's moves its deadlock rule made). None by
  // default.
  virtual std::vector<std::pair<std::string, long>> Counters() const {
    return {};
  }
};

// Whether a policy class states `static constexpr bool kCentralized = true`.
template <typename P, typename = void>
struct IsCentralizedPolicy : std::false_type {};
template <typename P>
struct IsCentralizedPolicy<P, std::void_t<decltype(P::kCentralized)>>
    : std::bool_constant<P::kCentralized> {};

// A policy class names itself once, for its objects and for the registry
// (PolicyRegistry::Add<P> reads the same constants):
//   class GreedyPolicy : public NamedPolicy<GreedyPolicy> {
//    public:
//     static constexpr std::string_view kName = "greedy";
//     // and, for a centralized one: static constexpr bool kCentralized = true;
template <typename P>
class NamedPolicy : public Policy {
 public:
  std::string_view name() const final { return P::kName; }
  bool centralized() const final { return IsCentralizedPolicy<P>::value; }
};

}  // namespace aia

#endif  // AIA_PLANNING_POLICY_H_
