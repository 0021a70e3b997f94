#include "aia/planning/tours.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace aia {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

Leg TourPlanner::CachedLeg(int from, int t, int k) {
  // Legs toward a static target depend on the departure step only through
  // the start (a robot already in the region at step 0 still has to move).
  const std::uint64_t when = legs_->TimeVarying(k)
                                 ? static_cast<std::uint64_t>(t) + 1
                                 : (t == 0 ? 1 : 0);
  const std::uint64_t key = (static_cast<std::uint64_t>(from) << 40) ^
                            (when << 20) ^ static_cast<std::uint64_t>(k);
  auto it = cache_.find(key);
  if (it != cache_.end()) return it->second;
  const Leg leg = legs_->Compute(from, t, k);
  cache_.emplace(key, leg);
  return leg;
}

TourPlanner::RouteValue TourPlanner::Evaluate(int robot,
                                              const std::vector<int>& route) {
  ++evaluations_;
  return Value(robot, route);
}

TourPlanner::RouteValue TourPlanner::Value(int robot,
                                           const std::vector<int>& route) {
  RouteValue v;
  int t = 0, cur = (*starts_)[robot];
  if (cur < 0) {
    v.feasible = route.empty();
    return v;
  }
  for (int k : route) {
    const Leg leg = CachedLeg(cur, t, k);
    if (leg.steps < 0) {
      v.feasible = false;
      return v;
    }
    // A robot that starts in an unlocalized target's region still needs a
    // step to measure it again.
    t += (t == 0) ? std::max(leg.steps, 1) : leg.steps;
    cur = leg.end;
    v.latency += (*weight_)[k] * t;
  }
  v.makespan = t;
  return v;
}

void TourPlanner::Summarize(const std::vector<RouteValue>& values) {
  latency_ = 0.0;
  top_.fill({0, -1});
  for (int i = 0; i < static_cast<int>(values.size()); ++i) {
    latency_ += values[i].latency;
    std::pair<int, int> v{values[i].makespan, i};
    for (auto& slot : top_)
      if (v.first > slot.first || slot.second < 0) std::swap(v, slot);
  }
}

double TourPlanner::Objective(const std::vector<RouteValue>& values) {
  Summarize(values);
  return ObjectiveWith(values, -1, {}, -1, {});
}

double TourPlanner::ObjectiveWith(const std::vector<RouteValue>& values, int a,
                                  const RouteValue& va, int b,
                                  const RouteValue& vb) const {
  // Routes other than a and b are unchanged (and feasible): their totals
  // come from Summarize.
  double latency = latency_;
  int makespan = 0;
  for (const auto& [span, robot] : top_) {
    if (robot >= 0 && robot != a && robot != b) {
      makespan = span;
      break;
    }
  }
  if (a >= 0) {
    if (!va.feasible) return kInf;
    latency += va.latency - values[a].latency;
    makespan = std::max(makespan, va.makespan);
  }
  if (b >= 0) {
    if (!vb.feasible) return kInf;
    latency += vb.latency - values[b].latency;
    makespan = std::max(makespan, vb.makespan);
  }
  if (objective_ == TourObjective::kLatency) return latency + 1e-9 * makespan;
  // Lexicographic: the makespan, then the latency (a fraction below 1).
  return makespan + 0.5 * latency / (weight_sum_ * (makespan + 1.0) + 1e-300);
}

struct TourPlanner::Insertion {
  int robot = -1, pos = -1;
  RouteValue value;      // the robot's route with the target inserted
  double best = kInf;    // the objective then
  double second = kInf;  // the best objective in another robot's route
};

void TourPlanner::ChooseCandidates(const std::vector<int>& robots,
                                   const std::vector<int>& targets,
                                   const TourSettings& settings) {
  const int num = static_cast<int>(targets.size());
  // Each target's candidate robots, in ascending order: all of them, or the
  // `candidates` whose starts are nearest (then the lowest ids).
  const size_t cap = static_cast<size_t>(std::max(1, settings.candidates));
  candidates_.assign(num, {});
  inserted_.assign(num, {});
  inserted_version_.assign(num, {});
  std::vector<std::pair<int, int>> near;
  for (int t = 0; t < num; ++t) {
    std::vector<int>& c = candidates_[t];
    if (robots.size() <= cap) {
      c = robots;
    } else {
      near.clear();
      for (int i : robots) {
        const int d = legs_->Distance((*starts_)[i], targets[t]);
        if (d >= 0) near.push_back({d, i});
      }
      if (near.size() > cap) {
        std::nth_element(near.begin(), near.begin() + (cap - 1), near.end());
        near.resize(cap);
      }
      for (const auto& [d, i] : near) c.push_back(i);
      std::sort(c.begin(), c.end());
    }
    inserted_[t].assign(c.size(), {});
    inserted_version_[t].assign(c.size(), -1);
  }
}

