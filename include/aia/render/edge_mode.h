// Which communication edges a frame draws (`aia render --edges`): its own
// header, without OpenCV, so that commands/render_mission.h can declare the
// flag.
#ifndef AIA_RENDER_EDGE_MODE_H_
#define AIA_RENDER_EDGE_MODE_H_

#include <array>

#include "aia/core/fields.h"

namespace aia {

enum class EdgeMode {
  kAuto,  // lost messages; delivered ones while they stay readable
  kAll,   // every pair that exchanged a message, and the lost messages
  kLost,  // the lost messages only
  kNone,  // no edges
};
constexpr std::array<EnumName<EdgeMode>, 4> EnumNames(EdgeMode) {
  return {{{EdgeMode::kAuto, "auto"},
           {EdgeMode::kAll, "all"},
           {EdgeMode::kLost, "lost"},
           {EdgeMode::kNone, "none"}}};
}

}  // namespace aia

#endif  // AIA_RENDER_EDGE_MODE_H_
