#include "aia/planning/search.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "aia/core/check.h"

namespace aia {

void SearchMemory::Reset(int num_robots, int num_targets) {
  AIA_CHECK(num_robots >= 0 && num_targets >= 0);
  num_robots_ = num_robots;
  num_targets_ = num_targets;
  slots_.assign(static_cast<std::size_t>(num_robots) * num_targets, Slot{});
  misses_ = 0;
}

bool SearchMemory::Reaim(const DecisionContext& ctx, int robot, int k) {
  const Map& map = *ctx.map;
  const SensorModel& sensor = *ctx.sensor;
  const Lattice& lattice = map.lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const int span =
      static_cast<int>(std::ceil(sensor.range / lattice.step())) + 1;
  // Near: the lattice distance (|dx| + |dy|) from the robot to the nearest
  // point of its own component that would measure a target at x.
  const auto cost = [&](const Vec2& x) {
    const int c = lattice.NearestPoint(x);
    const int component = lattice.components()[here];
    int best = -1;
    for (int iy = std::max(0, lattice.Iy(c) - span);
         iy <= std::min(lattice.ny() - 1, lattice.Iy(c) + span); ++iy) {
      for (int ix = std::max(0, lattice.Ix(c) - span);
           ix <= std::min(lattice.nx() - 1, lattice.Ix(c) + span); ++ix) {
        const int q = lattice.Index(ix, iy);
        if (!lattice.Free(q) || lattice.components()[q] != component) continue;
        const int d =
            std::abs(ix - lattice.Ix(here)) + std::abs(iy - lattice.Iy(here));
        if (best >= 0 && d >= best) continue;
        if (PredictedPrecision(map, sensor, lattice.Point(q), x) > 0.0)
          best = d;
      }
    }
    return best;
  };
  Slot& s = slots_[static_cast<std::size_t>(robot) * num_targets_ + k];
  const Mat2 cov = ctx.beliefs->PositionCovariance(robot, k);
  if (SearchAim(map, sensor, s.mean, cov, &s.missed, cost, &s.aim)) return true;
  // The prior is searched to 4 sigma: forget, and search it again.
  s.missed.clear();
  s.aim = s.mean;
  return false;
}

void SearchMemory::Update(const DecisionContext& ctx, int robot) {
  AIA_CHECK(robot >= 0 && robot < num_robots_);
  const BeliefSet& beliefs = *ctx.beliefs;
  AIA_CHECK(beliefs.layout().num_targets() == num_targets_);
  const Map& map = *ctx.map;
  const SensorModel& sensor = *ctx.sensor;
  const Lattice& lattice = map.lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const Vec2 p = lattice.Point(here);
  const double log_eps = std::log(ctx.eps);
  for (int k = 0; k < num_targets_; ++k) {
    Slot& s = slots_[static_cast<std::size_t>(robot) * num_targets_ + k];
    const double now = beliefs.LogDetCovariance(robot, k);
    const bool first = std::isnan(s.log_det);
    const bool shrank = !first && now < s.log_det + std::log1p(-1e-9);
    s.log_det = now;
    s.mean = beliefs.PositionMean(robot, k);
    const bool searching =
        !first && !shrank && now > log_eps && beliefs.layout().is_static(k);
    if (!searching) s.missed.clear();
    if (s.missed.empty()) s.aim = s.mean;
    if (!searching) continue;
    // Nothing measured, though this point sees the aim: the target is not
    // anywhere the point would have measured.
    if (PredictedPrecision(map, sensor, p, s.aim) <= 0.0 ||
        std::find(s.missed.begin(), s.missed.end(), here) != s.missed.end())
      continue;
    s.missed.push_back(here);
    ++misses_;
    Reaim(ctx, robot, k);
  }
}

void SearchMemory::Share(const DecisionContext& ctx,
                         const std::vector<int>& robots) {
  // What each robot's neighbours missed, from the lists as Update left them
  // (so the order of the robots does not matter), added to its own.
  const double log_eps = std::log(ctx.eps);
  incoming_.clear();
  for (int i : robots) {
    for (int k = 0; k < num_targets_; ++k) {
      const Slot& s = slots_[static_cast<std::size_t>(i) * num_targets_ + k];
      if (std::isnan(s.log_det) || s.log_det <= log_eps ||
          !ctx.beliefs->layout().is_static(k))
        continue;
      for (int j : ctx.comm->Neighbors(i)) {
        if (j == i) continue;
        for (int q :
             slots_[static_cast<std::size_t>(j) * num_targets_ + k].missed)
          if (std::find(s.missed.begin(), s.missed.end(), q) == s.missed.end())
            incoming_.push_back({i, k, q});
      }
    }
  }
  std::sort(incoming_.begin(), incoming_.end());
  incoming_.erase(std::unique(incoming_.begin(), incoming_.end()),
                  incoming_.end());
  for (std::size_t a = 0; a < incoming_.size();) {
    const int i = incoming_[a][0], k = incoming_[a][1];
    Slot& s = slots_[static_cast<std::size_t>(i) * num_targets_ + k];
    for (; a < incoming_.size() && incoming_[a][0] == i && incoming_[a][1] == k;
         ++a)
      s.missed.push_back(incoming_[a][2]);
    Reaim(ctx, i, k);
  }
}

Move TowardNearestAim::FirstMove(const Map& map, const SensorModel& sensor,
                                 int p, const std::vector<Vec2>& aims,
                                 const std::vector<std::uint8_t>& open,
                                 int* target) {
  AIA_CHECK(aims.size() == open.size());
  if (target) *target = -1;
  const Lattice& lattice = map.lattice();
  // The open aims by the lattice point nearest them; their observation points
  // are the points of the (2 span + 1)^2 window around it from which the aim
  // is seen.
  const int span =
      static_cast<int>(std::ceil(sensor.range / lattice.step())) + 1;
  const int num_aims = static_cast<int>(aims.size());
  centres_.resize(num_aims);
  open_.assign(num_aims, 0);
  bool any_open = false;
  for (int k = 0; k < num_aims; ++k) {
    if (!open[k]) continue;
    const int c = lattice.NearestPoint(aims[k]);
    centres_[k] = Vec2(lattice.Ix(c), lattice.Iy(c));
    open_[k] = 1;
    any_open = true;
  }
  if (!any_open) return Move::kStay;
  const double radius = 1.5 * span;  // covers the window's corners
  open_index_.Build(centres_, radius, &open_);

  // BFS from the robot, remembering each point's first move, popped in order
  // of distance. The first distance that holds an observation point decides;
  // among its points the one of the lowest target, then the lowest point
  // index (row by row), which is what scanning every target's window over a
  // full BFS in that order finds, at the cost of the BFS out to that distance.
  const int n = lattice.size();
  if (static_cast<int>(dist_.size()) != n) {
    dist_.assign(n, -1);
    first_.assign(n, Move::kStay);
    queue_.resize(n);
  }
  size_t head = 0, tail = 0;
  dist_[p] = 0;
  queue_[tail++] = p;
  int best_k = -1, best_q = -1, best_dist = 0;
  while (head < tail) {
    const int u = queue_[head++];
    const int d = dist_[u];
    if (best_k >= 0 && d > best_dist) break;
    if (d >= 1) {
      const int ux = lattice.Ix(u), uy = lattice.Iy(u);
      near_.clear();
      open_index_.Near(centres_, Vec2(ux, uy), radius, &near_);
      for (int k : near_) {  // ascending
        if (best_k >= 0 && (k > best_k || (k == best_k && u > best_q))) break;
        if (std::abs(static_cast<int>(centres_[k].x()) - ux) > span ||
            std::abs(static_cast<int>(centres_[k].y()) - uy) > span)
          continue;
        if (PredictedPrecision(map, sensor, lattice.Point(u), aims[k]) <= 0.0)
          continue;
        best_k = k;
        best_q = u;
        best_dist = d;
        break;
      }
    }
    if (best_k >= 0) continue;  // the rest of this distance only
    for (Move m : kMoves) {
      const int v = lattice.Next(u, m);
      if (v < 0 || dist_[v] >= 0) continue;
      dist_[v] = d + 1;
      first_[v] = (u == p) ? m : first_[u];
      queue_[tail++] = v;
    }
  }
  const Move move = best_k < 0 ? Move::kStay : first_[best_q];
  for (size_t i = 0; i < tail; ++i) dist_[queue_[i]] = -1;
  if (target) *target = move == Move::kStay ? -1 : best_k;
  return move;
}

void TargetClaims::Begin(const Map& map, const SensorModel& sensor) {
  map_ = &map;
  sensor_ = &sensor;
  index_.clear();
  plans_.clear();
}

const std::vector<int>& TargetClaims::Field(const Vec2& aim) {
  AIA_CHECK_MSG(map_ && sensor_, "Begin() before Field()");
  std::pair<std::uint64_t, std::uint64_t> key;
  std::memcpy(&key.first, &aim.x(), sizeof(double));
  std::memcpy(&key.second, &aim.y(), sizeof(double));
  const auto [it, fresh] =
      index_.emplace(key, static_cast<int>(index_.size()));
  const int index = it->second;
  if (!fresh) return fields_[index];
  const Lattice& lattice = map_->lattice();
  const int span =
      static_cast<int>(std::ceil(sensor_->range / lattice.step())) + 1;
  const int c = lattice.NearestPoint(aim);
  const int cx = lattice.Ix(c), cy = lattice.Iy(c);
  sources_.clear();
  for (int iy = std::max(0, cy - span); iy <= std::min(lattice.ny() - 1, cy + span);
       ++iy)
    for (int ix = std::max(0, cx - span);
         ix <= std::min(lattice.nx() - 1, cx + span); ++ix) {
      const int q = lattice.Index(ix, iy);
      if (lattice.Free(q) &&
          PredictedPrecision(*map_, *sensor_, lattice.Point(q), aim) > 0.0)
        sources_.push_back(q);
    }
  if (static_cast<int>(fields_.size()) <= index) fields_.emplace_back();
  BfsDistances(lattice, sources_.data(), static_cast<int>(sources_.size()),
               &fields_[index], &queue_);
  return fields_[index];
}

int TargetClaims::Distance(const Vec2& aim, int p) { return Field(aim)[p]; }

bool TargetClaims::Before(int a, int da, int b, int db) const {
  if (da != db) return da < db;
  const Vec2 pa = map_->lattice().Point(a), pb = map_->lattice().Point(b);
  return pa.x() < pb.x() || (pa.x() == pb.x() && pa.y() < pb.y());
}

void TargetClaims::Claim(int self, const std::vector<int>& others,
                         const std::vector<Vec2>& aims,
                         const std::vector<std::uint8_t>& open,
                         std::vector<std::uint8_t>* mine) {
  AIA_CHECK_MSG(map_ && sensor_, "Begin() before Claim()");
  AIA_CHECK(aims.size() == open.size());
  const int m = static_cast<int>(aims.size());
  const int n = static_cast<int>(others.size()) + 1;
  const auto point = [&](int r) { return r == 0 ? self : others[r - 1]; };
  mine->assign(m, 0);
  // Each open target's owner: the robot (0: self, r: others[r - 1]) nearest
  // to where it can be measured.
  owner_.assign(m, -1);
  held_.assign(n, 0);
  bool any = false;
  for (int k = 0; k < m; ++k) {
    if (!open[k]) continue;
    const std::vector<int>& f = Field(aims[k]);
    int best = -1;
    for (int r = 0; r < n; ++r) {
      const int d = f[point(r)];
      if (d >= 0 && (best < 0 || Before(point(r), d, point(best), f[point(best)])))
        best = r;
    }
    owner_[k] = best;
    if (best < 0) continue;
    ++held_[best];
    if (best == 0) (*mine)[k] = 1;
    any = any || best == 0;
  }
  if (any) return;
  // Idle: help where an owner holds two or more, as the nearest idle robot.
  for (int k = 0; k < m; ++k) {
    if (owner_[k] < 0 || held_[owner_[k]] < 2) continue;
    const std::vector<int>& f = Field(aims[k]);
    const int d = f[self];
    if (d < 0) continue;
    bool won = true;
    for (int r = 1; r < n && won; ++r) {
      const int e = f[point(r)];
      if (held_[r] == 0 && e >= 0 && Before(point(r), e, self, d)) won = false;
    }
    (*mine)[k] = won;
  }
}

class TargetClaims::Legs : public LegOracle {
 public:
  Legs(TargetClaims* claims, const std::vector<Vec2>* aims)
      : claims_(claims), aims_(aims) {}
  Leg Compute(int from, int, int k) override {
    const std::vector<int>& f = claims_->Field((*aims_)[k]);
    Leg leg;
    leg.steps = f[from];
    if (leg.steps < 0) return leg;
    const Lattice& lattice = claims_->map_->lattice();
    int q = from;
    while (f[q] > 0) q = lattice.Next(q, StepDownField(lattice, f, q));
    leg.end = q;
    return leg;
  }
  int Distance(int from, int k) override {
    return claims_->Field((*aims_)[k])[from];
  }
  bool TimeVarying(int) const override { return false; }