TourPlanner::Insertion TourPlanner::BestInsertion(
    int t, int k, const Tours& tours, const std::vector<RouteValue>& values,
    const std::vector<long>& version) {
  // A route's values with the target inserted are computed again only when
  // the route has changed; the budget counts the evaluations as if they
  // were all made anew.
  Insertion best;
  for (size_t c = 0; c < candidates_[t].size(); ++c) {
    const int i = candidates_[t][c];
    const std::vector<int>& route = tours.order[i];
    std::vector<RouteValue>& inserted = inserted_[t][c];
    if (inserted_version_[t][c] != version[i]) {
      inserted.resize(route.size() + 1);
      for (size_t p = 0; p <= route.size(); ++p) {
        trial_ = route;
        trial_.insert(trial_.begin() + p, k);
        inserted[p] = Value(i, trial_);
      }
      inserted_version_[t][c] = version[i];
      insert_work_ += static_cast<long>(route.size() + 1) * (route.size() + 1);
    }
    evaluations_ += static_cast<long>(route.size()) + 1;
    double robot_best = kInf;
    int robot_pos = -1;
    RouteValue robot_value;
    for (size_t p = 0; p <= route.size(); ++p) {
      const RouteValue& v = inserted[p];
      const double obj = ObjectiveWith(values, i, v, -1, {});
      if (obj < robot_best) {
        robot_best = obj;
        robot_pos = static_cast<int>(p);
        robot_value = v;
      }
    }
    if (robot_best < best.best) {
      best.second = best.best;
      best.best = robot_best;
      best.robot = i;
      best.pos = robot_pos;
      best.value = robot_value;
    } else if (robot_best < best.second) {
      best.second = robot_best;
    }
  }
  return best;
}

void TourPlanner::Insert(const std::vector<int>& robots,
                         const std::vector<int>& targets,
                         const TourSettings& settings, Tours* tours,
                         std::vector<RouteValue>* values_out) {
  std::vector<RouteValue>& values = *values_out;
  const int num = static_cast<int>(targets.size());
  ChooseCandidates(robots, targets, settings);
  std::vector<long> version(tours->order.size(), 0);
  // Regret-2 insertion: the target whose best insertion is cheapest compared
  // with its best insertion in another robot's route goes first.
  std::vector<int> remaining(num);
  for (int t = 0; t < num; ++t) remaining[t] = t;
  insert_work_ = 0;
  while (!remaining.empty()) {
    if (insert_work_ > settings.insert_work) {
      AppendRest(targets, remaining, tours, &values);
      break;
    }
    int pick = -1;
    double pick_key = -kInf;
    Insertion chosen;
    for (size_t r = 0; r < remaining.size(); ++r) {
      const int t = remaining[r];
      const Insertion in =
          BestInsertion(t, targets[t], *tours, values, version);
      if (in.best == kInf) continue;
      const double key = robots.size() > 1 ? in.second - in.best : -in.best;
      if (key > pick_key || (key == pick_key && in.best < chosen.best)) {
        pick_key = key;
        pick = static_cast<int>(r);
        chosen = in;
      }
    }
    if (pick < 0) {  // nothing left that any robot can reach
      for (int t : remaining) tours->unassigned.push_back(targets[t]);
      break;
    }
    std::vector<int>& route = tours->order[chosen.robot];
    route.insert(route.begin() + chosen.pos, targets[remaining[pick]]);
    ++version[chosen.robot];
    values[chosen.robot] = chosen.value;
    Summarize(values);
    remaining.erase(remaining.begin() + pick);
  }
}

void TourPlanner::AppendRest(const std::vector<int>& targets,
                             const std::vector<int>& rest, Tours* tours,
                             std::vector<RouteValue>* values_out) {
  std::vector<RouteValue>& values = *values_out;
  for (int t : rest) {
    const int k = targets[t];
    int robot = -1;
    double best = kInf;
    RouteValue value;
    for (int i : candidates_[t]) {
      trial_ = tours->order[i];
      trial_.push_back(k);
      const RouteValue v = Evaluate(i, trial_);
      const double obj = ObjectiveWith(values, i, v, -1, {});
      if (obj < best) {
        best = obj;
        robot = i;
        value = v;
      }
    }
    if (robot < 0) {  // no candidate can reach it
      tours->unassigned.push_back(k);
      continue;
    }
    tours->order[robot].push_back(k);
    values[robot] = value;
    Summarize(values);
  }
}

struct TourPlanner::Search {
  const std::vector<int>& robots;
  long budget;
  Tours& tours;
  std::vector<RouteValue>& values;
  double current;           // the objective of the tours now
  std::vector<int> ra, rb;  // routes tried
};

