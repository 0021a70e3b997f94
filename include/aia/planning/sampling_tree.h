// The sampling-based tree search of C-SB (Kantaros et al. 2019; docs/design.md,
// Policies), shared by the expert (the whole team, the centralized filter) and
// Dec-SB (one robot, its own DKF belief).
//
// A node is (joint lattice configuration, per-target information blocks,
// accumulated cost J = sum_t sum_k det Sigma_k, depth, parent). Each iteration
// picks a node with f_V (with probability p_V one at the deepest level, else
// any), picks one move per robot with f_U (with probability p_U a step along
// the BFS distance field toward the robot's assigned target, else a random
// valid move) and adds the child, whose information is the Riccati map of the
// parent's: Omega' = (A Omega^-1 A' + Q)^-1 + sum_i r_i M'M. Nodes whose
// targets all have det Sigma_k <= eps join the goal set; after the first goal
// the search goes on for an anytime budget and returns the cheapest goal path.
//
// Storage is a flat arena (struct of arrays): no per-node heap allocation.
// The search is deterministic for a given Rng state, and a larger anytime
// budget only extends the same sequence of samples, so it never returns a
// costlier plan.
#ifndef AIA_PLANNING_SAMPLING_TREE_H_
#define AIA_PLANNING_SAMPLING_TREE_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/fields.h"
#include "aia/core/rng.h"
#include "aia/core/types.h"
#include "aia/estimation/belief.h"
#include "aia/estimation/sensor_model.h"
#include "aia/planning/aim_table.h"
#include "aia/planning/bucket_grid.h"
#include "aia/planning/node_arena.h"
#include "aia/planning/policy.h"
#include "aia/planning/tours.h"
#include "aia/world/map.h"

namespace aia {

// The most anytime iterations policy.anytime and `aia plan --budget` take.
inline constexpr double kMaxAnytime = 1e9;

// The tree's settings. The ones a user may set are declared (they are the
// expert's parameters, `policy:` keys); max_depth and p_sorted are set by the
// planners that use the tree.
struct SamplingParams {
  double p_v = 0.9;
  double p_u = 0.9;
  long anytime = 20000;
  long max_iterations = 200000;
  long max_nodes = 2000000;
  double p_tour = 0.5;
  long tour_budget = 20000;
  int max_depth = 0;  // 0: unlimited; else nodes this deep are not expanded
  // f_U's assignment: with this probability the globally nearest robot-target
  // pairs are matched first, else robots pick in a random order.
  double p_sorted = 0.5;
  // Tours, seeded rollouts and the idle rewrite (the expert); Dec-SB's short
  // single-robot trees go without.
  bool routing = true;
  // The spatial indexes of targets and robots (docs/design.md, Policies);
  // false scans every open target and robot instead, with the same plans
  // (for tests).
  bool spatial_index = true;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(p_v).In(kUnit).Doc(
        "f_V: probability of growing the newest branch (its deepest node) "
        "rather than a node of a uniformly drawn level"));
    a->Visit(AIA_FIELD(p_u).In(kUnit).Doc(
        "f_U: probability that a robot steps along the BFS field toward its "
        "assigned target rather than at random"));
    a->Visit(AIA_FIELD(p_tour).In(kUnit).Doc(
        "f_U: probability that the robots follow the best tours (each toward "
        "the next target of its tour not yet localized) rather than a "
        "nearest-first assignment"));
    a->Visit(AIA_FIELD(anytime)
                 .In(Between(0, kMaxAnytime))
                 .Doc("sampling iterations after the first goal (`aia plan "
                      "--budget`)"));
    a->Visit(AIA_FIELD(max_iterations)
                 .In(Between(1, 1e10))
                 .Doc("iterations allowed before a first goal"));
    a->Visit(AIA_FIELD(max_nodes)
                 .In(Between(2, 1e8))
                 .Doc("tree size cap (memory guard; the tree also stops "
                      "growing at 1 GiB)"));
    a->Visit(AIA_FIELD(tour_budget)
                 .In(Between(0, 1e8))
                 .Doc("route evaluations for the tours' local search "
                      "(relocate, swap, 2-opt)"));
  }
};

// A tree stops growing before its nodes would take more memory than this,
// whatever SamplingParams::max_nodes says. It is also the budget of all the
// trees of a process together (several threads of `aia eval`, Dec-SB's
// trees beside the expert's): a solve that may need a large arena waits
// until the trees solving at the same time leave it room (docs/design.md,
// Policies). Waiting changes when a plan is made, never which plan.
inline constexpr double kMaxTreeBytes = 1.0 * (1L << 30);

