// libFuzzer: scenario YAML -> World -> MJCF, compiled by MuJoCo from memory.
// Scenarios larger than a small budget are skipped so that every input runs
// in milliseconds; an InputError is expected, MuJoCo must accept every MJCF
// aia writes.
#include <mujoco/mujoco.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "aia/core/error.h"
#include "aia/scenario/loader.h"
#include "aia/world/mjcf.h"
#include "aia/world/world.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const aia::Scenario s =
        aia::ParseScenario(text, "fuzz.yaml", AIA_FUZZ_BASE_DIR);
    const aia::Vec2& ws = s.workspace.size;
    if (s.robots.count > 20 || s.NumTargets() > 20 ||
        ws.x() * ws.y() / (s.robots.step * s.robots.step) > 1e4 ||
        ws.x() * ws.y() / (s.workspace.cell * s.workspace.cell) > 1e6 ||
        (s.workspace.obstacles.random &&
         s.workspace.obstacles.random->count > 50) ||
        s.workspace.obstacles.boxes.size() > 50)
      return 0;
    const aia::World world = aia::World::Build(s);
    const std::string xml = aia::MakeMjcf(world, s);
    mjVFS vfs;
    mj_defaultVFS(&vfs);
    if (mj_makeEmptyFileVFS(&vfs, "world.xml", static_cast<int>(xml.size())) !=
        0)
      __builtin_trap();
    std::memcpy(vfs.filedata[vfs.nfile - 1], xml.data(), xml.size());
    char error[1000] = "";
    mjModel* model = mj_loadXML("world.xml", &vfs, error, sizeof(error));
    mj_deleteVFS(&vfs);
    if (model == nullptr) {
      std::fprintf(stderr, "MuJoCo rejects aia's MJCF: %s\n", error);
      __builtin_trap();
    }
    mj_deleteModel(model);
  } catch (const aia::InputError&) {
  }
  return 0;
}
