// The `igbnet` policy (docs/learning.md): robot i's move from its own fused
// belief, its neighbours' positions in this step's graph and the map only.
// Each step renders every active robot's channels (learning/channels.h),
// runs one batched forward for the team and takes each robot's most
// probable valid move. The model is loaded once per process (shared by
// every episode and thread that uses the same file).
#ifndef AIA_LEARNING_IGBNET_POLICY_H_
#define AIA_LEARNING_IGBNET_POLICY_H_

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aia/core/fields.h"
#include "aia/learning/channels.h"
#include "aia/learning/network.h"
#include "aia/planning/policy.h"
#include "aia/planning/registry.h"
#include "aia/planning/search.h"

namespace aia {

// Where `policy.model` points when a scenario does not say: models/igbnet.pt
// under the working folder if it is there, else under the source tree.
std::string DefaultModelPath();

// The model at `path`, loaded once per process; errors as IgbNet::Load.
std::shared_ptr<const IgbNet> LoadModelOnce(const std::string& path,
                                            const std::string& error_file,
                                            int error_line,
                                            const std::string& key);

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

// The policy's parameters (policy.* keys; the model is policy.model).
struct IgbNetParams {
  // The deadlock rule (docs/learning.md, Action selection): a robot whose
  // last `max_reversals` moves each undid the one before is deadlocked. It
  // then walks a shortest lattice path toward the nearest point that sees
  // an open target (where its search memory aims; with claims, one the
  // robot owns where it owns one; else targets a neighbour is nearer to
  // in a straight line are left to it) and hands back to the network once
  // it stands on one. 0: the most probable valid move, always (the paper's).
  int max_reversals = 1;
  // Moves a deadlocked robot walks at most before it hands back to the
  // network; 0: until it stands where it can measure.
  int max_walk = 0;
  // The search memory (planning/search.h; docs/learning.md, Search memory):
  // each robot remembers the points from which it saw a static target's
  // aim but measured nothing; channel 4 and the deadlock rule lead to the
  // part of the prior no such point rules out instead of the mean. false:
  // the mean, always.
  bool search = true;
  // With the search memory: each robot also takes in the points its
  // neighbours in this step's graph missed (a message beside the belief).
  bool share_search = true;
  // A network move that would undo the robot's last move is not taken: the
  // robot starts the deadlock rule's walk instead, or stays where it can
  // measure an open target or has nowhere to walk (a stay is no reversal);
  // a robot with no open target in its own belief (a tracking mission after
  // success) takes the network's best move that does not undo the last.
  bool no_undo = true;
  // Which open targets each robot shows the network (above).
  TargetClaimsMode claims = TargetClaimsMode::kRoute;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(max_reversals)
                 .In(Between(0, 1000))
                 .Doc("deadlock rule: reversals in a row after which a robot "
                      "walks a shortest path toward the nearest point that "
                      "sees an open target, then hands back to the network; "
                      "0: off, the paper's argmax"));
    a->Visit(AIA_FIELD(max_walk)
                 .In(Between(0, 100000))
                 .Doc("deadlock rule: moves a deadlocked robot walks at "
                      "most before it hands back to the network; 0: until "
                      "it stands where it can measure"));
    a->Visit(AIA_FIELD(search).Doc(
        "search memory: a robot that saw where a static target is believed "
        "to be and measured nothing aims channel 4 and the deadlock rule at "
        "the nearest part of the prior its missed points do not rule out "
        "(false: always the mean)"));
    a->Visit(AIA_FIELD(share_search)
                 .Doc("search memory: each robot also takes in the points its "
                      "neighbours in this step's graph missed (false: its own "
                      "misses only)"));
    a->Visit(AIA_FIELD(no_undo).Doc(
        "a network move that would undo the robot's last move is replaced "
        "by the deadlock rule's walk, or a stay where the robot can measure "
        "an open target or has nowhere to walk, or, where no target is open "
        "in its own belief, the network's best move that does not undo it "
        "(false: the network's move)"));
    a->Visit(AIA_FIELD(claims).Doc(
        "which open targets each robot's heat and reach channels show, "
        "worked out by the robot with its neighbours in this step's graph "
        "(distances in lattice moves, walls counted): route, the first "
        "target of its route in makespan tours of the robot and its "
        "neighbours; nearest, those it is nearest to (owning none: those of "
        "an owner of two or more it is the nearest idle robot to); none, all "
        "of them (the network's training input). All of them where it "
        "claims none"));
  }
};