// The process's tree budget: kMaxTreeBytes unless set. Setting it (at least
// 64 MiB) is for a program that embeds the planner in less memory, or a
// test that checks the sharing without taking a GiB; set it before any
// solve starts.
double TreeBudgetBytes();
void SetTreeBudgetBytes(double bytes);

// Goal paths whose J is within this fraction of eps of the cheapest one
// count as equally good, and the shortest of them is returned. One step of
// one unlocalized target's latency adds more than eps to J, so this only
// ever trades the leftovers of localized targets (about 1e-3 per target and
// step with the default sensor) for a shorter horizon.
inline constexpr double kGoalTolerance = 0.1;

// A problem for the tree: the team (or one robot), where it stands and what
// it believes.
struct SamplingProblem {
  const Map* map = nullptr;
  const SensorModel* sensor = nullptr;
  double eps = 0.1;
  std::vector<int> start;             // lattice index per robot
  std::vector<std::uint8_t> active;   // inactive robots neither move nor sense
  const BeliefSet* belief = nullptr;  // root information
  int belief_row = 0;
  // Extra information per target added to every child at depth 1 (Dec-SB:
  // what the neighbours' planned next positions will measure), as r of r M'M.
  std::vector<double> extra_at_depth1;
  // Per static target, lattice points from which a robot was predicted to
  // measure it and did not (empty or one list per target): the prior there
  // is ruled out, and the target is planned where it has not been searched.
  std::vector<std::vector<int>> missed;
};

// A deterministic rollout seeded into the tree.
struct RolloutResult {
  std::string name;  // "tours", "makespan_tours", "nearest", "greedy"
  bool found = false;
  int depth = 0;
  double cost = 0.0;
};

struct SamplingPlan {
  bool found = false;      // a goal node was reached
  int depth = 0;           // F*: number of moves of the returned path
  double cost = 0.0;       // J of the returned path
  double best_cost = 0.0;  // J of the cheapest goal found (cost is within
                           // kGoalTolerance * eps of it)
  // A lower bound on the horizon: the farthest unlocalized static target's
  // observation region from its nearest active robot (at least 1).
  int bound = 0;
  // Per robot, the last depth at which it makes a measurement that counts (of
  // a target not yet below eps); its later moves follow the idle rule.
  std::vector<int> useful_until;
  std::vector<Vec2> aims;  // per target, where it is planned at the root
  std::vector<RolloutResult> rollouts;
  int tour_makespan = 0;  // of the latency tours, on the tours' own model
  // Joint configuration per depth, (depth + 1) x robots; row 0 is the start.
  std::vector<std::vector<int>> configs;
  // Planned det Sigma_k per depth, (depth + 1) x targets.
  std::vector<std::vector<double>> det;
  long nodes = 0;
  long iterations = 0;
  long first_goal_iteration = -1;
  double seconds = 0.0;
  std::size_t arena_bytes = 0;  // the node storage filled
  PolicyStatus status = PolicyStatus::kOk;
};

class SamplingTree {
 public:
  // Solves from scratch; reuses its arena between calls (no reallocation once
  // it has grown).
  SamplingPlan Solve(const SamplingProblem& problem,
                     const SamplingParams& params, Rng& rng);

 private:
  struct TargetInfo {
    int dim = 2;
    int offset = 0;  // into a node's packed information
    bool is_static = true;
  };
  enum class RolloutKind { kTours, kMakespanTours, kNearest, kGreedy };
  class Legs;

