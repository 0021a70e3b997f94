// An aia program with one more policy: every command of `aia` (run, eval,
// render, policies, ...) with `nearest_mean` among the policies.
//
// nearest_mean: each robot steps toward the mean of the nearest target its
// own belief holds above eps (by straight-line distance, along the larger
// coordinate gap, a valid move when that one is blocked). It reads only
// what it is given: the DecisionContext.
#include <cmath>
#include <memory>

#include "aia/commands/cli.h"
#include "aia/planning/policy.h"
#include "aia/planning/registry.h"
#include "aia/runtime/policies.h"

namespace {

class NearestMeanPolicy : public aia::NamedPolicy<NearestMeanPolicy> {
 public:
  static constexpr std::string_view kName = "nearest_mean";

  void Reset(const aia::Map&, int, int, std::uint64_t) override {}

  aia::PolicyStatus Decide(const aia::DecisionContext& ctx,
                           std::vector<aia::Move>* moves) override {
    const aia::Lattice& lattice = ctx.map->lattice();
    const int targets = ctx.beliefs->layout().num_targets();
    for (std::size_t i = 0; i < moves->size(); ++i) {
      const int here = (*ctx.robot_lattice)[i];
      const aia::Vec2 p = lattice.Point(here);
      double best = INFINITY;
      aia::Vec2 goal = p;
      for (int k = 0; k < targets; ++k) {
        if (ctx.beliefs->DetCovariance(static_cast<int>(i), k) < ctx.eps)
          continue;
        const aia::Vec2 mean =
            ctx.beliefs->PositionMean(static_cast<int>(i), k);
        if ((mean - p).norm() < best) {
          best = (mean - p).norm();
          goal = mean;
        }
      }
      const aia::Vec2 d = goal - p;
      const aia::Move along_x =
          d.x() > 0 ? aia::Move::kRight : aia::Move::kLeft;
      const aia::Move along_y = d.y() > 0 ? aia::Move::kUp : aia::Move::kDown;
      aia::Move m = std::abs(d.x()) >= std::abs(d.y()) ? along_x : along_y;
      if (!lattice.Valid(here, m)) m = m == along_x ? along_y : along_x;
      (*moves)[i] = m;  // the world rule replaces a move still invalid
    }
    return aia::PolicyStatus::kOk;
  }
};

void AddMine(aia::PolicyRegistry* registry) {
  registry->Add<NearestMeanPolicy, aia::NoParams>(
      "toward the nearest target mean above eps in the robot's own belief "
      "(an example from examples/cpp_policy)",
      [](const aia::NoParams&) {
        return std::make_unique<NearestMeanPolicy>();
      });
}

}  // namespace

int main(int argc, char** argv) {
  aia::RegisterPolicies(&AddMine);
  return aia::CliMain(argc, argv);
}
