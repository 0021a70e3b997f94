// Compiled into every program that links aia through find_package(aia)
// (aiaConfig.cmake adds it to aia::core's interface): it tells the
// libraries, before main, where this installation keeps its plugins and
// models, so that such a program loads the installed ones and not those of
// the build tree it was installed from (nor fails when that tree is gone),
// as the installed `aia` and the Python package do.
#include "aia/core/plugin.h"

namespace {

const bool kInstalledDirsSet =
    (aia::SetInstalledDirs(AIA_INSTALLED_LIB_DIR, AIA_INSTALLED_DATA_DIR),
     true);

}  // namespace
