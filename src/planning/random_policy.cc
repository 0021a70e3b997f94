#include "aia/planning/random_policy.h"

#include <algorithm>

#include "aia/core/error.h"

namespace aia {

void CheckPolicyParams(const Scenario& scenario,
                       const std::vector<std::string>& allowed) {
  for (const auto& [key, value] : scenario.policy.params) {
    if (std::find(allowed.begin(), allowed.end(), key) != allowed.end())
      continue;
    std::string valid;
    for (const auto& a : allowed) valid += (valid.empty() ? "" : ", ") + a;
    const std::string full = "policy." + key;
    throw InputError(
        scenario.file, scenario.LineOf(full), full,
        "unknown parameter for policy '" + scenario.policy.name +
            "' (valid: " + (valid.empty() ? std::string("none") : valid) + ")");
  }
}

RandomPolicy::RandomPolicy(const Scenario& scenario) {
  CheckPolicyParams(scenario, {});
}

void RandomPolicy::Reset(const World& world, std::uint64_t seed) {
  rngs_.clear();
  for (int i = 0; i < world.NumRobots(); ++i)
    rngs_.emplace_back(seed, "policy.random", i);
}

PolicyStatus RandomPolicy::Decide(const DecisionContext& ctx,
                                  std::vector<Move>* moves) {
  const Lattice& lattice = ctx.world->lattice;
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < static_cast<int>(moves->size()); ++i) {
    (*moves)[i] = RandomValidMove(lattice, (*ctx.positions)[i], rngs_[i]);
    if ((*moves)[i] == Move::kStay && ctx.comm->Active(i))
      status = PolicyStatus::kNoValidMove;
  }
  return status;
}

}  // namespace aia