  void Prepare(const SamplingProblem& problem);
  int AddNode(int parent, const int* positions);
  double BlockDet(const double* packed, int k) const;
  // det Sigma_k after adding r to its position precision.
  double BlockDetAfter(const double* packed, int k, double r) const;
  void MarkOpen(int node);  // open_[k]: det Sigma_k > eps at the node
  void Assign(int node, bool sorted, Rng& rng);
  int NearestOpen(int q, int depth);
  // Spatial indexes (all targets static; docs/design.md, Policies): targets
  // by the centre of their observation region, robots of one configuration
  // by their point, in square buckets of lattice points.
  void BuildOpenIndex();
  void BuildRobotIndex(const int* positions);
  // The target with ok[k] != 0 nearest to q by its field (ties: the lowest
  // id), or -1; its distance in *dist. Exactly the linear scan over open_list_.
  int NearestTarget(int q, int depth, const std::vector<char>& ok, int* dist);
  // min over active robots of static target k's field at their points, or
  // INT_MAX when none reaches its region.
  int ReachOf(int k, const int* positions) const;
  int NextInTour(const std::vector<int>& tour) const;
  Move StepToward(int q, int k, int depth, Rng* rng);
  Leg ComputeLeg(int from, int t, int k);
  void PlanTours();
  int Rollout(RolloutKind kind, const SamplingParams& params);
  void RolloutMoves(int node, RolloutKind kind);
  // The greedy gain of measuring at lattice point v at `depth` with the
  // team's information `info` (GreedyMoves).
  double GreedyGain(const double* info, int depth, int v);
  void Register(int child, const SamplingParams& params);
  bool Expandable(int v, const SamplingParams& params) const;
  void Select();
  // Solve()'s steps. The root at the start configuration (a goal when every
  // target is localized there), and the lower bound on the horizon.
  int StartRoot(const SamplingProblem& problem, int* bound);
  // The tours and the four seeded rollouts (greedy, nearest, the tours).
  void SeededRollouts(const SamplingParams& params, int root,
                      SamplingPlan* plan);
  // The most nodes the rest of the solve can make.
  double MostNodes(const SamplingParams& params) const;
  void ReserveArena(double nodes);
  void ReleaseArena();
  // f_V: a node to expand, -1 for none this iteration, or kNothingToExpand.
  static constexpr int kNothingToExpand = -2;
  int SelectNode(const SamplingParams& params, Rng& rng);
  // f_U and the child it makes.
  void Expand(int node, const SamplingParams& params, Rng& rng);
  // The returned path (the best goal, idle moves rewritten, or the best
  // partial node) and what the plan reports.
  void ExtractPlan(const SamplingParams& params, SamplingPlan* plan);
  void UsefulUntil(const std::vector<int>& path, std::vector<int>* until);
  int RewriteIdle(int end);

  // Problem data.
  const SamplingProblem* problem_ = nullptr;
  int n_ = 0, m_ = 0, stride_ = 0;
  long node_cap_ = 0;  // max_nodes, or fewer to stay within the tree budget
  std::vector<TargetInfo> targets_;
  std::vector<const TargetModel*> models_;
  AimTable aims_;  // where each target is planned to be seen
  // Static targets observable from each lattice point: CSR (target, r).
  std::vector<int> obs_begin_;
  std::vector<std::pair<int, double>> obs_;
  // Prepare's scratch for obs_.
  struct Observed {
    int q, k;
    double r;
  };
  std::vector<Observed> observed_;
  std::vector<int> obs_fill_;
  bool any_moving_ = false;

  NodeArena arena_;
  std::vector<std::vector<int>> levels_;  // expandable nodes per depth
  // Search state.
  std::vector<int> goals_;  // goal nodes within the tolerance of j_min_
  double j_min_ = 0.0, tol_ = 0.0;
  // The best goal, the best partial node (fewest unlocalized targets, then
  // the smallest det sum: returned when no goal is found) and the newest.
  int best_ = -1, best_partial_ = 0, last_ = 0;
  long first_goal_iteration_ = -1, iteration_ = 0;
  // Tours.
  std::vector<std::vector<int>> tours_, makespan_tours_;
  int tour_makespan_ = 0;
  long tour_budget_ = 0;
  bool use_index_ = true;
  TourPlanner tour_planner_;
  // Scratch.
  std::vector<int> assigned_, order_, child_pos_;
  std::vector<char> open_;
  std::vector<std::pair<int, int>> pairs_;  // (distance, robot * m + target)
  // Spatial indexes.
  // Per static target, its region's bounds.
  std::vector<LatticeRect> region_box_;
  std::vector<const int*> static_field_;  // per static target, its field
  bool indexed_ = false;  // all targets static: the indexes are used
  int pad_ = 0;  // the largest distance from a region's centre to its bounds
  BucketGrid open_index_;        // the open targets by their region's centre
  bool open_indexed_ = false;    // open_index_ holds open_list_
  BucketGrid robot_index_;       // a node's active robots by their point
  bool robots_indexed_ = false;  // robot_index_ holds the current node's
  std::vector<int> open_list_;   // open targets, ascending
  std::vector<std::pair<int, int>> near_;  // (distance bound, target)
  std::vector<char> avail_;
};

}  // namespace aia

#endif  // AIA_PLANNING_SAMPLING_TREE_H_
