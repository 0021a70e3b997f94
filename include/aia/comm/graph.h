// The communication graph of one decision step (docs/design.md, Communication):
// full or range-limited, minus the directed edges lost to packet loss, minus
// every edge of a failed robot. Directed: an edge (i <- j) means robot i
// received robot j's message this step.
#ifndef AIA_COMM_GRAPH_H_
#define AIA_COMM_GRAPH_H_

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "aia/core/fields.h"
#include "aia/core/point_grid.h"
#include "aia/core/rng.h"
#include "aia/core/types.h"

namespace aia {

enum class CommMode { kFull, kRange };
constexpr std::array<EnumName<CommMode>, 2> EnumNames(CommMode) {
  return {{{CommMode::kFull, "full"}, {CommMode::kRange, "range"}}};
}

// A robot isolated for good from a step on: it stops moving, sensing and
// talking, and the mission is judged on the others.
struct RobotFailure {
  static constexpr int kRandomRobot = -1;
  int robot = kRandomRobot;  // kRandomRobot: drawn from the scenario seed
  int step = 0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(robot)
                 .In(AtLeast(0))
                 .Keyword("random", kRandomRobot)
                 .Doc("the robot's index (named by one entry at most), or "
                      "random (drawn from the seed among the robots no other "
                      "entry names or drew, so that k random entries fail k "
                      "robots)"));
    a->Visit(AIA_FIELD(step)
                 .In(Between(0, 1e6))
                 .Doc("decision step from which it is isolated"));
  }
};

// Declared once: the scenario's `communication:` section and what the graph
// and the DKF use.
struct CommParams {
  CommMode mode = CommMode::kFull;
  double range = 4.0;
  double kappa_self = 0.75;
  double packet_loss_lambda = 0.0;
  std::vector<RobotFailure> failures;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(mode).Doc(
        "full: every pair of active robots talks; range: pairs within range"));
    a->Visit(AIA_FIELD(range)
                 .In(Between(1e-3, 1e6))
                 .Doc("r_com of range mode, metres"));
    a->Visit(AIA_FIELD(kappa_self)
                 .In(kHalfOpenUnit)
                 .Doc("DKF self weight; the neighbours share 1 - kappa_self "
                      "equally"));
    a->Visit(AIA_FIELD(packet_loss_lambda)
                 .In(Between(0, 1e3))
                 .Doc("Poisson mean of directed edges lost per step"));
    a->Visit(AIA_FIELD(failures).Doc(
        "robots that fail: isolated for good from their step on"));
  }
};

class CommNetwork {
 public:
  CommNetwork() = default;
  // `failures` are the scenario's, resolved: every robot index given.
  CommNetwork(const CommParams& params, int num_robots,
              std::vector<RobotFailure> failures, std::uint64_t seed);

  // Builds this step's graph from the robots' positions. Call once per step,
  // with increasing steps; packet loss draws from the network's own stream.
  // O(N^2) for the full graph (its edges), O(N + edges) in range mode; a
  // full graph without packet loss is kept from the step before while the
  // same robots are active (O(N)).
  void Update(int step, const std::vector<Vec2>& positions);
  // Marks inactive, from now on, the robots whose failure step is `step` or
  // earlier, and takes them out of the current graph (decisions on arrival
  // come between two Updates); whether any robot failed now.
  bool ApplyFailures(int step);

  int size() const { return n_; }
  // Robots whose messages robot i received this step (i excluded), ascending.
  const std::vector<int>& Neighbors(int i) const { return neighbors_[i]; }
  const std::vector<std::vector<int>>& AllNeighbors() const {
    return neighbors_;
  }
  bool Active(int i) const { return active_[i] != 0; }
  const std::vector<std::uint8_t>& active() const { return active_; }
  int NumActive() const;
  // Changes whenever the graph may have (a new graph, a failure), unique in
  // the process and never 0: readers that derive something from the graph
  // (the DKF's weights) keep it while the stamp stays.
  std::uint64_t graph_stamp() const { return graph_stamp_; }
  // Directed edges (receiver, sender) that were in range but lost this step.
  const std::vector<std::pair<int, int>>& Lost() const { return lost_; }

 private:
  CommParams params_;
  int n_ = 0;
  std::vector<RobotFailure> failures_;
  Rng rng_;
  std::vector<std::uint8_t> active_;
  std::vector<std::vector<int>> neighbors_;
  std::vector<std::pair<int, int>> lost_;
  std::uint64_t graph_stamp_ = 0;
  // The active robots the full graph in neighbors_ was built for (empty:
  // none is kept).
  std::vector<std::uint8_t> full_active_;
  // Scratch: the lost edges' numbers, the range mode's grid of robots.
  std::vector<std::uint64_t> drop_;
  PointGrid grid_;
};

}  // namespace aia

#endif  // AIA_COMM_GRAPH_H_
