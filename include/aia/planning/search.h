// Searching a static target's prior after missed measurements
// (docs/design.md, Policies; docs/learning.md, Search memory). A robot whose
// lattice point sees where a target is believed to be, and that measured
// nothing of it, learned that the target is not anywhere that point would have
// measured: the Kalman filter cannot say so (it has no measurement to fuse),
// so a policy that only reads the belief would return to the same points
// forever. The aim is then moved to the nearest part of the prior that no
// missed point rules out. The expert searches so over the centralized belief;
// SearchMemory keeps the same per robot, from its own belief and its own
// points only.
#ifndef AIA_PLANNING_SEARCH_H_
#define AIA_PLANNING_SEARCH_H_

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <unordered_map>
#include <utility>
#include <vector>

#include "aia/core/geometry.h"
#include "aia/core/point_grid.h"
#include "aia/core/thread_pool.h"
#include "aia/core/types.h"
#include "aia/planning/information.h"
#include "aia/planning/policy.h"
#include "aia/planning/tours.h"
#include "aia/world/map.h"

namespace aia {

// Calls visit(x) for the points of each ring of the prior N(mean, cov): the
// mean alone, then Mahalanobis radius 0.25, 0.5, ..., 4 with 8 to 64 points
// each (about one per `step` of arc), in angle order; after each ring, stops
// where done() says so. Returns that ring (0: the mean), -1 where none did.
template <typename Visit, typename Done>
int WalkPriorRings(const Vec2& mean, const Mat2& cov, double step,
                   Visit&& visit, Done&& done);

// The rings of WalkPriorRings one at a time: Visit(ring, visit) calls
// visit(x) for ring `ring`'s points (0: the mean; kLast: 4 sigma).
class PriorRings {
 public:
  static constexpr int kLast = 16;
  PriorRings(const Vec2& mean, const Mat2& cov, double step);
  template <typename F>
  void Visit(int ring, F&& visit) const;

 private:
  Vec2 mean_;
  double step_;
  Mat2 l_;
  double sigma_ = 0.0;
};

// Where to look for a target believed at N(mean, cov) that the lattice points
// `missed` (may be null) did not measure. x is ruled out when a point of
// `missed` would have measured a target at x. Tried in order: the mean, then
// rings of the prior at Mahalanobis radius 0.25, 0.5, ..., 4 (8 to 64 points
// each); a free point that is not ruled out is a candidate when cost(x,
// bound) >= 0 (an int; the caller says what is near, -1: x cannot be
// observed; where the cost is not below `bound`, the best so far, any value
// from `bound` on may be returned instead, as such x is passed over). The
// first ring (the mean alone being the first) with a candidate decides: its
// candidate of least cost, ties to the first in angle order. Returns false,
// aim = mean, when no ring has one.
template <typename Cost>
bool SearchAim(const Map& map, const SensorModel& sensor, const Vec2& mean,
               const Mat2& cov, const std::vector<int>* missed, Cost&& cost,
               Vec2* aim);

// The lattice distance (|dx| + |dy|) from `here` to the nearest free point
// of its component, within `span` points of x's nearest lattice point (per
// axis), that would measure a target at x; -1 where none would, and `bound`
// where none nearer than `bound` would. The window is read in order of that
// distance, so the line of sight is tested only up to the first point that
// sees x (most of a window is farther than it).
int NearestObserverDistance(const Map& map, const SensorModel& sensor, int here,
                            const Vec2& x, int span,
                            int bound = std::numeric_limits<int>::max());

// Robots grouped by closed neighbourhood (the robot and its neighbours in
// this step's graph): robots whose neighbourhoods hold the same robots share
// a group. Neighbourhoods are hashed (FNV-1a over the robots, ascending),
// then compared exactly, each robot's once per graph (its class, kept while
// the graph's stamp is: CommNetwork::graph_stamp); a step's groups are its
// classes in the order the step first asks for them. O(edges) a new graph,
// O(robots asked) a step while the graph stays (a full graph: N^2 and N).
class ClosedNeighbourhoods {
 public:
  // Forgets every group (the start of a step); the classes stay.
  void Clear() {
    for (int c : group_classes_) group_of_class_[c] = -1;
    group_classes_.clear();
    first_.clear();
  }
  // Robot i's group: an index in order of making; *fresh says whether this
  // call made it. Between Clear and Clear the graph must stay.
  int Of(const DecisionContext& ctx, int i, bool* fresh);
  int size() const { return static_cast<int>(first_.size()); }
  // The first robot put in group g.
  int robot(int g) const { return first_[g]; }
  // Calls visit(j) for robot i and its neighbours, ascending.
  template <typename Visit>
  static void ForClosed(const DecisionContext& ctx, int i, Visit&& visit) {
    bool self = false;
    for (int j : ctx.comm->Neighbors(i)) {
      if (!self && i < j) {
        visit(i);
        self = true;
      }
      if (j != i) visit(j);
    }
    if (!self) visit(i);
  }

