#include "aia/commands/world_command.h"

#include <cstdio>
#include <filesystem>

#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"
#include "aia/scenario/loader.h"
#include "aia/world/mjcf.h"

namespace aia {

int RunWorldCommand(const WorldOptions& o) {
  if (o.out.empty())
    throw InputError::Flag("--out", "an output file is needed");
  const std::filesystem::path out(o.out);
  const std::filesystem::path parent =
      out.has_parent_path() ? out.parent_path() : ".";
  // A missing folder is made, as every command makes its --out's (below,
  // once the scenario is known to be good); one that is a file is refused.
  std::error_code ec;
  if (std::filesystem::exists(parent, ec) &&
      !std::filesystem::is_directory(parent, ec))
    throw InputError::Flag("--out",
                           "'" + parent.string() + "' is not a folder");
  CheckOutputFile(o.out, "--out");
  const PolicyRegistry registry = AllPolicies();
  const Scenario scenario =
      LoadScenario(o.scenario_path, o.overrides.ToOverrides(registry));
  // The world needs no policy, but a scenario `aia run` refuses is not
  // one to write a world from either.
  if (!registry.Has(scenario.policy.name))
    throw scenario.ErrorAt("policy.name",
                           registry.UnknownPolicy(scenario.policy.name));
  CheckNotAnInput(o.out, "--out", MissionInputs(scenario, nullptr));
  const std::shared_ptr<const Instance> instance = BuildInstance(scenario);
  ReportWarnings(scenario);
  const World& world = instance->world;
  // An unwritable folder is bad input (exit 2); a write that fails then (a
  // full disk) is an I/O error (exit 1), as for every command.
  MakeOutputDir(parent.string(), "--out");
  WriteFileAtomic(o.out, MakeMjcf(world, scenario));
  std::printf(
      "wrote %s: %d robots, %d targets, %zu obstacle boxes (seed %llu); "
      "open it with: mujoco-simulate %s\n",
      o.out.c_str(), world.NumRobots(), world.NumTargets(),
      world.map.obstacles().size(),
      static_cast<unsigned long long>(scenario.seed), o.out.c_str());
  return 0;
}

}  // namespace aia
