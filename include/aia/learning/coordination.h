// The igbnet policy's hand-written coordination layer (docs/learning.md,
// Coordination), kept apart from the scorer (learning/scorer.h) the way
// MuJoCo MPC keeps planners apart from tasks. `policy.coordination: none`
// uses no part of it: each robot takes the network's own most probable
// valid move. `rules` runs these named parts, each with its own parameters
// and counters:
//   observation shapers, which change what the network is shown:
//     MissMemory    (policy.search, policy.share_search) where a robot aims
//                   for a target after it measured nothing there;
//     ClaimsShaper  (policy.claims) which open targets a robot is shown;
//   move arbiters, which choose or change a robot's move:
//     DeadlockWalk  (policy.max_reversals, policy.max_walk) a robot that
//                   undid its last move walks a shortest path to where it
//                   can measure;
//     NoUndo        (policy.no_undo) the network's move that would undo the
//                   last one is replaced;
//     Approach      (policy.approach) where claims have no route plan, a
//                   network move that does not near the robot's owned
//                   targets is replaced by the walk toward them.
// Every part reads what the robot knows (its own belief, its neighbours'
// points in this step's graph, the map, its applied moves) and nothing else.
#ifndef AIA_LEARNING_COORDINATION_H_
#define AIA_LEARNING_COORDINATION_H_

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/fields.h"
#include "aia/learning/network.h"
#include "aia/planning/policy.h"
#include "aia/planning/search.h"