 private:
  bool SameClosed(const DecisionContext& ctx, int a, int b);
  // Per graph: each robot's class (-1: not asked yet); per class its first
  // robot and the next class of the same hash.
  std::uint64_t stamp_ = 0;
  std::vector<int> class_of_, class_first_, class_next_;
  std::unordered_map<std::uint64_t, int> index_;  // hash -> first class
  // Per step: each class's group (-1: none yet), the classes given one,
  // each group's first robot.
  std::vector<int> group_of_class_, group_classes_, first_;
  std::vector<int> closed_a_;  // SameClosed's scratch
};

// A robot's missed lattice points of one target, in the order they were
// added, each once: appended to or cleared, nothing else. It also keeps
// what NeighbourMisses::Share last made of it: its first shared() points
// are, as a set, the union that Share's call `call` made for neighbourhood
// `group`, until the list is cleared.
class MissList {
 public:
  const std::vector<int>& points() const { return points_; }
  std::vector<int>::const_iterator begin() const { return points_.begin(); }
  std::vector<int>::const_iterator end() const { return points_.end(); }
  std::size_t size() const { return points_.size(); }
  bool empty() const { return points_.empty(); }
  int operator[](std::size_t c) const { return points_[c]; }
  void push_back(int q) { points_.push_back(q); }
  void clear() {
    points_.clear();
    shared_ = 0;
    group_ = -1;
  }
  // The whole list is union `group` of Share's call `call`.
  void MarkShared(int group, std::uint32_t call) {
    shared_ = static_cast<std::uint32_t>(points_.size());
    group_ = group;
    call_ = call;
  }
  // The neighbourhood whose union of Share's call `call` the first
  // shared() points are; -1 if none.
  int SharedGroup(std::uint32_t call) const {
    return call_ == call && shared_ > 0 ? group_ : -1;
  }
  std::size_t shared() const { return shared_; }

 private:
  std::vector<int> points_;
  // 12 bytes: one list per robot and target (N x M of them).
  std::uint32_t shared_ = 0;
  std::int32_t group_ = -1;
  std::uint32_t call_ = 0;
};

// What a Share call makes once per closed neighbourhood and target (and
// per whatever else `same` tells apart: a belief, a component), per worker:
// the first robot of a neighbourhood to ask makes it, the others reuse it
// (SearchMemory's walks, SearchPoints' points). Clear() before each Share;
// the memory is kept.
template <typename Value>
class ShareCache {
 public:
  void Clear() {
    index_.clear();
    used_ = 0;
  }
  // The value kept for (group, k) that same(value) accepts; else a slot of
  // its own for the caller to fill (what it held before is left in it),
  // with *made set. The reference holds until the next Find.
  template <typename Same>
  Value& Find(int group, int k, Same&& same, bool* made) {
    std::vector<int>& kept = index_[(static_cast<std::uint64_t>(group) << 32) |
                                    static_cast<std::uint32_t>(k)];
    *made = false;
    for (const int v : kept)
      if (same(values_[v])) return values_[v];
    if (used_ == static_cast<int>(values_.size())) values_.emplace_back();
    kept.push_back(used_);
    *made = true;
    return values_[used_++];
  }

