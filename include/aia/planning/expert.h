// The expert (C-SB): the centralized sampling-based planner of docs/design.md
// (Policies) over the whole team and the centralized filter, executed step by
// step. It replans when physics leaves a robot off its planned lattice point,
// when a target moves, when a planned measurement did not happen (the true
// target was not where the mean said), and when the plan is spent.
//
// A missed measurement is remembered: the lattice points from which a static
// target's aim was in sight but nothing was measured rule that part of the
// prior out, and the next plan aims where it has not been searched (so the
// team searches instead of shuttling back to the same points).
#ifndef AIA_PLANNING_EXPERT_H_
#define AIA_PLANNING_EXPERT_H_

#include <memory>
#include <vector>

#include "aia/planning/policy.h"
#include "aia/planning/sampling_tree.h"

namespace aia {

// The expert's parameters (`policy:` keys when policy.name is expert;
// `aia policies`) are the tree's declared settings.
using ExpertParams = SamplingParams;

// The expert's problem at a decision step: the team at its lattice points,
// with the centralized belief as the root (ctx.central must be given).
SamplingProblem ExpertProblem(const DecisionContext& ctx);

class ExpertPolicy : public NamedPolicy<ExpertPolicy> {
 public:
  explicit ExpertPolicy(const ExpertParams& params);
  static constexpr std::string_view kName = "expert";
  static constexpr bool kCentralized = true;
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

  // The plan being executed (for tools and tests).
  const SamplingPlan& plan() const { return plan_; }
  int replans() const { return replans_; }
  // Whether robot i's last decided move was useful work in the plan (it
  // leads to a measurement that counts); false for idle-rule and filler
  // moves (the dataset's weak labels).
  bool LastMoveUseful(int robot) const {
    return robot >= 0 && robot < static_cast<int>(last_useful_.size()) &&
           last_useful_[robot] != 0;
  }
  // Per target, the lattice points from which it was missed so far.
  const std::vector<std::vector<int>>& missed() const { return missed_; }
  // A step it watches without deciding (a shadow that labels only some
  // steps): it records what the team missed, as Decide would, and plans
  // nothing.
  void Observe(const DecisionContext& ctx) { RecordMisses(ctx); }

 private:
  bool NeedsReplan(const DecisionContext& ctx) const;
  void RecordMisses(const DecisionContext& ctx);

  SamplingParams params_;
  SamplingTree tree_;
  Rng rng_;
  SamplingPlan plan_;
  // Per robot, the configuration of plan_ it is at or driving to (in
  // lockstep the same for every robot).
  std::vector<int> at_;
  bool team_best_ = false;  // plan_ was made on the team's best local beliefs
  int replans_ = 0;
  std::vector<int> best_rows_;
  std::vector<char> last_useful_;
  std::vector<std::vector<int>> missed_;
  std::vector<double> last_det_;  // central det Sigma_k at the last decision
  std::unique_ptr<BeliefSet> best_belief_;  // scratch for team-best roots
};

}  // namespace aia

#endif  // AIA_PLANNING_EXPERT_H_
