#include "aia/comm/graph.h"

#include <algorithm>

#include "aia/core/check.h"

namespace aia {

CommNetwork::CommNetwork(const CommParams& params, int num_robots,
                         std::vector<RobotFailure> failures, std::uint64_t seed)
    : params_(params),
      n_(num_robots),
      failures_(std::move(failures)),
      rng_(seed, "packet_loss"),
      active_(num_robots, 1),
      neighbors_(num_robots) {
  for (const auto& f : failures_) AIA_CHECK(f.robot >= 0 && f.robot < n_);
}

int CommNetwork::NumActive() const {
  int count = 0;
  for (auto a : active_) count += a;
  return count;
}

void CommNetwork::Update(int step, const std::vector<Vec2>& positions) {
  AIA_CHECK(static_cast<int>(positions.size()) == n_);
  for (const auto& f : failures_)
    if (step >= f.step) active_[f.robot] = 0;
  edges_.clear();
  const double r2 = params_.range * params_.range;
  for (int i = 0; i < n_; ++i) {
    if (!active_[i]) continue;
    for (int j = 0; j < n_; ++j) {
      if (j == i || !active_[j]) continue;
      if (params_.mode == CommMode::kRange &&
          (positions[i] - positions[j]).squaredNorm() > r2)
        continue;
      edges_.push_back({i, j});
    }
  }
  // Packet loss: Poisson(lambda) distinct directed edges, uniformly chosen.
  lost_.clear();
  drop_.assign(edges_.size(), 0);
  if (params_.packet_loss_lambda > 0.0) {
    const int k = std::min<int>(rng_.Poisson(params_.packet_loss_lambda),
                                static_cast<int>(edges_.size()));
    for (int c = 0; c < k; ++c) {
      // Floyd's algorithm would also do; rejection is fine for k << edges.
      size_t e;
      do {
        e = rng_.UniformInt(edges_.size());
      } while (drop_[e]);
      drop_[e] = 1;
    }
  }
  for (auto& nb : neighbors_) nb.clear();
  for (size_t e = 0; e < edges_.size(); ++e) {
    if (drop_[e]) {
      lost_.push_back(edges_[e]);
    } else {
      neighbors_[edges_[e].first].push_back(edges_[e].second);
    }
  }
}

}  // namespace aia
