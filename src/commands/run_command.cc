#include "aia/commands/run_command.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "aia/core/io.h"
#include "aia/runtime/outputs.h"
#include "aia/scenario/loader.h"

namespace aia {
namespace {

// renders/NAME for a run without --out: the scenario file's stem, unless it
// would name another folder ("..yaml", "...yaml") or hold a character that
// makes a poor folder name (a control character, a '/'): then "scenario".
std::string DefaultOutName(const std::string& scenario_path) {
  const std::string stem = std::filesystem::path(scenario_path).stem().string();
  bool plain = !stem.empty() && stem != "." && stem != "..";
  for (const char c : stem)
    plain =
        plain && static_cast<unsigned char>(c) >= 0x20 && c != 0x7f && c != '/';
  return plain ? stem : "scenario";
}

}  // namespace

MissionSummary RunMission(const RunOptions& options) {
  const PolicyRegistry registry = AllPolicies();
  PreparedMission mission =
      PrepareMission(LoadScenario(options.scenario_path,
                                  options.overrides.ToOverrides(registry)),
                     registry);
  std::string out = options.out_dir;
  if (out.empty()) out = "renders/" + DefaultOutName(options.scenario_path);
  // The folder may hold the scenario itself (DIR/effective.yaml of an
  // earlier run): none of the files written may be an input.
  const std::vector<InputFile> inputs =
      MissionInputs(mission.scenario, mission.policy.get());
  std::vector<std::string> files;
  for (const std::string& name : MissionFileNames()) {
    files.push_back(out + "/" + name);
    CheckNotAnInput(files.back(), "--out", inputs,
                    "written into the output folder");
  }
  CheckOutputFiles(files, "--out", "written into the output folder");
  MakeOutputDir(out, "--out", /*lock=*/true);

  MissionRunner runner(mission, out + "/", "aia run", options.progress, {},
                       options.trace);
  const MissionSummary summary = runner.Run();
  WriteFileAtomic(out + "/summary.json",
                  SummaryJson(summary, runner.episode()));
  std::printf(
      "%s: policy %s, seed %llu: %s in %d steps (%d robots, %d targets, %ld "
      "invalid moves), %.2f s -> %s/\n",
      mission.scenario.name.c_str(), summary.policy.c_str(),
      static_cast<unsigned long long>(summary.seed),
      summary.success ? "success" : "no success",
      summary.success ? summary.flowtime : summary.steps, summary.robots,
      summary.targets, summary.invalid_moves, summary.wall_s, out.c_str());
  return summary;
}

}  // namespace aia