 private:
  std::unordered_map<std::uint64_t, std::vector<int>> index_;  // (group, k)
  std::vector<Value> values_;  // [0, used_) this Share
  int used_ = 0;
};

// Share's work, one definition for SearchMemory and SearchPoints: each
// robot among `robots` takes the points its neighbours in this step's graph
// missed for a static target still open in its own belief (log det above
// log eps) and not in its own list, read as Update left the lists (so the
// order of the robots does not matter); then, per (robot, target) that took
// any, in ascending order of both, `then(i, k, group, worker)` after its
// points were appended in ascending order (`group`: the neighbourhood's
// index in this call; every robot of a group that took points of k now
// holds the same set of them, its union; `worker`: the thread's index).
// Robots with the same closed neighbourhood (itself and its neighbours)
// take from the same lists, so the union of those lists per target is made
// once per neighbourhood: once for the whole team in a full graph, once per
// robot in a sparse one. A union visits only the targets its robots missed
// any point of (a list per robot, made in one pass over the slots) and
// drops duplicates with stamps. A list that the last call made equal to a
// union (MissList::SharedGroup) adds that union once per new union and then
// only the points appended since, so that a full graph, where every robot
// holds the same union, reads it once instead of once per robot. A robot's
// own list is part of its union, so a list as long as the union is the
// union and takes nothing; else the robot takes the union's points its own
// stamped list does not hold. O(robots x targets) for the lists, O(edges)
// for the neighbourhoods, O(P log P) per neighbourhood for the P points
// new to its unions, then O(1) per (robot, target) of its union, plus
// O(own list + union) where a robot takes; no list searched. The robots
// take their points and call `then` split over `run` (each robot's calls on
// one thread, in order). Reuses its scratch.
class NeighbourMisses {
 public:
  // `touched`: per robot of the slots, whether its lists may have changed
  // since the last call (all, after a Reset of the slots): only those are
  // read again for the targets they missed (an async round's few deciding
  // robots, not the whole team's N x M slots); cleared here, and set again
  // for `robots`, whose lists the call changes.
  template <typename Slot, typename Then>
  void Share(const DecisionContext& ctx, const std::vector<int>& robots,
             int num_targets, std::vector<Slot>* slots, Then then,
             std::vector<std::uint8_t>* touched, const RangeRunner& run = {},
             int workers = 1) {
    const double log_eps = std::log(ctx.eps);
    const auto points = static_cast<std::size_t>(ctx.map->lattice().size());
    if (mark_.size() != points) {
      mark_.assign(points, 0);
      stamp_ = 0;
    }
    if (static_cast<int>(takers_.size()) < std::max(1, workers))
      takers_.resize(std::max(1, workers));
    const auto at = [&](int i, int k) -> Slot& {
      return (*slots)[static_cast<std::size_t>(i) * num_targets + k];
    };
    // Per robot, the targets it missed any point of, in one pass over the
    // touched robots' slots (split over `run`): the unions below visit only
    // those, not every target.
    const int num_robots = static_cast<int>(touched->size());
    AIA_CHECK(slots->size() ==
              static_cast<std::size_t>(num_robots) * num_targets);
    if (static_cast<int>(missing_.size()) < num_robots)
      missing_.resize(num_robots);
    RunRange(run, num_robots, [&](int j0, int j1, int) {
      for (int j = j0; j < j1; ++j) {
        if (!(*touched)[j]) continue;
        (*touched)[j] = 0;
        missing_[j].clear();
        for (int k = 0; k < num_targets; ++k)
          if (!at(j, k).missed.empty()) missing_[j].push_back(k);
      }
    });
    for (int i : robots) (*touched)[i] = 1;  // the robots take below
    // The last call's unions, which the lists it shared refer to.
    ++call_;
    last_union_.swap(union_);
    last_groups_.swap(groups_);
    last_added_.assign(last_groups_.size(), 0);
    groups_.clear();
    hoods_.Clear();
    union_.clear();
    order_.assign(robots.begin(), robots.end());
    std::sort(order_.begin(), order_.end());
    // Every robot's neighbourhood and its union first, from the lists as
    // Update left them; then each robot takes what its own list lacks,
    // appends it (ascending) and calls then(i, k), the robots split over
    // `run`: a robot writes and reads its own lists only.
    group_of_.resize(order_.size());
    for (std::size_t o = 0; o < order_.size(); ++o)
      group_of_[o] = GroupOf(ctx, order_[o], num_targets, at);
    RunRange(run, static_cast<int>(order_.size()), [&](int o0, int o1, int w) {
      Taker& t = takers_[w];
      if (t.mark.size() != points) {
        t.mark.assign(points, 0);
        t.stamp = 0;
      }
      for (int o = o0; o < o1; ++o) {
        const int i = order_[o];
        const int group = group_of_[o];
        const Group& g = groups_[group];
        for (int a = g.begin; a < g.end;) {
          const int k = union_[a].first;
          int b = a;
          while (b < g.end && union_[b].first == k) ++b;
          Slot& s = at(i, k);
          if (!std::isnan(s.log_det) && s.log_det > log_eps &&
              ctx.beliefs->layout().is_static(k)) {
            MissList& own = s.missed;
            const std::size_t had = own.size();
            if (had != static_cast<std::size_t>(b - a)) {
              t.stamp = NextStampOf(&t.mark, t.stamp);
              for (int q : own) t.mark[q] = t.stamp;
              for (int c = a; c < b; ++c)
                if (t.mark[union_[c].second] != t.stamp)
                  own.push_back(union_[c].second);
            }
            own.MarkShared(group, call_);
            if (own.size() > had) then(i, k, group, w);
          }
          a = b;
        }
      }
    });
  }

