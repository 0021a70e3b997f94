// Plugins of this build: shared objects loaded at their first use, so that a
// process which never needs what they link (libtorch, OpenCV's codecs) does
// not pay for loading it (half a second of every short run). A plugin
// exports one symbol, a function returning its table of plain functions; the
// table starts with a PluginHeader, checked against the caller's. Only the
// table and the plain values it passes cross: each side keeps its own copy
// of what it links statically, and no virtual call or RTTI is shared.
#ifndef AIA_CORE_PLUGIN_H_
#define AIA_CORE_PLUGIN_H_

#include <cstddef>
#include <string>

namespace aia {

struct PluginHeader {
  int version = 0;       // the table's version (bumped when it changes)
  std::size_t size = 0;  // sizeof the table
};

// Loads the plugin (`built_path`, where the build wrote it, else the file of
// that name beside the running program; an installed aia's own plugin,
// InstalledLibDir(), before either) and returns its table, the result
// of its `symbol`. A missing plugin, or one of another version or table
// size, is a std::runtime_error on one line that says `what` the plugin is
// for and names each place tried. Not cached: callers keep the table (a
// function-local static).
const void* LoadPluginTable(const std::string& built_path, const char* symbol,
                            const PluginHeader& expected,
                            const std::string& what);

// The running program's folder with a trailing '/', or "" (for files
// installed beside it: PREFIX/bin/../lib/aia, PREFIX/bin/../share/aia).
std::string ExecutableDir();

// An installed aia's folders (PREFIX/lib/aia/ and PREFIX/share/aia/, with
// a trailing '/'), so that it loads its own plugins and models even while
// the build tree it was installed from still exists. A program installed as
// PREFIX/bin/ finds them by itself (PREFIX/lib/aia/ beside it); code that
// runs inside another program (the Python package's module) says where they
// are with SetInstalledDirs, once, before anything is loaded.
void SetInstalledDirs(const std::string& lib_dir, const std::string& data_dir);
// "" when this aia is not an installed one (it runs from its build tree).
std::string InstalledLibDir();
std::string InstalledDataDir();

}  // namespace aia

#endif  // AIA_CORE_PLUGIN_H_
