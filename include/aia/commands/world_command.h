// `aia world`: a scenario's generated world as one MJCF file (obstacles,
// robots at their starts, targets at their true initial positions), to open
// in MuJoCo's own viewer (mujoco-simulate) or load with Python's `mujoco`.
#ifndef AIA_COMMANDS_WORLD_COMMAND_H_
#define AIA_COMMANDS_WORLD_COMMAND_H_

#include <string>

#include "aia/runtime/mission.h"

namespace aia {

struct WorldOptions {
  std::string scenario_path;
  CommandOverrides overrides;  // --seed and --set
  std::string out;             // the MJCF file
};

// Builds the world (the model is compiled once by MuJoCo, so a file that is
// written also loads) and writes it atomically. InputError on bad input.
int RunWorldCommand(const WorldOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_WORLD_COMMAND_H_