 private:
  // One closed neighbourhood's union: union_[begin, end), (target, point)
  // ascending without duplicates; groups_[g] is hoods_' group g.
  struct Group {
    int begin = 0, end = 0;
  };
  // The index of robot i's group in groups_ (made if new).
  template <typename At>
  int GroupOf(const DecisionContext& ctx, int i, int num_targets,
              const At& at) {
    bool fresh = false;
    const int group = hoods_.Of(ctx, i, &fresh);
    if (!fresh) return group;
    Group g;
    g.begin = static_cast<int>(union_.size());
    // (target, robot) for each target a robot of the neighbourhood missed
    // points of, by target (robots ascending, as ForClosed visits them);
    // then per target, its robots' points, each once.
    pairs_.clear();
    ClosedNeighbourhoods::ForClosed(ctx, i, [&](int j) {
      for (int k : missing_[j]) pairs_.push_back({k, j});
    });
    SortByTarget(num_targets);
    const auto add = [this](int k, int q) {
      if (mark_[q] == stamp_) return;
      mark_[q] = stamp_;
      union_.push_back({k, q});
    };
    for (std::size_t a = 0; a < pairs_.size();) {
      const int k = pairs_[a].first;
      NextStamp();
      ++block_;
      const auto first = union_.size();
      for (; a < pairs_.size() && pairs_[a].first == k; ++a) {
        const MissList& list = at(pairs_[a].second, k).missed;
        std::size_t from = 0;
        const int last = list.SharedGroup(call_ - 1);
        if (last >= 0) {  // its first points: that union, added once
          from = list.shared();
          if (last_added_[last] != block_) {
            last_added_[last] = block_;
            const Group& lg = last_groups_[last];
            const auto lo = std::lower_bound(
                last_union_.begin() + lg.begin, last_union_.begin() + lg.end,
                std::pair<int, int>{k, std::numeric_limits<int>::min()});
            for (auto p = lo;
                 p != last_union_.begin() + lg.end && p->first == k; ++p)
              add(k, p->second);
          }
        }
        for (std::size_t c = from; c < list.size(); ++c) add(k, list[c]);
      }
      std::sort(union_.begin() + static_cast<std::ptrdiff_t>(first),
                union_.end());
    }
    g.end = static_cast<int>(union_.size());
    groups_.push_back(g);
    return group;
  }
  // pairs_ in ascending (target, robot) order: a counting sort by target
  // where the pairs outnumber the targets (each target's robots are already
  // ascending), else a sort.
  void SortByTarget(int num_targets) {
    if (pairs_.size() < static_cast<std::size_t>(num_targets)) {
      std::sort(pairs_.begin(), pairs_.end());
      return;
    }
    counts_.assign(static_cast<std::size_t>(num_targets) + 1, 0);
    for (const auto& p : pairs_) ++counts_[p.first + 1];
    for (int k = 0; k < num_targets; ++k) counts_[k + 1] += counts_[k];
    sorted_.resize(pairs_.size());
    for (const auto& p : pairs_) sorted_[counts_[p.first]++] = p;
    pairs_.swap(sorted_);
  }
  static std::uint32_t NextStampOf(std::vector<std::uint32_t>* marks,
                                   std::uint32_t stamp) {
    if (++stamp == 0) {  // wrapped: no stale mark may match
      std::fill(marks->begin(), marks->end(), 0u);
      stamp = 1;
    }
    return stamp;
  }
  void NextStamp() { stamp_ = NextStampOf(&mark_, stamp_); }
  // A thread's stamps over the lattice points (a robot's own list).
  struct Taker {
    std::vector<std::uint32_t> mark;
    std::uint32_t stamp = 0;
  };
  std::vector<Taker> takers_;                // per worker
  std::vector<int> group_of_;                // per robot of order_
  std::vector<std::vector<int>> missing_;    // per robot: targets missed
  std::vector<std::pair<int, int>> pairs_;   // (target, robot)
  std::vector<std::pair<int, int>> sorted_;  // SortByTarget's scratch
  std::vector<int> counts_;                  // SortByTarget's scratch
  std::vector<std::pair<int, int>> union_;   // (target, point) per group
  std::vector<Group> groups_;
  // The last call's union_ and groups_, and per group of it the union block
  // (block_) that last added its points.
  std::vector<std::pair<int, int>> last_union_;
  std::vector<Group> last_groups_;
  std::vector<std::uint64_t> last_added_;
  std::uint32_t call_ = 0;  // MissList's (it wraps after 2^32 calls)
  std::uint64_t block_ = 0;
  ClosedNeighbourhoods hoods_;
  std::vector<int> order_;
  std::vector<std::uint32_t> mark_;  // per lattice point
  std::uint32_t stamp_ = 0;
};

// What each robot's closed neighbourhood (the robot and its neighbours in
// this step's graph: what their messages carry) holds of each target, and
// which targets are open for the robot by it (IgbNetParams::open
// neighbours, learning/coordination.h). Per target: the smallest log det
// Sigma (`Best`), and the pooled level -2 log(mean_j exp(-log det_j / 2))
// (`Pooled`), which is at least log det of the neighbourhood's mean
// information for 2-D blocks (Minkowski's determinant inequality): what the
// consensus settles to without new measurements. A target is open unless
// a robot of the neighbourhood holds it below refresh x eps, or below eps
// while the pooled level is below eps too: one whose only holder's share is
// ebbing into the team opens again before it is lost. Robots with the same
// closed neighbourhood share one row (a full graph: one for the team), so a
// step costs O(groups x neighbourhood size x targets), the targets split
// over `run`.
class NeighbourhoodHolds {
 public:
  // For robots `robots` (Has is false for the others).
  void Compute(const DecisionContext& ctx, const std::vector<int>& robots,
               double refresh, const RangeRunner& run = {});
  bool Has(int robot) const {
    return robot >= 0 && robot < static_cast<int>(group_of_.size()) &&
           group_of_[robot] >= 0;
  }
  double Best(int robot, int k) const { return best_[Cell(robot, k)]; }
  double Pooled(int robot, int k) const { return pooled_[Cell(robot, k)]; }
  bool Open(int robot, int k) const { return open_[Cell(robot, k)] != 0; }

