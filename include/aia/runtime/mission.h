// One mission from a scenario file to result files, shared by `aia run` and
// `aia render` (which adds its video observer to the same loop):
//   PREFIX summary.json     the outcome (unchanged format, see README)
//   PREFIX trace.csv        det Sigma per step, target and robot
//   PREFIX estimate.csv     the best estimate's error and NEES per step
//   PREFIX effective.yaml   the scenario as run: every key, defaults filled in,
//                           overrides and the policy's parameters applied
//   PREFIX diagnostics.json policy statuses, physics timeouts, RMSE and NEES,
//                           wall time per phase
// with PREFIX "DIR/" for `aia run` and "DIR/STEM." for `aia render`.
#ifndef AIA_RUNTIME_MISSION_H_
#define AIA_RUNTIME_MISSION_H_

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aia/core/fields.h"
#include "aia/core/io.h"
#include "aia/planning/registry.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/observers.h"
#include "aia/runtime/outputs.h"
#include "aia/runtime/policies.h"
#include "aia/scenario/loader.h"

namespace aia {

// The scenario flags of the mission commands, in the order they apply:
// --policy, --seed, --max-steps, then each --set.
struct CommandOverrides {
  std::optional<std::string> policy;
  std::optional<std::uint64_t> seed;
  std::optional<int> max_steps;
  // Flags that set a scenario key, as given on the command line (e.g.
  // {"--seed", "seed", "12"}): read by the scenario's reader, so an error is
  // the key's, naming the flag. Applied after the three above.
  std::vector<Override> flags;
  // "key.path=value", applied last; a key one of the flags above gives is
  // refused (InputError naming both).
  std::vector<std::string> sets;

  // As scenario overrides; InputError (naming the flag) for an unknown
  // policy or a malformed --set.
  std::vector<Override> ToOverrides(const PolicyRegistry& registry) const;
};

// An episode of a scenario with its policy from the registry (a convenience
// for tests and tools; commands share instances and resolved policies).
std::unique_ptr<Episode> MakeEpisode(const Scenario& scenario,
                                     const PolicyRegistry& registry);

// A mission ready to run: the scenario as overridden, its policy resolved
// (parameters checked, resources loaded) and its instance built.
struct PreparedMission {
  Scenario scenario;
  std::shared_ptr<const PolicySpec> policy;
  std::shared_ptr<const Instance> instance;
  std::chrono::steady_clock::time_point started;
};
// `scenario` is modified by nothing after this; InputError for bad input.
PreparedMission PrepareMission(Scenario scenario,
                               const PolicyRegistry& registry);

// The scenario with the resolved policy's parameters written in full, and a
// learned policy's model file by absolute path and SHA-256.
Scenario EffectiveScenario(const PreparedMission& mission);

// The files a mission reads: the scenario file, its map image and a learned
// policy's model. No output of a command may be one of them
// (CheckNotAnInput).
std::vector<InputFile> MissionInputs(const Scenario& scenario,
                                     const PolicySpec* policy);

// The names of the files MissionRunner writes under its prefix.
std::vector<std::string> MissionFileNames();

// The outcome of a finished episode.
struct MissionSummary {
  std::string scenario;
  std::string policy;
  std::uint64_t seed = 0;
  int robots = 0;
  int targets = 0;
  bool success = false;
  int flowtime = -1;  // -1: not reached
  int steps = 0;
  long invalid_moves = 0;
  double localized_share =
      0.0;  // share of steps (0..steps) with every target localized
  double wall_s = 0.0;
};
MissionSummary Summarize(const Episode& episode, double wall_s);
// summary.json's text.
std::string SummaryJson(const MissionSummary& summary, const Episode& episode);
// diagnostics.json's text: policy statuses and counters, physics, moves
// (`moves` watched the episode), the estimate's errors (`estimate` did) and
// wall times (`wall_s` the whole mission's).
std::string DiagnosticsJson(const Episode& episode, const MoveObserver& moves,
                            const EstimateObserver& estimate, double wall_s);

// What trace.csv holds per step and target: the team's min_det, and with
// kFull every robot's det Sigma (N x M numbers a step); kAuto is kFull up to
// kTraceFullRobots robots, kMin beyond (a 1000 x 1000 mission would write
// 12 MB a step).
enum class TraceMode { kAuto, kFull, kMin };
constexpr std::array<EnumName<TraceMode>, 3> EnumNames(TraceMode) {
  return {{{TraceMode::kAuto, "auto"},
           {TraceMode::kFull, "full"},
           {TraceMode::kMin, "min"}}};
}
inline constexpr int kTraceFullRobots = 100;
bool TraceHasRobotColumns(TraceMode mode, int num_robots);

// Runs a prepared mission with the standard observers (trace, estimate,
// progress) and any added ones, then writes the result files but
// summary.json (the caller's, which may add to it) under `prefix`.
class MissionRunner {
 public:
  MissionRunner(const PreparedMission& mission, std::string prefix,
                std::string label, bool progress,
                std::function<std::string()> progress_extra = {},
                TraceMode trace = TraceMode::kAuto);
  ~MissionRunner();

  Episode& episode() { return *episode_; }
  void AddObserver(StepObserver* observer) { episode_->AddObserver(observer); }
  // Runs to the end and writes trace.csv, estimate.csv, effective.yaml and
  // diagnostics.json; returns the summary.
  MissionSummary Run();

 private:
  const PreparedMission& mission_;
  std::string prefix_;
  std::unique_ptr<Episode> episode_;
  std::unique_ptr<TraceObserver> trace_;
  std::unique_ptr<EstimateObserver> estimate_;
  std::unique_ptr<ProgressObserver> progress_;
  std::unique_ptr<MoveObserver> moves_;
};

}  // namespace aia

#endif  // AIA_RUNTIME_MISSION_H_
