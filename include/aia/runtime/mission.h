// `aia run`: one mission from a scenario file to summary.json and trace.csv.
#ifndef AIA_RUNTIME_MISSION_H_
#define AIA_RUNTIME_MISSION_H_

#include <cstdint>
#include <optional>
#include <string>

#include "aia/planning/registry.h"
#include "aia/runtime/episode.h"
#include "aia/scenario/config.h"

namespace aia {

// Every policy aia knows (planning's built-ins plus the learned ones).
PolicyRegistry AllPolicies();

// Command-line overrides of a scenario. An unknown policy name is an
// InputError naming the flag and the valid names.
struct ScenarioOverrides {
  std::optional<std::string> policy;
  std::optional<std::uint64_t> seed;
  std::optional<int> max_steps;
};
void ApplyOverrides(const ScenarioOverrides& overrides,
                    const PolicyRegistry& registry, Scenario* scenario);

// Creates an output folder named by a flag; InputError (exit code 2) naming
// the flag when it cannot be created.
void MakeOutputDir(const std::string& dir, const std::string& flag);

// Builds the episode for a scenario with its policy from the registry.
std::unique_ptr<Episode> MakeEpisode(const Scenario& scenario,
                                     const PolicyRegistry& registry);

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
std::string SummaryJson(const MissionSummary& summary, const Episode& episode);

// Streams trace.csv: one row per step and target: step, target, min over
// active robots of det Sigma, and each robot's det Sigma.
class TraceWriter {
 public:
  explicit TraceWriter(const std::string& path, int num_robots);
  void Write(const Episode& episode);
  void Commit();

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

// A progress line on stderr, drawn only when stderr is a terminal.
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled);
  void Update(const std::string& text);
  void Finish();

 private:
  bool enabled_;
  size_t last_width_ = 0;
};

struct RunOptions {
  std::string scenario_path;
  ScenarioOverrides overrides;
  std::string out_dir;  // empty: renders/<scenario file stem>
  bool progress = true;
};

// Runs the mission, writes DIR/summary.json and DIR/trace.csv atomically and
// prints a one-line result. Throws InputError for bad input.
MissionSummary RunMission(const RunOptions& options);

}  // namespace aia

#endif  // AIA_RUNTIME_MISSION_H_
