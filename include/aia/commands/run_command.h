// `aia run` (docs/scenarios.md): one mission with the standard result files.
#ifndef AIA_COMMANDS_RUN_COMMAND_H_
#define AIA_COMMANDS_RUN_COMMAND_H_

#include <string>

#include "aia/core/fields.h"
#include "aia/runtime/mission.h"

namespace aia {

struct RunOptions {
  std::string scenario_path;
  CommandOverrides overrides;
  std::string out_dir;  // empty: renders/<scenario file stem>
  bool progress = true;
  TraceMode trace = TraceMode::kAuto;

  // `aia run`'s own flags, declared once.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(trace).Doc(
        "trace.csv per step and target: full (every robot's det Sigma), min "
        "(the team's min_det only) or auto (full up to 100 robots)"));
  }
};

// `aia run`: runs the mission, writes the result files under DIR/ and prints
// a one-line result. Throws InputError for bad input.
MissionSummary RunMission(const RunOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_RUN_COMMAND_H_
