// What a policy may know, by construction: this distributed policy compiles
// against the public headers as it is, and each AIA_REACH_FOR_TRUTH variant,
// which reaches for the ground truth through what a policy is given, must
// not compile (tests/CMakeLists.txt builds all of them). Not linked anywhere.
#include <vector>

#include "aia/planning/policy.h"

namespace {

class Probe : public aia::Policy {
 public:
  std::string_view name() const override { return "probe"; }
  void Reset(const aia::Map& map, int, int, std::uint64_t) override {
#if AIA_REACH_FOR_TRUTH == 3
    (void)map.targets;  // the map holds no targets
#elif AIA_REACH_FOR_TRUTH == 4
    (void)map.truth;  // nor the ground truth
#else
    (void)map.lattice();
#endif
  }
  aia::PolicyStatus Decide(const aia::DecisionContext& ctx,
                           std::vector<aia::Move>* moves) override {
#if AIA_REACH_FOR_TRUTH == 1
    (void)ctx.world;  // the context carries the map, not the world
#elif AIA_REACH_FOR_TRUTH == 2
    (void)ctx.truth;  // nor the ground truth
#elif AIA_REACH_FOR_TRUTH == 5
    (void)ctx.map->priors;  // nor the instance's targets
#else
    (void)ctx.map->lattice();
#endif
    moves->assign(moves->size(), aia::Move::kLeft);
    return aia::PolicyStatus::kOk;
  }
};

}  // namespace

aia::Policy* MakeProbe() { return new Probe(); }
