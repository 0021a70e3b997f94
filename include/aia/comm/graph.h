// The communication graph of one decision step (SPEC section 6): full or
// range-limited, minus the directed edges lost to packet loss, minus every
// edge of a failed robot. Directed: an edge (i <- j) means robot i received
// robot j's message this step.
#ifndef AIA_COMM_GRAPH_H_
#define AIA_COMM_GRAPH_H_

#include <cstdint>
#include <utility>
#include <vector>

#include "aia/core/rng.h"
#include "aia/core/types.h"

namespace aia {

struct CommParams {
  bool range_limited = false;  // false: every pair of active robots talks
  double range = 4.0;          // r_com when range_limited
  double loss_lambda = 0.0;    // Poisson mean of directed edges lost per step
};

struct ScheduledFailure {
  int robot = 0;
  int step = 0;  // isolated from this step on, for good
};

class CommNetwork {
 public:
  CommNetwork() = default;
  CommNetwork(const CommParams& params, int num_robots,
              std::vector<ScheduledFailure> failures, std::uint64_t seed);

  // Builds this step's graph from the robots' positions. Call once per step,
  // with increasing steps; packet loss draws from the network's own stream.
  void Update(int step, const std::vector<Vec2>& positions);

  int size() const { return n_; }
  // Robots whose messages robot i received this step (i excluded), ascending.
  const std::vector<int>& Neighbors(int i) const { return neighbors_[i]; }
  const std::vector<std::vector<int>>& AllNeighbors() const {
    return neighbors_;
  }
  bool Active(int i) const { return active_[i] != 0; }
  const std::vector<std::uint8_t>& active() const { return active_; }
  int NumActive() const;
  // Directed edges (receiver, sender) that were in range but lost this step.
  const std::vector<std::pair<int, int>>& Lost() const { return lost_; }

 private:
  CommParams params_;
  int n_ = 0;
  std::vector<ScheduledFailure> failures_;
  Rng rng_;
  std::vector<std::uint8_t> active_;
  std::vector<std::vector<int>> neighbors_;
  std::vector<std::pair<int, int>> edges_;  // scratch: candidate directed edges
  std::vector<std::pair<int, int>> lost_;
  std::vector<std::uint8_t> drop_;
};

}  // namespace aia

#endif  // AIA_COMM_GRAPH_H_
