// Multi-robot tours over observation regions (docs/design.md, Policies): what
// a routing solver knows about the expert's problem, given to its sampling
// tree as seed branches and as f_U's bias.
//
// With static targets and a sensor that localizes a target with one
// measurement, the expert's problem is multi-robot routing: every target's
// observation region must be visited, and J is (nearly) the sum over targets
// of det Sigma_k times the step at which the region is reached. A tour is an
// ordered target list per robot; its legs come from the tree's BFS fields
// (LegOracle). Tours are built by regret insertion and improved by relocate,
// swap and 2-opt moves under a deterministic evaluation budget.
#ifndef AIA_PLANNING_TOURS_H_
#define AIA_PLANNING_TOURS_H_

#include <array>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace aia {

// One leg of a route: the number of steps from a lattice point to target k's
// observation region, leaving at step t, and the point where it ends.
struct Leg {
  int steps = -1;  // -1: the region cannot be reached from there
  int end = -1;
};

class LegOracle {
 public:
  virtual ~LegOracle() = default;
  virtual Leg Compute(int from, int t, int k) = 0;
  // A cheap estimate of a leg's steps from `from` at step 0 (-1: cannot be
  // reached), used only to rank the robots nearest to a target.
  virtual int Distance(int from, int k) { return Compute(from, 0, k).steps; }
  // Whether legs toward k depend on the departure step (moving targets).
  virtual bool TimeVarying(int k) const = 0;
};

// What a set of tours optimizes: kLatency is the weighted sum of arrival
// steps (J's routing part); kMakespan is the last arrival (F*), with the
// latency sum as a small tie-breaker.
enum class TourObjective { kLatency, kMakespan };

struct TourSettings {
  TourObjective objective = TourObjective::kLatency;
  long budget = 20000;  // route evaluations allowed for the local search
  // Regret insertion tries each target in the routes of the robots whose
  // starts are nearest to it (LegOracle::Distance), this many of them; in
  // every route when there are no more robots than that.
  int candidates = 80;
  // Legs regret insertion may look up at the most (each route a target is
  // tried in, at every position). Insertion costs about M^4 / 3 legs for
  // one robot and M targets (1e8 near 130 targets, a second or two); past
  // this, the targets left join the routes at their ends, each where it
  // costs least, so that a plan with many targets per robot ends.
  long insert_work = 100000000;
};

struct Tours {
  std::vector<std::vector<int>> order;  // per robot, target ids in visit order
  std::vector<int> unassigned;          // targets no robot can reach
  double latency = 0.0;                 // sum_k weight_k * arrival_k
  int makespan = 0;                     // the last arrival
  long evaluations = 0;                 // route evaluations spent
};

class TourPlanner {
 public:
  // starts: lattice point per robot (inactive robots left out by the caller
  // get empty tours: pass -1); targets: the ids to visit; weight: per target
  // id, the cost of one step of its latency.
  Tours Plan(const std::vector<int>& starts, const std::vector<int>& targets,
             const std::vector<double>& weight, const TourSettings& settings,
             LegOracle& legs);

 private:
  struct RouteValue {
    double latency = 0.0;
    int makespan = 0;
    bool feasible = true;
  };
  RouteValue Evaluate(int robot, const std::vector<int>& route);
  RouteValue Value(int robot, const std::vector<int>& route);  // uncounted

  // Regret insertion (Plan's first phase): every target into a route.
  // Past settings.insert_work, AppendRest.
  void Insert(const std::vector<int>& robots, const std::vector<int>& targets,
              const TourSettings& settings, Tours* tours,
              std::vector<RouteValue>* values);
  // The targets `rest` (indices into `targets`), in order, each at the end
  // of the candidate route where the objective grows least.
  void AppendRest(const std::vector<int>& targets, const std::vector<int>& rest,
                  Tours* tours, std::vector<RouteValue>* values);
  // Each target's candidate robots (candidates_) and their scratch.
  void ChooseCandidates(const std::vector<int>& robots,
                        const std::vector<int>& targets,
                        const TourSettings& settings);
  // Where target k (index t of the targets) goes best, and its regret.
  struct Insertion;
  Insertion BestInsertion(int t, int k, const Tours& tours,
                          const std::vector<RouteValue>& values,
                          const std::vector<long>& version);

  // The local search (Plan's second phase): relocate, swap and 2-opt moves,
  // first improvement, until no move improves or the budget is spent. Each
  // move returns whether it took one.
  struct Search;
  void LocalSearch(const std::vector<int>& robots, const TourSettings& settings,
                   Tours* tours, std::vector<RouteValue>* values);
  bool Relocate(Search* s);  // one target to any position of any route
  bool Swap(Search* s);      // two targets, in one route or two
  bool TwoOpt(Search* s);    // a stretch of one route reversed
  // Takes route a (and b, unless b < 0) when that lowers the objective.
  bool Take(Search* s, int a, const std::vector<int>& route_a,
            const RouteValue& va, int b, const std::vector<int>& route_b,
            const RouteValue& vb);

  void Summarize(const std::vector<RouteValue>& values);
  double Objective(const std::vector<RouteValue>& values);
  double ObjectiveWith(const std::vector<RouteValue>& values, int a,
                       const RouteValue& va, int b, const RouteValue& vb) const;
  Leg CachedLeg(int from, int t, int k);

  LegOracle* legs_ = nullptr;
  const std::vector<int>* starts_ = nullptr;
  const std::vector<double>* weight_ = nullptr;
  TourObjective objective_ = TourObjective::kLatency;
  long evaluations_ = 0;
  long insert_work_ = 0;  // legs regret insertion looked up (upper bound)
  double weight_sum_ = 0.0;
  double latency_ = 0.0;                      // sum over routes
  std::array<std::pair<int, int>, 3> top_{};  // largest (makespan, robot)
  std::unordered_map<std::uint64_t, Leg> cache_;
  // Regret insertion's scratch, per target (its index in `targets`) and
  // candidate robot: the value of the robot's route with the target inserted
  // at each position, and the version of the route it was computed on.
  std::vector<std::vector<int>> candidates_;
  std::vector<std::vector<std::vector<RouteValue>>> inserted_;
  std::vector<std::vector<long>> inserted_version_;
  std::vector<int> trial_;  // a route with a target inserted
};

}  // namespace aia

#endif  // AIA_PLANNING_TOURS_H_
