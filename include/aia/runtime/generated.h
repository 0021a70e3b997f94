// The generated worlds of the experiments and of the commands that make
// them from flags (aia eval, aia bench, aia dataset): a scenario from a size,
// a seed and --set overrides, and errors about it named by the flag at fault.
#ifndef AIA_RUNTIME_GENERATED_H_
#define AIA_RUNTIME_GENERATED_H_

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/error.h"
#include "aia/scenario/config.h"
#include "aia/scenario/loader.h"

namespace aia {

struct Instance;

// The generated worlds of the experiments (docs/design.md, Evaluation): 20 x 20
// m, 30 random boxes, N robots and M random static targets, all drawn from
// `seed`.
Scenario GeneratedScenario(int robots, int targets, std::uint64_t seed);

// A generated scenario as a command makes it from its flags: a size (given
// to `size_flag` as `size`), a seed and the overrides (--set).
struct GeneratedSpec {
  std::string size;  // its label, e.g. "10x10" (TeamSize::ToText)
  std::string size_flag = "--sizes";
  int robots = 0;
  int targets = 0;
  std::uint64_t seed = 0;
  std::vector<Override> overrides;
};

// The generated scenario with `overrides` applied. A structured world given
// by them (workspace.obstacles.generator) takes the place of the random
// boxes, which it cannot be combined with.
Scenario GeneratedWith(int robots, int targets, std::uint64_t seed,
                       const std::vector<Override>& overrides);

// The spec's scenario, read back and checked as a file's would be.
// InputErrors name the flag behind them (NameTheFlag).
Scenario ReadGenerated(const GeneratedSpec& spec);

// An InputError about a generated scenario, which has no file, as one about
// the command-line flag behind it: the size's flag when the size alone is
// refused, else the first override that makes the scenario invalid, or
// (when every read passes) its world fail to build. One that names a flag
// already is thrown as it is.
[[noreturn]] void NameTheFlag(const InputError& error,
                              const GeneratedSpec& spec);

// Builds `s`, the spec's scenario (as ReadGenerated gives it, perhaps with
// settings the command fixes itself): its InputErrors name the flag behind
// them (NameTheFlag).
std::shared_ptr<const Instance> BuildGenerated(const Scenario& s,
                                               const GeneratedSpec& spec);

}  // namespace aia

#endif  // AIA_RUNTIME_GENERATED_H_