bool TourPlanner::Take(Search* s, int a, const std::vector<int>& route_a,
                       const RouteValue& va, int b,
                       const std::vector<int>& route_b, const RouteValue& vb) {
  constexpr double kTolerance = 1e-12;
  const double obj = ObjectiveWith(s->values, a, va, b, vb);
  if (!(obj < s->current - kTolerance)) return false;
  s->tours.order[a] = route_a;
  s->values[a] = va;
  if (b >= 0) {
    s->tours.order[b] = route_b;
    s->values[b] = vb;
  }
  s->current = Objective(s->values);
  return true;
}

bool TourPlanner::Relocate(Search* s) {
  std::vector<std::vector<int>>& order = s->tours.order;
  std::vector<int>& ra = s->ra;
  std::vector<int>& rb = s->rb;
  for (int i : s->robots) {
    for (size_t p = 0; p < order[i].size() && evaluations_ < s->budget; ++p) {
      const int k = order[i][p];
      ra = order[i];
      ra.erase(ra.begin() + p);
      const RouteValue va = Evaluate(i, ra);
      for (int j : s->robots) {
        const std::vector<int>& base = (j == i) ? ra : order[j];
        for (size_t q = 0; q <= base.size() && evaluations_ < s->budget; ++q) {
          if (j == i && q == p) continue;
          rb = base;
          rb.insert(rb.begin() + q, k);
          const RouteValue vb = Evaluate(j, rb);
          if ((j == i) ? Take(s, i, rb, vb, -1, rb, vb)
                       : Take(s, i, ra, va, j, rb, vb))
            return true;
        }
      }
    }
  }
  return false;
}

bool TourPlanner::Swap(Search* s) {
  const std::vector<int>& robots = s->robots;
  std::vector<std::vector<int>>& order = s->tours.order;
  std::vector<int>& ra = s->ra;
  std::vector<int>& rb = s->rb;
  for (size_t a = 0; a < robots.size() && evaluations_ < s->budget; ++a) {
    const int i = robots[a];
    for (size_t b = a; b < robots.size() && evaluations_ < s->budget; ++b) {
      const int j = robots[b];
      for (size_t p = 0; p < order[i].size(); ++p) {
        for (size_t q = (i == j) ? p + 1 : 0;
             q < order[j].size() && evaluations_ < s->budget; ++q) {
          ra = order[i];
          bool taken;
          if (i == j) {
            std::swap(ra[p], ra[q]);
            const RouteValue va = Evaluate(i, ra);
            taken = Take(s, i, ra, va, -1, ra, va);
          } else {
            rb = order[j];
            std::swap(ra[p], rb[q]);
            const RouteValue va = Evaluate(i, ra), vb = Evaluate(j, rb);
            taken = Take(s, i, ra, va, j, rb, vb);
          }
          if (taken) return true;
        }
      }
    }
  }
  return false;
}

bool TourPlanner::TwoOpt(Search* s) {
  std::vector<int>& ra = s->ra;
  for (int i : s->robots) {
    const size_t len = s->tours.order[i].size();
    for (size_t p = 0; p + 1 < len && evaluations_ < s->budget; ++p) {
      for (size_t q = p + 2; q <= len && evaluations_ < s->budget; ++q) {
        ra = s->tours.order[i];
        std::reverse(ra.begin() + p, ra.begin() + q);
        const RouteValue va = Evaluate(i, ra);
        if (Take(s, i, ra, va, -1, ra, va)) return true;
      }
    }
  }
  return false;
}

void TourPlanner::LocalSearch(const std::vector<int>& robots,
                              const TourSettings& settings, Tours* tours,
                              std::vector<RouteValue>* values) {
  Search s{robots, settings.budget, *tours, *values, Objective(*values), {},
           {}};
  bool improved = true;
  while (improved && evaluations_ < s.budget)
    improved = Relocate(&s) || Swap(&s) || TwoOpt(&s);
}

Tours TourPlanner::Plan(const std::vector<int>& starts,
                        const std::vector<int>& targets,
                        const std::vector<double>& weight,
                        const TourSettings& settings, LegOracle& legs) {
  legs_ = &legs;
  starts_ = &starts;
  weight_ = &weight;
  objective_ = settings.objective;
  evaluations_ = 0;
  cache_.clear();
  const int n = static_cast<int>(starts.size());
  Tours tours;
  tours.order.assign(n, {});
  std::vector<RouteValue> values(n);
  weight_sum_ = 0.0;
  for (int k : targets) weight_sum_ += weight[k];
  Summarize(values);
  std::vector<int> robots;
  for (int i = 0; i < n; ++i)
    if (starts[i] >= 0) robots.push_back(i);
  if (robots.empty()) {
    tours.unassigned = targets;
    return tours;
  }
  Insert(robots, targets, settings, &tours, &values);
  LocalSearch(robots, settings, &tours, &values);
  for (int i : robots) {
    tours.latency += values[i].latency;
    tours.makespan = std::max(tours.makespan, values[i].makespan);
  }
  tours.evaluations = evaluations_;
  return tours;
}

}  // namespace aia
