#include "aia/runtime/generated.h"

#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/runtime/instance.h"

namespace aia {

Scenario GeneratedWith(int robots, int targets, std::uint64_t seed,
                       const std::vector<Override>& overrides) {
  Scenario s = GeneratedScenario(robots, targets, seed);
  const std::string key = "workspace.obstacles.generator";
  for (const Override& o : overrides)
    if (o.path == key || o.path.rfind(key + ".", 0) == 0)
      s.workspace.obstacles.random.reset();
  return WithOverrides(s, overrides);
}

Scenario GeneratedScenario(int robots, int targets, std::uint64_t seed) {
  Scenario s;
  s.name =
      "generated_" + std::to_string(robots) + "x" + std::to_string(targets);
  s.seed = seed;
  s.workspace.obstacles.random = RandomObstaclesConfig{};
  s.robots.count = robots;
  s.targets.count = targets;
  return s;
}

namespace {

std::string FlagKey(const Override& o) {
  return o.flag == "--set" ? "--set " + o.path : o.flag;
}

// The spec's scenario with its first `n` overrides, unchanged when there
// are none.
Scenario WithFirstOverrides(const GeneratedSpec& spec, std::size_t n) {
  return GeneratedWith(spec.robots, spec.targets, spec.seed,
                       std::vector<Override>(spec.overrides.begin(),
                                             spec.overrides.begin() + n));
}

}  // namespace

Scenario ReadGenerated(const GeneratedSpec& spec) {
  try {
    // WithOverrides reads back and checks even when there are none.
    Scenario s = WithFirstOverrides(spec, spec.overrides.size());
    ReportWarnings(s);
    return s;
  } catch (const InputError& e) {
    NameTheFlag(e, spec);
  }
}

std::shared_ptr<const Instance> BuildGenerated(const Scenario& s,
                                               const GeneratedSpec& spec) {
  try {
    return BuildInstance(s);
  } catch (const InputError& e) {
    NameTheFlag(e, spec);
  }
}

void NameTheFlag(const InputError& error, const GeneratedSpec& spec) {
  if (error.file() == "command line") throw error;
  const std::string size = spec.size_flag + " " + spec.size;
  const std::string world = " (in the generated world of " + size + ", seed " +
                            std::to_string(spec.seed) + ")";
  // Read (then build the world) with more and more of the overrides: the
  // first that fails is the one at fault; when the size alone fails, the
  // size is.
  for (const bool build : {false, true}) {
    for (std::size_t n = 0; n <= spec.overrides.size(); ++n) {
      try {
        const Scenario s = WithFirstOverrides(spec, n);
        if (build) BuildInstance(s);
      } catch (const InputError& e) {
        if (e.file() == "command line") throw;
        const std::string why = e.key() + ": " + e.message();
        if (n == 0) {
          throw InputError::Flag(
              spec.size_flag,
              build ? why + world : "'" + spec.size + "': " + why);
        }
        throw InputError::Flag(
            FlagKey(spec.overrides[n - 1]),
            why + (build ? world
                         : " (in the generated scenario of " + size + ")"));
      }
    }
  }
  // Not found again: the size and seed it was found with.
  throw InputError::Flag(spec.size_flag,
                         error.key() + ": " + error.message() + world);
}

}  // namespace aia
