// The expert (C-SB): the centralized sampling-based planner of SPEC section 7
// over the whole team and the centralized filter, executed step by step. It
// replans when physics leaves a robot off its planned lattice point, when a
// target moves, when a planned measurement did not happen (the true target
// was not where the mean said), and when the plan is spent.
#ifndef AIA_PLANNING_EXPERT_H_
#define AIA_PLANNING_EXPERT_H_

#include <memory>
#include <vector>

#include "aia/core/fields.h"
#include "aia/planning/policy.h"
#include "aia/planning/sampling_tree.h"

namespace aia {

// The expert's declared parameters (`policy:` keys when policy.name is
// expert; `aia policies`).
struct ExpertParams {
  double p_v = 0.9;
  double p_u = 0.9;
  long anytime = 20000;
  long max_iterations = 200000;
  long max_nodes = 2000000;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(p_v).In(kUnit).Doc(
        "f_V: probability of growing the newest branch (its deepest node) "
        "rather than a node of a uniformly drawn level"));
    a->Visit(AIA_FIELD(p_u).In(kUnit).Doc(
        "f_U: probability that a robot steps along the BFS field toward its "
        "assigned target rather than at random"));
    a->Visit(AIA_FIELD(anytime).In(Between(0, 1e9)).Doc(
        "sampling iterations after the first goal (`aia plan --budget`)"));
    a->Visit(AIA_FIELD(max_iterations)
                 .In(Between(1, 1e10))
                 .Doc("iterations allowed before a first goal"));
    a->Visit(AIA_FIELD(max_nodes).In(Between(2, 1e9)).Doc("tree size cap"));
  }

  SamplingParams Sampling() const;
};

// The expert's problem at a decision step: the team at its lattice points,
// with the centralized belief as the root (ctx.central must be given).
SamplingProblem ExpertProblem(const DecisionContext& ctx);

class ExpertPolicy : public Policy {
 public:
  explicit ExpertPolicy(const ExpertParams& params);
  std::string_view name() const override { return "expert"; }
  bool centralized() const override { return true; }
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;

  // The plan being executed (for tools and tests).
  const SamplingPlan& plan() const { return plan_; }
  int replans() const { return replans_; }

 private:
  bool NeedsReplan(const DecisionContext& ctx) const;

  SamplingParams params_;
  SamplingTree tree_;
  Rng rng_;
  SamplingPlan plan_;
  int index_ = 0;           // position of the team in plan_.configs
  bool team_best_ = false;  // plan_ was made on the team's best local beliefs
  int replans_ = 0;
  std::vector<int> best_rows_;
  std::unique_ptr<BeliefSet> best_belief_;  // scratch for team-best roots
};

}  // namespace aia

#endif  // AIA_PLANNING_EXPERT_H_