class IgbNetPolicy : public NamedPolicy<IgbNetPolicy> {
 public:
  explicit IgbNetPolicy(std::shared_ptr<const IgbNet> net,
                        IgbNetParams params = {});
  static constexpr std::string_view kName = "igbnet";
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;
  // What each robot learned from its missed measurements (empty until the
  // first decision; unused with `search` false).
  const SearchMemory& search() const { return search_; }
  // decisions (robot moves decided), rule_moves (made by the deadlock
  // rule), rule_stays (no_undo's stays), idle_moves (no_undo's moves of a
  // robot with nothing open), misses (points added to the search memory),
  // since Reset.
  std::vector<std::pair<std::string, long>> Counters() const override;
  // The last step's logits, robot-major (4 per robot; zero for inactive
  // robots), for tools and tests.
  const std::vector<float>& logits() const { return logits_; }

 private:
  // Robots in one forward of the network.
  static constexpr int kForwardBatch = 32;
  // Renders the images of robots `rows_` into images_ and their logits into
  // batch_logits_, on libtorch's threads (scratch reused: nothing is
  // allocated once warm but by libtorch's forward).
  void RenderAndForward(const DecisionContext& ctx);

  std::shared_ptr<const IgbNet> net_;
  IgbNetParams params_;
  std::optional<ChannelRenderer> renderer_;
  // Per robot, what the deadlock rule remembers: its lattice point at the
  // last decision (-1: none yet), the move that brought it to its current
  // one (kStay: none) and how many moves in a row undid the one before.
  std::vector<int> last_point_;
  std::vector<Move> last_move_;
  std::vector<int> reversals_;
  // Moves walked since the robot was found deadlocked (0: not walking).
  std::vector<int> walked_;
  // The target a walk heads for, chosen at its first move and kept until
  // the robot can measure, the target is localized or it cannot be reached
  // (-1: none yet), so that claims that change as the robots move do not
  // turn the walk around.
  std::vector<int> goal_;
  long decisions_ = 0, rule_moves_ = 0, rule_stays_ = 0, idle_moves_ = 0;
  SearchMemory search_;
  bool searching_ = false;  // this step's aims are search_'s
  // The deadlock rule's move for robot i: toward the nearest point that sees
  // the aim of the walk's target (goal_), or, choosing one, of an open
  // target no neighbour in this step's graph is nearer to (all open targets
  // when each is); kStay where the robot sees one, or none is reachable.
  // Scratch: toward_, aims_, open_, claimed_.
  Move Escape(const DecisionContext& ctx, int i);
  TowardNearestAim toward_;
  std::vector<Vec2> aims_;
  std::vector<std::uint8_t> open_, claimed_;
  std::vector<float> images_, batch_logits_, logits_;
  std::vector<int> rows_;
  // Each robot's row in rows_ (-1: inactive).
  std::vector<int> row_of_;
  // Message passing (a model with message_hops > 0): the rows' hidden
  // features and their graph in row indices.
  std::vector<float> features_;
  TeamGraph graph_;
  TeamHeatmap heat_;
  // Per worker thread (ParallelFor): a heatmap and the neighbours' points.
  std::vector<Grid<float>> worker_heat_;
  std::vector<std::vector<Vec2>> worker_neighbours_;
  std::vector<std::vector<HeatSource>> worker_targets_;  // channel 4
  std::vector<double> no_prior_;
  // Robot i's open targets (above eps in its own belief) into open_ and
  // their aims (the search memory's, else the means) into aims_.
  void OpenAims(const DecisionContext& ctx, int i);
  // With `claims`: per row, the targets whose heat it is shown (empty: all).
  void ClaimTargets(const DecisionContext& ctx);
  TargetClaims claims_;
  std::vector<std::vector<std::uint8_t>> keep_;
  // Per row, the open targets the robot owns (TargetClaims::Claim; empty:
  // none worked out), which the deadlock rule's walk heads for.
  std::vector<std::vector<std::uint8_t>> owned_;
  std::vector<int> others_;
};

// Adds `igbnet` to a registry.
void AddLearnedPolicies(PolicyRegistry* registry);

}  // namespace aia

#endif  // AIA_LEARNING_IGBNET_POLICY_H_
