#include "aia/planning/expert.h"

#include <cmath>

#include "aia/core/error.h"
#include "aia/planning/random_policy.h"

namespace aia {
namespace {

double Param(const Scenario& s, const std::string& key, double fallback,
             double lo, double hi, bool integer) {
  const auto it = s.policy.params.find(key);
  if (it == s.policy.params.end()) return fallback;
  const double v = it->second;
  const std::string full = "policy." + key;
  if (!(v >= lo && v <= hi) || (integer && v != std::floor(v))) {
    throw InputError(s.file, s.LineOf(full), full,
                     std::string("must be ") +
                         (integer ? "an integer" : "a number") + " in [" +
                         std::to_string(lo) + ", " + std::to_string(hi) +
                         "], got " + std::to_string(v));
  }
  return v;
}

}  // namespace

SamplingParams ExpertParams(const Scenario& s) {
  CheckPolicyParams(s,
                    {"p_v", "p_u", "anytime", "max_iterations", "max_nodes"});
  SamplingParams p;
  p.p_v = Param(s, "p_v", p.p_v, 0.0, 1.0, false);
  p.p_u = Param(s, "p_u", p.p_u, 0.0, 1.0, false);
  p.anytime = static_cast<long>(Param(s, "anytime", p.anytime, 0, 1e9, true));
  p.max_iterations = static_cast<long>(
      Param(s, "max_iterations", p.max_iterations, 1, 1e10, true));
  p.max_nodes =
      static_cast<long>(Param(s, "max_nodes", p.max_nodes, 2, 1e9, true));
  return p;
}

SamplingProblem ExpertProblem(const DecisionContext& ctx) {
  SamplingProblem p;
  p.world = ctx.world;
  p.sensor = ctx.sensor;
  p.eps = ctx.eps;
  p.start = *ctx.positions;
  p.active = ctx.comm->active();
  p.belief = ctx.central;
  p.belief_row = 0;
  return p;
}

ExpertPolicy::ExpertPolicy(const Scenario& scenario)
    : params_(ExpertParams(scenario)) {}

void ExpertPolicy::Reset(const World&, std::uint64_t seed) {
  rng_ = Rng(seed, "policy.expert");
  plan_ = SamplingPlan{};
  index_ = 0;
  replans_ = 0;
  team_best_ = false;
}

bool ExpertPolicy::NeedsReplan(const DecisionContext& ctx) const {
  if (plan_.configs.empty() ||
      index_ + 1 >= static_cast<int>(plan_.configs.size()))
    return true;
  if (!ctx.beliefs->layout().all_static()) return true;  // targets move
  if (*ctx.positions != plan_.configs[index_])
    return true;  // physics disagreed
  if (team_best_) return false;
  // A planned measurement that did not happen: the centralized belief is far
  // less certain than the plan predicted for this step.
  for (int k = 0; k < ctx.central->layout().num_targets(); ++k) {
    const double actual = ctx.central->DetCovariance(0, k);
    if (actual > ctx.eps && actual > 2.0 * plan_.det[index_][k]) return true;
  }
  return false;
}

PolicyStatus ExpertPolicy::Decide(const DecisionContext& ctx,
                                  std::vector<Move>* moves) {
  const Lattice& lattice = ctx.world->lattice;
  if (NeedsReplan(ctx)) {
    SamplingProblem problem = ExpertProblem(ctx);
    // When the centralized belief is already below eps everywhere but no
    // single robot's is (the DKF lags the centralized filter), plan on the
    // team's best local beliefs instead, so that targets get re-measured.
    bool central_done = true;
    for (int k = 0; k < ctx.central->layout().num_targets(); ++k)
      central_done =
          central_done && ctx.central->DetCovariance(0, k) <= ctx.eps;
    team_best_ = central_done;
    if (team_best_) {
      const BeliefSet& b = *ctx.beliefs;
      if (!best_rows_ || best_rows_->data().cols() != b.data().cols())
        best_rows_ = std::make_unique<BeliefSet>(&b.layout(), 1);
      for (int k = 0; k < b.layout().num_targets(); ++k) {
        int best = -1;
        for (int i = 0; i < b.rows(); ++i) {
          if (!ctx.comm->Active(i)) continue;
          if (best < 0 || b.DetCovariance(i, k) < b.DetCovariance(best, k))
            best = i;
        }
        if (best < 0) best = 0;
        best_rows_->Omega(0, k) = b.Omega(best, k);
        best_rows_->Xi(0, k) = b.Xi(best, k);
      }
      problem.belief = best_rows_.get();
    }
    plan_ = tree_.Solve(problem, params_, rng_);
    index_ = 0;
    ++replans_;
  }
  PolicyStatus status = plan_.status;
  const bool has_next = index_ + 1 < static_cast<int>(plan_.configs.size());
  for (int i = 0; i < static_cast<int>(moves->size()); ++i) {
    Move m = Move::kStay;
    if (has_next)
      m = MoveBetween(lattice, plan_.configs[index_][i],
                      plan_.configs[index_ + 1][i]);
    if (m == Move::kStay && ctx.comm->Active(i)) {
      // Nothing planned for this robot (depth-0 plan or no valid move): any
      // valid move, as the world rule would pick.
      m = RandomValidMove(lattice, (*ctx.positions)[i], rng_);
    }
    (*moves)[i] = m;
  }
  if (has_next) ++index_;
  return status;
}

}  // namespace aia