 private:
  TargetClaims* claims_;
  const std::vector<Vec2>* aims_;
};

void TargetClaims::Route(int self, const std::vector<int>& others,
                         const std::vector<Vec2>& aims,
                         const std::vector<std::uint8_t>& open,
                         std::vector<std::uint8_t>* mine) {
  AIA_CHECK_MSG(map_ && sensor_, "Begin() before Route()");
  AIA_CHECK(aims.size() == open.size());
  const Lattice& lattice = map_->lattice();
  const int m = static_cast<int>(aims.size());
  mine->assign(m, 0);
  std::vector<int> points = others;
  points.push_back(self);
  std::sort(points.begin(), points.end(), [&](int a, int b) {
    const Vec2 pa = lattice.Point(a), pb = lattice.Point(b);
    return pa.x() < pb.x() || (pa.x() == pb.x() && pa.y() < pb.y());
  });
  const auto same_aims = [&](const Plan& plan) {
    for (int k = 0; k < m; ++k)
      if (open[k] && (plan.aims[k].x() != aims[k].x() ||
                      plan.aims[k].y() != aims[k].y()))
        return false;
    return true;
  };
  const Plan* plan = nullptr;
  for (const Plan& p : plans_)
    if (p.points == points && p.open == open && same_aims(p)) plan = &p;
  if (!plan) {
    std::vector<int> targets;
    for (int k = 0; k < m; ++k)
      if (open[k]) targets.push_back(k);
    Legs legs(this, &aims);
    TourSettings settings;
    settings.objective = TourObjective::kMakespan;
    settings.budget = kRouteBudget;
    const std::vector<double> weight(m, 1.0);
    Tours tours = planner_.Plan(points, targets, weight, settings, legs);
    plans_.push_back({points, open, aims, std::move(tours.order)});
    plan = &plans_.back();
  }
  const int at = static_cast<int>(
      std::find(points.begin(), points.end(), self) - points.begin());
  const std::vector<int>& route = plan->order[at];
  if (!route.empty()) (*mine)[route.front()] = 1;
}

}  // namespace aia
