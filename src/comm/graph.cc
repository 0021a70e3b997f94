#include "aia/comm/graph.h"

#include <algorithm>
#include <atomic>

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

namespace {

std::uint64_t NewGraphStamp() {
  static std::atomic<std::uint64_t> last{0};
  return ++last;
}

}  // namespace

bool CommNetwork::ApplyFailures(int step) {
  bool any = false;
  for (const auto& f : failures_) {
    if (step >= f.step && active_[f.robot]) {
      active_[f.robot] = 0;
      any = true;
    }
  }
  if (!any) return false;
  graph_stamp_ = NewGraphStamp();
  for (int i = 0; i < n_; ++i) {
    std::vector<int>& nb = neighbors_[i];
    if (!active_[i]) {
      nb.clear();
      continue;
    }
    nb.erase(std::remove_if(nb.begin(), nb.end(),
                            [this](int j) { return !active_[j]; }),
             nb.end());
  }
  return true;
}

void CommNetwork::Update(int step, const std::vector<Vec2>& positions) {
  AIA_CHECK(static_cast<int>(positions.size()) == n_);
  for (const auto& f : failures_)
    if (step >= f.step) active_[f.robot] = 0;
  lost_.clear();
  // A full graph without loss is the same while the same robots are active
  // (ApplyFailures changes active_, so it is built again after one).
  const bool keep =
      params_.mode != CommMode::kRange && params_.packet_loss_lambda <= 0.0;
  if (keep && full_active_ == active_) return;
  graph_stamp_ = NewGraphStamp();
  full_active_.clear();
  // The candidate edges (i <- j), each robot's ascending: every other
  // active robot, or those in range.
  for (auto& nb : neighbors_) nb.clear();
  if (params_.mode == CommMode::kRange) {
    // O(N + edges) through a grid of the active robots.
    grid_.Build(positions, params_.range, &active_);
    for (int i = 0; i < n_; ++i) {
      if (!active_[i]) continue;
      grid_.Near(positions, positions[i], params_.range, &neighbors_[i]);
      auto self = std::find(neighbors_[i].begin(), neighbors_[i].end(), i);
      if (self != neighbors_[i].end()) neighbors_[i].erase(self);
    }
  } else {
    for (int i = 0; i < n_; ++i) {
      if (!active_[i]) continue;
      for (int j = 0; j < n_; ++j)
        if (j != i && active_[j]) neighbors_[i].push_back(j);
    }
    if (keep) full_active_ = active_;
  }
  // Packet loss: Poisson(lambda) distinct directed edges, uniformly chosen
  // among the candidates numbered in order (receiver, then sender).
  if (params_.packet_loss_lambda <= 0.0) return;
  std::size_t edges = 0;
  for (const auto& nb : neighbors_) edges += nb.size();
  const std::size_t k =
      std::min<std::size_t>(rng_.Poisson(params_.packet_loss_lambda), edges);
  drop_.clear();
  for (std::size_t c = 0; c < k; ++c) {
    std::uint64_t e;
    do {
      e = rng_.UniformInt(edges);
    } while (std::find(drop_.begin(), drop_.end(), e) != drop_.end());
    drop_.push_back(e);
  }
  std::sort(drop_.begin(), drop_.end());
  // Remove the dropped edges, walking the numbering once.
  std::size_t first = 0, next = 0;
  for (int i = 0; i < n_ && next < drop_.size(); ++i) {
    std::vector<int>& nb = neighbors_[i];
    const std::size_t end = first + nb.size();
    std::size_t kept = 0;
    for (std::size_t e = first; e < end; ++e) {
      const int j = nb[e - first];
      if (next < drop_.size() && drop_[next] == e) {
        lost_.push_back({i, j});
        ++next;
      } else {
        nb[kept++] = j;
      }
    }
    nb.resize(kept);
    first = end;
  }
}

}  // namespace aia