namespace aia {

// policy.coordination (SPEC section 14).
enum class Coordination { kNone, kRules };
constexpr std::array<EnumName<Coordination>, 2> EnumNames(Coordination) {
  return {{{Coordination::kNone, "none"}, {Coordination::kRules, "rules"}}};
}

// Which open targets a robot's heat and reach channels show (policy.claims;
// planning/search.h, TargetClaims): all of them (the network's training
// input); those the robot owns among itself and its neighbours (nearest in
// lattice moves, or helping an owner of two or more); or the first target
// of its route in makespan tours of itself and its neighbours. Where it
// claims none: all of them.
enum class TargetClaimsMode { kNone, kNearest, kRoute };
constexpr std::array<EnumName<TargetClaimsMode>, 3> EnumNames(
    TargetClaimsMode) {
  return {{{TargetClaimsMode::kNone, "none"},
           {TargetClaimsMode::kNearest, "nearest"},
           {TargetClaimsMode::kRoute, "route"}}};
}

// When a target is open for a robot (what claims, the walk and no undo work
// with): while its own det Sigma is above eps; or by what its closed
// neighbourhood holds (planning/search.h, NeighbourhoodHolds): unless a
// robot of it holds the target below refresh x eps, or below eps with the
// neighbourhood's pooled level below eps too.
enum class OpenRule { kOwn, kNeighbours };
constexpr std::array<EnumName<OpenRule>, 2> EnumNames(OpenRule) {
  return {{{OpenRule::kOwn, "own"}, {OpenRule::kNeighbours, "neighbours"}}};
}

// The igbnet policy's parameters (policy.* keys; the model is
// policy.model): which coordination, and the rules' parameters (used only
// with coordination rules; with none a rule's key away from its default is
// refused, since it would do nothing).
struct IgbNetParams {
  Coordination coordination = Coordination::kRules;
  // The network's arithmetic at inference (learning/network.h, Precision).
  Precision precision = Precision::kAuto;
  // DeadlockWalk: a robot whose last `max_reversals` moves each undid the
  // one before is deadlocked. It then walks a shortest lattice path toward
  // the nearest point that sees an open target (where its search memory
  // aims; with claims, one the robot owns where it owns one; else targets a
  // neighbour is nearer to in a straight line are left to it) and hands
  // back to the network once it stands on one. 0: never.
  int max_reversals = 1;
  // Moves a deadlocked robot walks at most before it hands back to the
  // network; 0: until it stands where it can measure.
  int max_walk = 0;
  // MissMemory (planning/search.h, SearchMemory): each robot remembers the
  // points from which it saw a static target's aim but measured nothing;
  // the reach channel and the walk lead to the part of the prior no such
  // point rules out instead of the mean. false: the mean, always.
  bool search = true;
  // With the memory: each robot also takes in the points its neighbours in
  // this step's graph missed (a message beside the belief).
  bool share_search = true;
  // NoUndo: a network move that would undo the robot's last move is not
  // taken: the robot starts the walk instead, or stays where it can measure
  // an open target or has nowhere to walk; a robot with no open target (as
  // `open` below decides it; a tracking mission after success) takes the
  // network's best move that does not undo the last.
  bool no_undo = true;
  // ClaimsShaper: which open targets each robot shows the network (above).
  TargetClaimsMode claims = TargetClaimsMode::kRoute;
  // Approach: where a robot's claims have no route plan (claims nearest, or
  // beyond what TargetClaims::Plans allows) and it
  // owns open targets, a network move that does not bring it nearer, in
  // lattice moves, to a point that measures one of them starts the walk
  // toward the nearest (at scale the network, shown one target a step away,
  // can walk past it for tens of steps).
  bool approach = true;
  // Which targets are open (above).
  OpenRule open = OpenRule::kNeighbours;
  // With open neighbours: a target held below refresh x eps is closed
  // whatever the pooled level (so it opens again some log(1 / refresh) /
  // log(1 / kappa_ii^2) steps before its holder, alone, loses it).
  double refresh = 0.003;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(coordination)
                 .Doc("none: each robot takes the network's own most probable "
                      "valid move, nothing hand-written chooses or changes "
                      "it; rules: the hand-written coordination layer "
                      "(search memory, claims, deadlock walk, no undo; the "
                      "keys below) around the network (docs/learning.md, "
                      "Coordination)"));
    a->Visit(AIA_FIELD(precision).Doc(
        "the network's convolutions at inference: float32 (as trained), "
        "bfloat16 (about three times as fast on a CPU with AMX or AVX-512 "
        "BF16, refused on others) or auto (bfloat16 for teams of 100 robots "
        "or more where the CPU has it, float32 otherwise)"));
    a->Visit(AIA_FIELD(max_reversals)
                 .In(Between(0, 1000))
                 .Doc("rules, deadlock walk: reversals in a row after which a "
                      "robot walks a shortest path toward the nearest point "
                      "that sees an open target, then hands back to the "
                      "network; 0: never"));
    a->Visit(AIA_FIELD(max_walk)
                 .In(Between(0, 100000))
                 .Doc("rules, deadlock walk: moves a deadlocked robot walks at "
                      "most before it hands back to the network; 0: until "
                      "it stands where it can measure"));
    a->Visit(AIA_FIELD(search).Doc(
        "rules, search memory: a robot that saw where a static target is "
        "believed to be and measured nothing aims the reach channel and the "
        "walk at the nearest part of the prior its missed points do not rule "
        "out (false: always the mean)"));
    a->Visit(AIA_FIELD(share_search)
                 .Doc("rules, search memory: each robot also takes in the "
                      "points its neighbours in this step's graph missed "
                      "(false: its own misses only)"));
    a->Visit(AIA_FIELD(no_undo).Doc(
        "rules, no undo: a network move that would undo the robot's last "
        "move is replaced by the deadlock walk, or a stay where the robot "
        "can measure an open target or has nowhere to walk, or, where no "
        "target is open, the network's best move that does "
        "not undo it (false: the network's move)"));
    a->Visit(AIA_FIELD(claims).Doc(
        "rules, claims: which open targets each robot's heat and reach "
        "channels show, worked out by the robot with its neighbours in this "
        "step's graph (distances in lattice moves, walls counted): route, the "
        "first target of its route in makespan tours of the robot and its "
        "neighbours; nearest, those it is nearest to (owning none: those of "
        "an owner of two or more it is the nearest idle robot to); none, all "
        "of them (the network's training input). All of them where it "
        "claims none"));
    a->Visit(AIA_FIELD(approach).Doc(
        "rules, approach: where claims have no route plan for a robot "
        "(claims nearest, or beyond the 40 x 40 robots x open targets or the "
        "40 open targets route plans are made for) and it owns open targets, "
        "a network move that "
        "does not bring it nearer, in lattice moves, to a point that "
        "measures one of them is replaced by the deadlock walk toward the "
        "nearest (false: the network's move)"));
    a->Visit(AIA_FIELD(open).Doc(
        "rules: when a target is open for a robot (what claims, the walk and "
        "no undo work with): own, while its own det Sigma is above eps; "
        "neighbours, unless a robot of its closed neighbourhood in this "
        "step's graph holds it below refresh x eps, or below eps while the "
        "neighbourhood's pooled level is below eps too (at scale a lone "
        "holder's share ebbs into the team: the target opens again before "
        "it is lost)"));
    a->Visit(AIA_FIELD(refresh)
                 .In(Between(1e-12, 1.0))
                 .Doc("rules, open neighbours: a target held below refresh x "
                      "eps is closed whatever the pooled level"));
  }
};

// The key of the first rule parameter of `params` that is not at its
// default ("" when all are): with coordination none such a key would do
// nothing.
std::string FirstRuleKeySet(const IgbNetParams& params);

