#include "aia/planning/decsb.h"

#include <algorithm>
#include <cmath>

#include "aia/planning/information.h"

namespace aia {

SamplingParams DecSbParams::Sampling() const {
  SamplingParams p;
  p.p_v = p_v;
  p.p_u = p_u;
  p.max_depth = horizon;
  p.max_iterations = iterations;
  p.routing = false;
  // A robot's tree stops at the horizon; a goal (its own belief below eps
  // everywhere) ends the search early, with a short anytime polish.
  p.anytime = iterations / 4;
  return p;
}

DecSbPolicy::DecSbPolicy(const DecSbParams& params)
    : params_(params.Sampling()) {}

void DecSbPolicy::Reset(const Map&, int num_robots, int, std::uint64_t seed) {
  rngs_.clear();
  for (int i = 0; i < num_robots; ++i)
    rngs_.emplace_back(seed, "policy.decsb", i);
  plans_.assign(num_robots, {});
  next_.assign(num_robots, -1);
}

namespace internal {

void AnnouncedPrecision(const Map& map, const SensorModel& sensor,
                        const std::vector<Vec2>& announced,
                        const std::vector<Vec2>& means, long grid_pairs,
                        TargetGrid* grid, std::vector<double>* extra) {
  const int m = static_cast<int>(means.size());
  extra->assign(m, 0.0);
  if (static_cast<long>(announced.size()) * m <= grid_pairs) {
    for (const Vec2& q : announced)
      for (int k = 0; k < m; ++k)
        (*extra)[k] += PredictedPrecision(map, sensor, q, means[k]);
    return;
  }
  // Every pair further apart than the sensor's range adds exactly 0, so
  // only the targets in the grid cells around each announced position are
  // evaluated: each extra[k] gets the same terms in the same order as
  // above, the zeros left out. The means go into cells of at least the
  // range (at most 256 a side, and about four times as many as targets at
  // most: the cells are cleared for each robot), clamped to the
  // workspace's (a clamp only brings cells nearer); a mean that is not
  // finite is never in range.
  const Vec2 size = map.size();
  const double cell =
      std::max({sensor.range, size.x() / 256.0, size.y() / 256.0,
                std::sqrt(size.x() * size.y() / (4.0 * m))});
  const int gx = std::max(1, static_cast<int>(std::ceil(size.x() / cell)));
  const int gy = std::max(1, static_cast<int>(std::ceil(size.y() / cell)));
  const auto cell_of = [&](const Vec2& v) {
    const auto axis = [cell](double c, int g) {
      return static_cast<int>(std::clamp(std::floor(c / cell), 0.0, g - 1.0));
    };
    return axis(v.x(), gx) + gx * axis(v.y(), gy);
  };
  std::vector<int>& start = grid->start;
  start.assign(static_cast<std::size_t>(gx) * gy + 1, 0);
  for (int k = 0; k < m; ++k)
    if (means[k].allFinite()) ++start[cell_of(means[k]) + 1];
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  grid->items.resize(start.back());
  grid->fill.assign(start.begin(), start.end() - 1);
  for (int k = 0; k < m; ++k)
    if (means[k].allFinite()) grid->items[grid->fill[cell_of(means[k])]++] = k;
  // The cells the range spans, one more for a pair straddling a cell
  // border and one for the rounding of the divisions.
  const int reach = static_cast<int>(sensor.range / cell) + 2;
  for (const Vec2& q : announced) {
    const int c = cell_of(q), cx = c % gx, cy = c / gx;
    for (int y = std::max(0, cy - reach); y <= std::min(gy - 1, cy + reach);
         ++y)
      for (int x = std::max(0, cx - reach); x <= std::min(gx - 1, cx + reach);
           ++x)
        for (int at = start[x + gx * y]; at < start[x + gx * y + 1]; ++at) {
          const int k = grid->items[at];
          (*extra)[k] += PredictedPrecision(map, sensor, q, means[k]);
        }
  }
}

}  // namespace internal

PolicyStatus DecSbPolicy::Decide(const DecisionContext& ctx,
                                 std::vector<Move>* moves) {
  const Lattice& lattice = ctx.map->lattice();
  const int n = static_cast<int>(moves->size());
  const int m = ctx.beliefs->layout().num_targets();
  // What each robot announces this step: the position after its next move,
  // from the plan it made last step, if it is still on that plan.
  for (int j = 0; j < n; ++j) {
    const auto& plan = plans_[j];
    next_[j] =
        (plan.size() >= 3 && plan[1] == (*ctx.robot_lattice)[j]) ? plan[2] : -1;
  }
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < n; ++i) {
    (*moves)[i] = Move::kStay;
    if (!ctx.comm->Active(i)) {
      plans_[i].clear();
      continue;
    }
    if (!Deciding(ctx, i)) continue;  // on its way, on its plan
    // Neighbours' announced positions, evaluated on robot i's own means.
    announced_.clear();
    for (int j : ctx.comm->Neighbors(i))
      if (next_[j] >= 0) announced_.push_back(lattice.Point(next_[j]));
    means_.resize(m);
    for (int k = 0; k < m; ++k) means_[k] = ctx.beliefs->PositionMean(i, k);
    internal::AnnouncedPrecision(*ctx.map, *ctx.sensor, announced_, means_,
                                 internal::kGridPairs, &grid_, &extra_);
    SamplingProblem problem;
    problem.map = ctx.map;
    problem.sensor = ctx.sensor;
    problem.eps = ctx.eps;
    problem.start = {(*ctx.robot_lattice)[i]};
    problem.active = {1};
    problem.belief = ctx.beliefs;
    problem.belief_row = i;
    problem.extra_at_depth1 = extra_;
    const SamplingPlan plan = tree_.Solve(problem, params_, rngs_[i]);
    auto& path = plans_[i];
    path.clear();
    for (const auto& config : plan.configs) path.push_back(config[0]);
    Move move =
        path.size() >= 2 ? MoveBetween(lattice, path[0], path[1]) : Move::kStay;
    if (move == Move::kStay) {  // nothing left to gain within the horizon
      move = RandomValidMove(lattice, path[0], rngs_[i]);
      if (move == Move::kStay) status = PolicyStatus::kNoValidMove;
    }
    (*moves)[i] = move;
  }
  return status;
}

}  // namespace aia