 private:
  std::size_t Cell(int robot, int k) const {
    return static_cast<std::size_t>(group_of_[robot]) * m_ + k;
  }
  int m_ = 0;
  ClosedNeighbourhoods hoods_;
  std::vector<int> group_of_;  // per robot; -1: not computed
  std::vector<double> best_, pooled_;
  std::vector<std::uint8_t> open_;
};

namespace internal {

// One robot's memory of one target in SearchMemory and SearchPoints.
struct AimSlot {
  double log_det = std::numeric_limits<double>::quiet_NaN();  // last seen
  Vec2 mean{0.0, 0.0};
  Vec2 aim{0.0, 0.0};
  MissList missed;
};
struct PointsSlot {
  double log_det = std::numeric_limits<double>::quiet_NaN();  // last seen
  Vec2 mean{0.0, 0.0};
  MissList missed;
  std::vector<Vec2> points;
};

// SearchMemory's walk over the rings, made once per neighbourhood, target
// and belief by Share: after Share the robots of a closed neighbourhood
// that search a target hold the same missed points, and in a full graph
// most of them hold the same belief too (bit for bit), so they walk the
// same rings and differ only in where they stand. A ring point keeps what
// its cost needs from any robot: the component, bounding box and corner
// sums of the lattice points that would measure a target there.
struct SharedWalk {
  struct RingPoint {
    Vec2 x{0.0, 0.0};
    int component = -1;                  // its observers': -1 none, -2 several
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // their bounding box (lattice)
    // min over them of ix + iy, -ix + iy, ix - iy, -ix - iy
    std::array<int, 4> corner{};
  };
  Vec2 mean{0.0, 0.0};
  Mat2 cov = Mat2::Zero();
  std::vector<int> ring_end;  // ring r: points[ring_end[r - 1], ring_end[r])
  std::vector<RingPoint> points;
};

// SearchPoints' points made once by Share for the others of the
// neighbourhood: they hold the same misses (its union), and where they also
// hold the same belief bit for bit and stand in the same component of the
// lattice, their points (and whether the misses were forgotten) are the
// same, since a point's observability reads only the component.
struct SharedPoints {
  Vec2 mean{0.0, 0.0};
  Mat2 cov = Mat2::Zero();
  int component = -1;
  bool forgot = false;
  std::vector<Vec2> points;
};

}  // namespace internal

// What SearchMemory and SearchPoints keep alike: a slot per robot and target
// (`Slot`, with its `missed` list and the log det and mean last seen), the
// misses counted, Update robot by robot (Derived::Record, the points it
// added) and Share through NeighbourMisses, after which each (robot,
// target) that took points is recomputed by Derived::RecomputeShared with
// this worker's ShareCache<Shared>, cleared by each Share.
template <typename Derived, typename Slot, typename Shared>
class MissSlots {
 public:
  void Reset(int num_robots, int num_targets);
  // Derived::Record for robot i after this step's fusion, at its lattice
  // point (the first call only records the belief).
  void Update(const DecisionContext& ctx, int robot);
  // Update for each robot of `robots`, split over `run`'s `workers`.
  void Update(const DecisionContext& ctx, const std::vector<int>& robots,
              const RangeRunner& run, int workers);
  // After every robot's Update: each robot among `robots` adds the points
  // its neighbours in this step's graph missed (for the static targets
  // still open in its own belief), from their lists as Update left them,
  // and recomputes what follows from them; the robots split over `run`.
  void Share(const DecisionContext& ctx, const std::vector<int>& robots,
             const RangeRunner& run = {}, int workers = 1);
  const std::vector<int>& Missed(int robot, int k) const {
    return slot(robot, k).missed.points();
  }
  int num_robots() const { return num_robots_; }
  int num_targets() const { return num_targets_; }
  // Points added to any robot's misses since Reset.
  long misses() const { return misses_; }

 protected:
  using Cache = ShareCache<Shared>;
  const Slot& slot(int i, int k) const {
    return slots_[static_cast<std::size_t>(i) * num_targets_ + k];
  }
  Slot& slot(int i, int k) {
    return slots_[static_cast<std::size_t>(i) * num_targets_ + k];
  }
  int num_robots_ = 0, num_targets_ = 0;