// The network's most probable valid move at lattice point `here` from its
// kNumMoves `logits` (ties to the lower index), `skip` left out (-1: none);
// -1 where no move is valid.
int BestValidMove(const Lattice& lattice, int here, const float* logits,
                  int skip = -1);

// Robot i's open targets (above eps in its own belief, or by what its
// neighbourhood holds where the context has NeighbourhoodHolds for it; see
// OpenRule) and where it aims for them: the memory's aims where given, else
// its belief's means.
class OpenAims {
 public:
  void Of(const DecisionContext& ctx, int robot, const SearchMemory* memory);
  // Where robot i aims for target k: the memory's aim, else its mean.
  static Vec2 AimOf(const DecisionContext& ctx, int robot, int k,
                    const SearchMemory* memory);
  const std::vector<std::uint8_t>& open() const { return open_; }
  const std::vector<Vec2>& aims() const { return aims_; }
  bool any() const;

 private:
  std::vector<std::uint8_t> open_;
  std::vector<Vec2> aims_;
};

// Observation shaper: the search memory (planning/search.h) kept for the
// team, one row of it per robot.
class MissMemory {
 public:
  MissMemory(bool search, bool share) : search_(search), share_(share) {}
  void Reset(int num_robots, int num_targets);
  // After this step's fusion, before scoring: each active robot of `rows`
  // updates its memory, then (with share) takes in its neighbours' misses.
  // A hand-made context without a sensor, or whose team differs from
  // Reset's, has no memory this step.
  void Update(const DecisionContext& ctx, const std::vector<int>& rows);
  // This step's memory; null where there is none (then: the means).
  const SearchMemory* aims() const { return active_ ? &memory_ : nullptr; }
  const SearchMemory& memory() const { return memory_; }
  // Whether the memory moved robot i's aim of an open target off its mean.
  bool Moved(const DecisionContext& ctx, int robot) const;
  std::vector<std::pair<std::string, long>> Counters() const {
    return {{"misses", memory_.misses()}};
  }

 private:
  bool search_, share_;
  bool active_ = false;
  SearchMemory memory_;
};

// Observation shaper: claims (planning/search.h, TargetClaims). Per row of
// this step's team: the open targets its heat and reach channels show and
// those it owns (which the walk heads for).
class ClaimsShaper {
 public:
  explicit ClaimsShaper(TargetClaimsMode mode) : mode_(mode) {}
  TargetClaimsMode mode() const { return mode_; }
  void Reset() { claims_.Reset(); }
  // Rows are robots `rows`; `memory` their aims (null: the means).
  void Shape(const DecisionContext& ctx, const std::vector<int>& rows,
             const SearchMemory* memory);
  // Per row: the targets shown (empty: every target).
  const std::vector<std::vector<std::uint8_t>>& shown() const { return shown_; }
  // Whether row b is shown fewer than its open targets.
  bool Narrowed(int b) const { return narrowed_[b] != 0; }
  // Row b's owned open targets (one flag per target); null where none were
  // worked out (mode none, no sensor).
  const std::vector<std::uint8_t>* Owned(int b) const;
  // Whether row b is shown the targets it owns, with no route plan (mode
  // nearest, or route beyond TargetClaims::Plans).
  bool Unplanned(int b) const { return unplanned_[b] != 0; }
  // Lattice moves from point p to the nearest point that measures `aim`
  // (-1: out of reach); the fields this step's claims used.
  int Distance(const Vec2& aim, int p) { return claims_.Distance(aim, p); }

 private:
  TargetClaimsMode mode_;
  TargetClaims claims_;
  // Per policy thread.
  struct Scratch {
    OpenAims open;
    std::vector<std::uint8_t> claimed;
    std::vector<int> others;
  };
  std::vector<Scratch> scratch_;
  std::vector<std::vector<std::uint8_t>> shown_, owned_;
  std::vector<std::uint8_t> narrowed_, unplanned_;
};

// Move arbiter: the deadlock walk. A robot whose last `max_reversals` moves
// each undid the one before walks toward the nearest point that sees an
// open target it owns (with claims), else one no neighbour in this step's
// graph is nearer to in a straight line (all open targets when each is),
// keeping the target it chose while that stays open and reachable, and
// hands back to the network where it can measure (or after max_walk moves).
class DeadlockWalk {
 public:
  DeadlockWalk(int max_reversals, int max_walk)
      : max_reversals_(max_reversals), max_walk_(max_walk) {}
  void Reset(int num_robots);
  // Before the network's move: whether robot i walks this step (then its
  // move in *move). `reversals`: its reversals in a row (MoveHistory);
  // `owned`: its owned targets (null: no claims); `memory`: its aims.
  bool Walk(const DecisionContext& ctx, int robot, int reversals,
            const std::vector<std::uint8_t>* owned, const SearchMemory* memory,
            Move* move);
  // Starts a walk now toward a fresh target: its first move (counted), or
  // kStay where the robot can measure an open target or none is reachable.
  Move Start(const DecisionContext& ctx, int robot,
             const std::vector<std::uint8_t>* owned,
             const SearchMemory* memory);
  // Robot i's open targets as the last Walk or Start saw them.
  const OpenAims& open() const { return open_; }
  std::vector<std::pair<std::string, long>> Counters() const {
    return {{"walk_moves", moves_}};
  }

