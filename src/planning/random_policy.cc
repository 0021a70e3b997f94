#include "aia/planning/random_policy.h"

namespace aia {

void RandomPolicy::Reset(const Map&, int num_robots, int, std::uint64_t seed) {
  rngs_.clear();
  for (int i = 0; i < num_robots; ++i)
    rngs_.emplace_back(seed, "policy.random", i);
}

PolicyStatus RandomPolicy::Decide(const DecisionContext& ctx,
                                  std::vector<Move>* moves) {
  const Lattice& lattice = ctx.map->lattice();
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < static_cast<int>(moves->size()); ++i) {
    if (!Deciding(ctx, i)) {  // on its way (async decisions)
      (*moves)[i] = Move::kStay;
      continue;
    }
    (*moves)[i] = RandomValidMove(lattice, (*ctx.robot_lattice)[i], rngs_[i]);
    if ((*moves)[i] == Move::kStay && ctx.comm->Active(i))
      status = PolicyStatus::kNoValidMove;
  }
  return status;
}

}  // namespace aia
