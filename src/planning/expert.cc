#include "aia/planning/expert.h"

#include <algorithm>
#include <cmath>

#include "aia/core/check.h"
#include "aia/planning/information.h"

namespace aia {

SamplingProblem ExpertProblem(const DecisionContext& ctx) {
  AIA_CHECK_MSG(ctx.central != nullptr,
                "the expert plans on the centralized belief");
  SamplingProblem p;
  p.map = ctx.map;
  p.sensor = ctx.sensor;
  p.eps = ctx.eps;
  p.start = *ctx.robot_lattice;
  p.active = ctx.comm->active();
  p.belief = ctx.central;
  p.belief_row = 0;
  return p;
}

ExpertPolicy::ExpertPolicy(const ExpertParams& params) : params_(params) {}

void ExpertPolicy::Reset(const Map&, int, int, std::uint64_t seed) {
  rng_ = Rng(seed, "policy.expert");
  plan_ = SamplingPlan{};
  at_.clear();
  replans_ = 0;
  team_best_ = false;
  missed_.clear();
  last_det_.clear();
  best_belief_.reset();  // it points into the last episode's layout
}

void ExpertPolicy::RecordMisses(const DecisionContext& ctx) {
  const BeliefSet& central = *ctx.central;
  const int m = central.layout().num_targets();
  const Lattice& lattice = ctx.map->lattice();
  const bool comparable = !team_best_ &&
                          static_cast<int>(plan_.aims.size()) == m &&
                          static_cast<int>(last_det_.size()) == m;
  missed_.resize(m);
  last_det_.resize(m);
  for (int k = 0; k < m; ++k) {
    const double det = central.DetCovariance(0, k);
    const double before = last_det_[k];
    last_det_[k] = det;
    if (!comparable || !central.layout().is_static(k) || det <= ctx.eps)
      continue;
    if (det < before * (1.0 - 1e-9)) {  // measured: the search is over
      missed_[k].clear();
      continue;
    }
    // Nothing measured this step: every robot with the aim in sight missed.
    for (int i = 0; i < static_cast<int>(ctx.robot_lattice->size()); ++i) {
      const int q = (*ctx.robot_lattice)[i];
      if (!ctx.comm->Active(i) ||
          PredictedPrecision(*ctx.map, *ctx.sensor, lattice.Point(q),
                             plan_.aims[k]) <= 0.0)
        continue;
      std::vector<int>& tried = missed_[k];
      if (std::find(tried.begin(), tried.end(), q) == tried.end())
        tried.push_back(q);
    }
  }
}

bool ExpertPolicy::NeedsReplan(const DecisionContext& ctx) const {
  const int size = static_cast<int>(plan_.configs.size());
  if (size == 0) return true;
  const int n = static_cast<int>(ctx.robot_lattice->size());
  for (int i = 0; i < n; ++i)
    if (Deciding(ctx, i) && at_[i] + 1 >= size) return true;  // plan done
  if (!ctx.beliefs->layout().all_static()) return true;       // targets move
  for (int i = 0; i < n; ++i)
    if ((*ctx.robot_lattice)[i] != plan_.configs[at_[i]][i])
      return true;  // physics disagreed
  if (team_best_) return false;
  // A planned measurement that did not happen: the centralized belief is far
  // less certain than the plan predicted for the team's least advanced robot.
  const int at = *std::min_element(at_.begin(), at_.end());
  for (int k = 0; k < ctx.central->layout().num_targets(); ++k) {
    const double actual = ctx.central->DetCovariance(0, k);
    if (actual > ctx.eps && actual > 2.0 * plan_.det[at][k]) return true;
  }
  return false;
}

PolicyStatus ExpertPolicy::Decide(const DecisionContext& ctx,
                                  std::vector<Move>* moves) {
  const Lattice& lattice = ctx.map->lattice();
  const int n = static_cast<int>(moves->size());
  at_.resize(n, 0);
  RecordMisses(ctx);
  if (NeedsReplan(ctx)) {
    SamplingProblem problem = ExpertProblem(ctx);
    problem.missed = missed_;
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
      if (!best_belief_ || &best_belief_->layout() != &b.layout())
        best_belief_ = std::make_unique<BeliefSet>(&b.layout(), 1);
      TeamBestRows(b, ctx.comm->active(), &best_rows_);
      TeamBestBelief(b, best_rows_, best_belief_.get());
      problem.belief = best_belief_.get();
    }
    // Robots on their way (async decisions) plan from where they drive to.
    plan_ = tree_.Solve(problem, params_, rng_);
    std::fill(at_.begin(), at_.end(), 0);
    ++replans_;
  }
  PolicyStatus status = plan_.status;
  const int size = static_cast<int>(plan_.configs.size());
  last_useful_.assign(n, 0);
  // Each deciding robot takes the next step of its own path in the plan
  // (in lockstep the whole team, one configuration after the other).
  for (int i = 0; i < n; ++i) {
    if (!Deciding(ctx, i)) continue;
    const int at = at_[i];
    const bool has_next = at + 1 < size;
    Move m = Move::kStay;
    if (has_next) {
      m = MoveBetween(lattice, plan_.configs[at][i], plan_.configs[at + 1][i]);
      last_useful_[i] = i < static_cast<int>(plan_.useful_until.size()) &&
                        at + 1 <= plan_.useful_until[i];
    }
    if (m == Move::kStay && ctx.comm->Active(i)) {
      // Nothing planned for this robot (depth-0 plan or no valid move): any
      // valid move, as the world rule would pick; none (walled in): it
      // stays, and says so as the other policies do.
      const int here = (*ctx.robot_lattice)[i];
      if (lattice.NumValidMoves(here) == 0)
        status = PolicyStatus::kNoValidMove;
      else
        m = RandomValidMove(lattice, here, rng_);
    }
    (*moves)[i] = m;
    if (has_next) ++at_[i];
  }
  return status;
}

}  // namespace aia