 private:
  // The walk's move for robot i (kStay: it can measure, or nothing is
  // reachable).
  Move Escape(const DecisionContext& ctx, int robot,
              const std::vector<std::uint8_t>* owned,
              const SearchMemory* memory);
  void Grow(int num_robots);
  int max_reversals_, max_walk_;
  // Per robot: moves walked since it was found deadlocked (0: not walking)
  // and the target the walk heads for (-1: none yet).
  std::vector<int> walked_, goal_;
  long moves_ = 0;
  OpenAims open_;
  TowardNearestAim toward_;
  std::vector<std::uint8_t> claimed_;
};

// Move arbiter: no undo. Where the network's move would undo the robot's
// last one, the robot starts the deadlock walk instead, or stays where it
// can measure an open target or has nowhere to walk; a robot with no open
// target (OpenAims: IgbNetParams::open decides, its neighbourhood's holds
// by default) takes the network's best valid move that does not undo the
// last.
class NoUndo {
 public:
  // Robot i's move in place of the network's `best` (which undoes its last
  // move); `logits` its four logits.
  Move Replace(const DecisionContext& ctx, int robot, Move best,
               const float* logits, const std::vector<std::uint8_t>* owned,
               const SearchMemory* memory, DeadlockWalk* walk);
  std::vector<std::pair<std::string, long>> Counters() const {
    return {{"no_undo_stays", stays_}, {"idle_moves", idle_moves_}};
  }
  void Reset() { stays_ = idle_moves_ = 0; }

 private:
  long stays_ = 0, idle_moves_ = 0;
};

// Move arbiter: approach. Where row b has no route plan (ClaimsShaper::
// Unplanned) and owns open targets, a network move that does not bring the
// robot nearer, in lattice moves, to a point that measures one of them
// (nor leaves it on such a point) starts the deadlock walk toward the
// nearest of them.
class Approach {
 public:
  // Whether robot i walks instead of the network's `best` (then its move
  // in *move).
  bool Replace(const DecisionContext& ctx, int robot, Move best,
               const std::vector<std::uint8_t>& owned,
               const SearchMemory* memory, ClaimsShaper* claims,
               DeadlockWalk* walk, Move* move);
  std::vector<std::pair<std::string, long>> Counters() const {
    return {{"approach_walks", walks_}};
  }
  void Reset() { walks_ = 0; }

 private:
  long walks_ = 0;
};

// The layer: the five parts in their order for one step.
class RulesLayer {
 public:
  explicit RulesLayer(const IgbNetParams& params);
  void Reset(int num_robots, int num_targets);
  // Before scoring: the memory, then the claims, for robots `rows`.
  void Shape(const DecisionContext& ctx, const std::vector<int>& rows);
  // What the scorer is shown: per row, the targets (null: all of them) and
  // the aims (null: the means).
  const std::vector<std::vector<std::uint8_t>>* shown() const;
  const SearchMemory* aims() const { return memory_.aims(); }
  // Whether row b's input differs from the unshaped one (claims hid an
  // open target, or the memory moved an aim the input shows).
  bool Shaped(const DecisionContext& ctx, int b, int robot,
              bool shows_aims) const;
  // Before the network's move: the walk's move for row b (robot i), if it
  // walks.
  bool Walk(const DecisionContext& ctx, int b, int robot, Move* move);
  // After it: the move to apply in place of the network's `best` (kStay:
  // none valid); sets *replaced when a part chose another.
  Move Arbitrate(const DecisionContext& ctx, int b, int robot, Move best,
                 const float* logits, bool* replaced);
  std::vector<std::pair<std::string, long>> Counters() const;
  const SearchMemory& memory() const { return memory_.memory(); }

 private:
  IgbNetParams params_;
  MissMemory memory_;
  std::vector<int> deciding_;  // Shape's rows that decide now
  ClaimsShaper claims_;
  DeadlockWalk walk_;
  NoUndo no_undo_;
  Approach approach_;
};

}  // namespace aia

#endif  // AIA_LEARNING_COORDINATION_H_