 private:
  Derived& derived() { return static_cast<Derived&>(*this); }
  // Update's work for one robot: per target it is still searching (not
  // measured, open, static), its point added to its misses where the
  // point sees where the target is looked for (Derived::Sees), then
  // Derived::Recompute; Derived::Settle first (what a slot keeps when the
  // search is over, or goes on). The points it added.
  int Record(const DecisionContext& ctx, int robot);
  long misses_ = 0;
  NeighbourMisses sharing_;
  std::vector<Slot> slots_;
  // Per robot: whether its lists may have changed since sharing_ last read
  // them (Record's and Share's robots; every robot after Reset).
  std::vector<std::uint8_t> touched_;
  std::vector<long> added_;    // per worker
  std::vector<Cache> caches_;  // per worker
};

// What one team's robots learned from their own missed measurements of
// static targets, per robot and target: the lattice points from which the
// robot saw its aim without measuring the target, and the aim that follows
// (SearchAim; the mean while nothing is missed). Moving targets are not
// searched (their aim is the mean). Nothing in it depends on the step
// number; robot i's memory depends on robot i's belief row and points only.
// Update: no measurement of the target while the robot's point saw the aim
// adds the point to what the robot missed (and moves the aim); a
// measurement clears it (the mean moved and the search is over). Measured:
// the robot's own measurements where the context has them, else a belief
// that shrank. Share moves the aims after the points taken.
class SearchMemory
    : public MissSlots<SearchMemory, internal::AimSlot, internal::SharedWalk> {
 public:
  // Where robot i looks for target k (its belief's mean until it missed).
  const Vec2& Aim(int robot, int k) const { return slot(robot, k).aim; }

 private:
  friend class MissSlots<SearchMemory, internal::AimSlot, internal::SharedWalk>;
  // SearchAim for robot's target k from its memory (forgets a prior
  // searched to 4 sigma); false then.
  bool Reaim(const DecisionContext& ctx, int robot, int k);
  // Reaim after Share, from the walk that robot shares with the others of
  // its neighbourhood `group` holding the same belief (internal::SharedWalk):
  // the same aim and return as Reaim.
  bool RecomputeShared(const DecisionContext& ctx, int robot, int k, int group,
                       Cache* cache);
  // MissSlots::Record's hooks: a finished search forgets its misses, and
  // with no miss the aim is the mean (Unmissed: unless no point of the
  // robot's component would measure a target there, a mean inside an
  // obstacle, where it is the nearest point of the prior one would, as
  // SearchAim picks it; the robots froze beside such a mean); the aim is
  // what a point must see.
  void Resized() {
    start_.assign(static_cast<std::size_t>(num_robots_) * num_targets_,
                  kUnchecked);
  }
  // Before an Update's robots (one thread): clear_ for this lattice.
  void Prepare(const DecisionContext& ctx);
  void Settle(std::size_t at, internal::AimSlot* s, bool searching);
  void Unmissed(const DecisionContext& ctx, int robot, int k);
  static bool Sees(const Map& map, const SensorModel& sensor, const Vec2& p,
                   const internal::AimSlot& s);
  void Recompute(const DecisionContext& ctx, int robot, int k) {
    Reaim(ctx, robot, k);
  }
  // Per slot, Unmissed's check of the mean once a search starts (kRing:
  // no point of the robot's component would measure a target there); kept
  // apart from the slots, which the default policy reads every step for
  // every robot and target.
  enum : std::uint8_t { kUnchecked, kMean, kRing };
  std::vector<std::uint8_t> start_;
  // Per lattice point of the lattice clear_for_: whether no occupancy cell
  // within half a step of it holds an obstacle, so that it sees every
  // point nearer to it than to any other (Unmissed's cheap test: a line of
  // sight per search start cost 0.2 s at 1000 x 1000).
  std::vector<std::uint8_t> clear_;
  std::uint64_t clear_for_ = 0;
};

// What each robot knows from its missed measurements of static targets, as
// a set: the input of a network that learns to search (learning/channels.h,
// ChannelParams::search), where SearchMemory above picks one aim for the
// hand-written rules. Per robot and target: the lattice points from which
// the robot (or, through Share, a neighbour) saw one of the target's search
// points without measuring the target, and the search points that follow:
// the mean while no missed point would have measured a target there, else
// every point of the first ring of the prior (WalkPriorRings) that is free,
// that no missed point would have measured, and that some free point of the
// robot's component would (where the robot can look). Nothing in it is
// chosen for the robot beyond that; nothing depends on the step number.
// Moving targets are not searched. Update: no measurement of the target
// (as SearchMemory's Update reads it) while the point saw one of its search
// points adds the point to the misses (and moves the search points); a
// measurement clears them.
class SearchPoints : public MissSlots<SearchPoints, internal::PointsSlot,
                                      internal::SharedPoints> {
 public:
  // Robot i's search points for target k; empty: its belief's mean.
  const std::vector<Vec2>& Points(int robot, int k) const {
    return slot(robot, k).points;
  }

 private:
  friend class MissSlots<SearchPoints, internal::PointsSlot,
                         internal::SharedPoints>;
  // The search points of robot i's target k from its misses (all forgotten
  // where the prior is searched to 4 sigma).
  void Recompute(const DecisionContext& ctx, int robot, int k);
  // Recompute after Share, from the points robot shares with the others of
  // its neighbourhood `group` (internal::SharedPoints): the same points and
  // misses as Recompute.
  void RecomputeShared(const DecisionContext& ctx, int robot, int k, int group,
                       Cache* cache);
  // MissSlots::Record's hooks: a finished search forgets its misses and
  // points; a point sees the search when it sees one of its points (the
  // mean while there are none).
  void Resized() {}
  void Prepare(const DecisionContext&) {}
  static void Settle(std::size_t, internal::PointsSlot* s, bool searching);
  void Unmissed(const DecisionContext&, int, int) {}
  static bool Sees(const Map& map, const SensorModel& sensor, const Vec2& p,
                   const internal::PointsSlot& s);
};

// The first move of a shortest lattice path from point p to the nearest
// lattice point (one move away or more) predicted to measure a target at one
// of the aims whose `open` flag is set; among the points at that distance,
// the one of the lowest target, then the lowest point index. kStay when no
// such point is reachable. What greedy does where no move gains anything,
// and the igbnet deadlock rule where the reach channel is flat. `target`, when
// given, receives the target the move heads for (-1 with kStay). Reuses its
// scratch: nothing is allocated once warm.
class TowardNearestAim {
 public:
  Move FirstMove(const Map& map, const SensorModel& sensor, int p,
                 const std::vector<Vec2>& aims,
                 const std::vector<std::uint8_t>& open, int* target = nullptr);

