#include "aia/core/plugin.h"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <stdexcept>
#include <vector>

namespace aia {
namespace {

std::string FileName(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The build's file, then beside the program, then where `cmake --install`
// puts it relative to the program (PREFIX/bin/aia, PREFIX/lib/aia/), then
// the bare name, which the dynamic loader looks up along the program's
// RUNPATH (find_package(aia) adds PREFIX/lib/aia to it) and
// LD_LIBRARY_PATH.
std::vector<std::string> Candidates(const std::string& built_path) {
  std::vector<std::string> paths = {built_path};
  const std::string dir = ExecutableDir();
  if (!dir.empty()) {
    for (const std::string& p : {dir + FileName(built_path),
                                 dir + "../lib/aia/" + FileName(built_path)})
      if (p != built_path) paths.push_back(p);
  }
  paths.push_back(FileName(built_path));
  return paths;
}

}  // namespace

std::string ExecutableDir() {
  char exe[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) return "";
  std::string dir(exe, static_cast<std::size_t>(n));
  dir.resize(dir.rfind('/') + 1);
  return dir;
}

const void* LoadPluginTable(const std::string& built_path, const char* symbol,
                            const PluginHeader& expected,
                            const std::string& what) {
  std::string tried;
  for (const std::string& path : Candidates(built_path)) {
    // RTLD_LOCAL: the plugin's symbols and its libraries' stay out of the
    // process's global scope.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = dlerror();
      tried += "; " + path + ": " + (why ? why : "cannot be loaded");
      continue;
    }
    using Entry = const void* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, symbol));
    const void* table = entry ? entry() : nullptr;
    const auto* header = static_cast<const PluginHeader*>(table);
    if (!header || header->version != expected.version ||
        header->size != expected.size) {
      tried += "; " + path +
               ": not this build's plugin (rebuild: cmake --build build)";
      continue;
    }
    return table;
  }
  throw std::runtime_error("cannot load " + FileName(built_path) + " (" + what +
                           "; build it with `cmake --build build`)" + tried);
}

}  // namespace aia
