// `aia bench`: decision steps per second on generated worlds, the share of
// wall time inside mj_step, where a step's time goes, and mujoco-testspeed's
// figure on the same generated model.
#ifndef AIA_COMMANDS_BENCH_H_
#define AIA_COMMANDS_BENCH_H_

#include <cstdint>
#include <string>
#include <vector>

#include "aia/core/field_values.h"
#include "aia/scenario/config.h"

namespace aia {

struct BenchOptions {
  std::vector<TeamSize> sizes{{10, 10}, {80, 80}};
  int steps = 60;
  int repeats = 5;
  std::uint64_t seed = 1;
  std::string policy = "random";
  bool skip_testspeed = false;
  // --expert: time the expert's solve from the initial state instead, over
  // `seeds` generated worlds per size (seeds seed .. seed + seeds - 1).
  bool expert = false;
  int seeds = 20;
  // --set key.path=value, applied to every generated scenario (after its
  // size and seed).
  std::vector<std::string> sets;
  // --network: time I-GBNet's network alone (inference at 10 and 80 robots
  // per batch, training at batch 16) for stem strides 1 and 2.
  bool network = false;
  // Threads of a learned policy's rendering and inference, and of a large
  // team's fusion (SetPolicyThreads; `aia run` uses every core, `aia eval`
  // one per worker).
  int policy_threads = 1;

  // The flags, declared once for `aia bench`'s flags and their checks.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(sizes).Doc("robots x targets, e.g. 10x10,80x80"));
    a->Visit(AIA_FIELD(steps)
                 .In(Between(1, limits::kMaxSteps))
                 .Doc("decision steps per run (mission.max_steps' range)"));
    a->Visit(AIA_FIELD(repeats)
                 .In(Between(1, 1000))
                 .Doc("runs per size (median reported)"));
    a->Visit(AIA_FIELD(seed).Doc("seed of the generated worlds"));
    a->Visit(AIA_FIELD(seeds)
                 .In(Between(1, 100000))
                 .Doc("with --expert: worlds per size"));
    a->Visit(AIA_FIELD(policy_threads)
                 .In(Between(1, 256))
                 .Doc("threads of a learned policy's rendering and inference, "
                      "and of a large team's fusion (aia run uses every "
                      "core)"));
  }
  // At least one size; with --expert, the last seed fits in 64 bits.
  void Validate(const FieldChecker& c) const;
};

int RunBench(const BenchOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_BENCH_H_