 private:
  std::vector<Vec2> centres_;  // lattice coordinates of the open aims
  std::vector<std::uint8_t> open_;
  PointGrid open_index_;
  std::vector<int> near_;
  std::vector<int> dist_, queue_;  // dist_ is -1 outside a BFS
  std::vector<Move> first_;
};

// Which open targets a robot claims among itself and its neighbours: each
// is owned by the robot with the fewest lattice moves to a point predicted
// to measure the target's aim (the aims' BFS fields over free space, so
// walls and doors count; ties to the robot of the lower x, then y, so that
// the robots' order does not matter). A robot that owns none helps: it
// claims the targets of owners that hold two or more where it is the
// nearest robot that owns none. A robot works this out from its own belief
// (the aims) and its neighbours' positions, as the DKF's graph gives them.
// The fields are kept per aim until the next Begin: a team that holds the
// same aims shares them (one BFS per target a step). A field reaches every
// point while targets x lattice points is at most kFieldBudget; beyond it
// (hundreds of targets in worlds of 60 m and more), each field reaches
// Horizon() moves from where its aim can be measured, so that a step's
// fields cost about kFieldBudget points however large the team, and a
// robot farther than that is out of reach for the claim. Claim, Route and
// Distance may be called from several threads at once between two Begins
// (the fields' cache and the plans are locked; answers do not depend on
// the order of the calls). Scratch reused.
class TargetClaims {
 public:
  static constexpr long kRouteBudget = 2000;
  // Route plans only where robots x open targets is at most this (the
  // tours' regret insertion grows as robots x targets^2): 40 x 40; beyond
  // it, Claim's answer.
  static constexpr long kRouteMaxPairs = 1600;
  // ... and over this many open targets at most: a robot with few
  // neighbours among hundreds of open targets (a range graph at scale)
  // would otherwise plan tours over all of them, each robot its own every
  // step (30 s a step at 200 robots).
  static constexpr long kRouteMaxTargets = 40;
  // Whether Route plans for a robot with `num_others` neighbours and
  // `num_open` open targets (else it gives Claim's answer).
  static bool Plans(long num_open, long num_others) {
    return num_open <= kRouteMaxTargets &&
           num_open * (num_others + 1) <= kRouteMaxPairs;
  }
  // Idle robots help only where robots x open targets is at most this
  // (80 x 80: the owners cost robots x targets per robot that owns none).
  static constexpr long kHelpMaxPairs = 6400;
  // Fields reach every lattice point while targets x points is at most
  // this (100 targets in a 100 x 100 m world of 0.5 m steps); beyond it,
  // Horizon() moves.
  static constexpr long kFieldBudget = 4000000;
  // How far a field reaches, in lattice moves from the points that measure
  // its aim, for `num_targets` targets on `lattice` with the sensor's
  // `span` (its range in lattice steps, rounded up, plus one): -1 (every
  // point) within kFieldBudget; else the most moves whose windows, of side
  // 2 (moves + span) + 1, cost kFieldBudget points for all the targets,
  // and at least 2 span.
  static int Horizon(int num_targets, const Lattice& lattice, int span);
  // A new step on this map, for `num_targets` targets (their fields'
  // horizon). The fields of aims the last step used are kept (a field is a
  // function of the map, the sensor, the horizon and the aim only), the
  // others dropped; all of them when the map, the sensor or the horizon is
  // another.
  void Begin(const Map& map, const SensorModel& sensor, int num_targets = 0);
  // Forgets every field (a new episode).
  void Reset();
  // Moves from lattice point p to the nearest point predicted to measure a
  // target at `aim`; -1 where none can be reached within the horizon.
  int Distance(const Vec2& aim, int p);
  // mine[k] (resized to aims.size()): `self` claims open target k, as
  // above, against `others` (lattice points). A target `self` cannot reach
  // is not its; none is where every open target is out of reach. An idle
  // robot helps only up to kHelpMaxPairs robots x open targets.
  void Claim(int self, const std::vector<int>& others,
             const std::vector<Vec2>& aims,
             const std::vector<std::uint8_t>& open,
             std::vector<std::uint8_t>* mine);
  // mine[k]: open target k is the first of `self`'s route in makespan
  // tours (planning/tours.h, the expert's routing) of `self` and `others`
  // over the open targets, legs from the same fields, kRouteBudget route
  // evaluations of local search; the robots ordered by position, so that
  // their labels do not matter. Robots given the same points and aims share
  // one plan per step. None where the route is empty. Claim's answer where
  // Plans() is false.
  void Route(int self, const std::vector<int>& others,
             const std::vector<Vec2>& aims,
             const std::vector<std::uint8_t>& open,
             std::vector<std::uint8_t>* mine);

 private:
  // Lattice moves to the nearest point that measures an aim, in a window
  // of lattice coordinates (the whole lattice, or the box the horizon can
  // reach); -1 outside it, beyond the horizon or unreachable.
  class AimField {
   public:
    int At(const Lattice& lattice, int p) const {
      if (whole_) return dist_[p];
      const int x = lattice.Ix(p) - x0_, y = lattice.Iy(p) - y0_;
      if (x < 0 || y < 0 || x >= nx_ || y >= ny_) return -1;
      return dist_[static_cast<std::size_t>(y) * nx_ + x];
    }
    // The first move (kMoves order) from p to a point one move nearer;
    // kStay at 0 or where none is.
    Move StepDown(const Lattice& lattice, int p) const;
    // The field of `sources` within `horizon` moves (-1: every point).
    void Compute(const Lattice& lattice, const std::vector<int>& sources,
                 int horizon, std::vector<int>* queue);
    const std::vector<int>& sources() const { return sources_; }
    // The step that last used the field.
    std::atomic<long> step{0};

   private:
    std::vector<int> sources_;
    bool whole_ = true;
    int x0_ = 0, y0_ = 0, nx_ = 0, ny_ = 0;
    std::vector<int> dist_;
  };
  // The field of `aim` (made if new; thread-safe): its address holds until
  // the next Begin.
  const AimField& Field(const Vec2& aim);
  // The robots' order wherever they tie: lattice point a's x, then y, below
  // b's.
  bool ByPosition(int a, int b) const;
  // What a robot and its neighbours work out, the same for every robot that
  // holds the same points and aims: the robots' points ordered by x, then
  // y; each open target's owner and (for owners of two or more) helper, as
  // indices into the points (-1: none); the tours, once planned.
  struct Plan {
    std::vector<int> points;
    std::vector<std::uint8_t> open;
    std::vector<Vec2> aims;
    std::vector<int> owner, helper;
    bool routed = false;
    std::vector<std::vector<int>> order;
  };
  // This step's plan for `self` and `others` (made if new); *at is self's
  // index in its points. Under plans_mutex_, held while the plan is read.
  Plan& PlanFor(int self, const std::vector<int>& others,
                const std::vector<Vec2>& aims,
                const std::vector<std::uint8_t>& open, int* at);
  class Legs;
  const Map* map_ = nullptr;
  const SensorModel* sensor_ = nullptr;
  std::vector<Plan> plans_;  // the first used_ are this step's
  int used_ = 0;
  std::vector<int> points_, held_, targets_;
  std::vector<double> weight_;
  TourPlanner planner_;
  // aim (its coordinates' bits) -> its field's slot in fields_ and the
  // step that last used it; the field's points (its sources) -> its slot,
  // so that aims a few bits or centimetres apart, which are measured from
  // the same points (robots' own beliefs of one target on a range graph),
  // share one field; free_ lists the unused slots. Fields are read under a
  // shared lock and added under an exclusive one; a field is made outside
  // the lock.
  struct Slot {
    int slot = -1;
    std::atomic<long> step{0};
  };
  std::shared_mutex fields_mutex_;
  std::mutex plans_mutex_;
  std::unordered_map<PointKey, Slot, PointKeyHash> index_;
  std::map<std::vector<int>, int> by_sources_;
  std::vector<std::unique_ptr<AimField>> fields_;
  int horizon_ = -1, span_ = 0;
  std::vector<int> free_;
  long step_ = 0;
  double range_ = 0.0;
};

// ---------------------------------------------------------------------------

// (cos, sin) of 2 pi a / count for a in [0, count), count in [1, 64]: the
// rings' directions, worked out once (the same numbers as computing each).
inline const Vec2* RingDirections(int count) {
  static const std::vector<std::vector<Vec2>> table = [] {
    std::vector<std::vector<Vec2>> t(65);
    for (int c = 1; c <= 64; ++c)
      for (int a = 0; a < c; ++a) {
        const double theta = 2.0 * M_PI * a / c;
        t[c].emplace_back(std::cos(theta), std::sin(theta));
      }
    return t;
  }();
  return table[count].data();
}

inline PriorRings::PriorRings(const Vec2& mean, const Mat2& cov, double step)
    : mean_(mean), step_(step) {
  Eigen::LLT<Mat2> llt(cov);
  l_ = llt.info() == Eigen::Success ? Mat2(llt.matrixL()) : Mat2::Identity();
  sigma_ = std::sqrt(std::max(cov(0, 0), cov(1, 1)));
}

template <typename F>
void PriorRings::Visit(int ring, F&& visit) const {
  constexpr double kRingStep = 0.25;
  const double rho = ring * kRingStep;
  const int count =
      ring == 0
          ? 1
          : std::clamp(
                static_cast<int>(std::ceil(2.0 * M_PI * rho * sigma_ / step_)),
                8, 64);
  const Vec2* direction = RingDirections(count);
  for (int a = 0; a < count; ++a)
    visit(Vec2(mean_ +
               l_ * Vec2(rho * direction[a].x(), rho * direction[a].y())));
}

template <typename Visit, typename Done>
int WalkPriorRings(const Vec2& mean, const Mat2& cov, double step,
                   Visit&& visit, Done&& done) {
  const PriorRings rings(mean, cov, step);
  for (int ring = 0; ring <= PriorRings::kLast; ++ring) {
    rings.Visit(ring, visit);
    if (done()) return ring;
  }
  return -1;
}

// The positions of the lattice points `missed` (may be null: none), in a
// scratch list of the calling thread, so that a walk over the rings reads
// them without working each out again.
inline const std::vector<Vec2>& MissedPoints(const Lattice& lattice,
                                             const std::vector<int>* missed) {
  thread_local std::vector<Vec2> points;
  points.clear();
  if (missed)
    for (int q : *missed) points.push_back(lattice.Point(q));
  return points;
}

// Whether a point of `missed` (MissedPoints) would have measured a target
// at x.
inline bool RuledOut(const Map& map, const SensorModel& sensor,
                     const std::vector<Vec2>& missed, const Vec2& x) {
  for (const Vec2& p : missed)
    if (PredictedPrecision(map, sensor, p, x) > 0.0) return true;
  return false;
}

template <typename Cost>
bool SearchAim(const Map& map, const SensorModel& sensor, const Vec2& mean,
               const Mat2& cov, const std::vector<int>* missed, Cost&& cost,
               Vec2* aim) {
  int best = std::numeric_limits<int>::max();
  const std::vector<Vec2>& ruled = MissedPoints(map.lattice(), missed);
  const int ring = WalkPriorRings(
      mean, cov, map.lattice().step(),
      [&](const Vec2& x) {
        if (!map.PointFree(x) || RuledOut(map, sensor, ruled, x)) return;
        const int c = cost(x, best);
        if (c < 0 || c >= best) return;
        best = c;
        *aim = x;
      },
      [&] { return best != std::numeric_limits<int>::max(); });
  if (ring >= 0) return true;
  *aim = mean;
  return false;
}

}  // namespace aia

#endif  // AIA_PLANNING_SEARCH_H_
