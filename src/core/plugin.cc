#include "aia/core/plugin.h"

#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace aia {
namespace {

std::string FileName(const std::string& path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool IsDir(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string WithSlash(std::string dir) {
  if (!dir.empty() && dir.back() != '/') dir += '/';
  return dir;
}

struct InstalledDirs {
  std::mutex mu;
  bool set = false;
  std::string lib, data;
};

InstalledDirs& Installed() {
  static InstalledDirs dirs;
  return dirs;
}

// An installed aia's own plugin first; then the build's file, then beside
// the program, then where `cmake --install`
// puts it relative to the program (PREFIX/bin/aia, PREFIX/lib/aia/), then
// the bare name, which the dynamic loader looks up along the program's
// RUNPATH (find_package(aia) adds PREFIX/lib/aia to it) and
// LD_LIBRARY_PATH.
std::vector<std::string> Candidates(const std::string& built_path) {
  std::vector<std::string> paths;
  const std::string installed = InstalledLibDir();
  if (!installed.empty()) paths.push_back(installed + FileName(built_path));
  paths.push_back(built_path);
  const std::string dir = ExecutableDir();
  if (!dir.empty()) {
    for (const std::string& p : {dir + FileName(built_path),
                                 dir + "../lib/aia/" + FileName(built_path)})
      if (p != built_path && p != paths.front()) paths.push_back(p);
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

void SetInstalledDirs(const std::string& lib_dir, const std::string& data_dir) {
  InstalledDirs& d = Installed();
  std::lock_guard<std::mutex> lock(d.mu);
  d.set = true;
  d.lib = WithSlash(lib_dir);
  d.data = WithSlash(data_dir);
}

namespace {

// The folder set by SetInstalledDirs, else `relative` beside the executable
// when it runs from an installed prefix (../lib/aia exists), else "".
std::string InstalledDir(std::string InstalledDirs::*set_dir,
                         const char* relative) {
  InstalledDirs& d = Installed();
  {
    std::lock_guard<std::mutex> lock(d.mu);
    if (d.set) return d.*set_dir;
  }
  const std::string dir = ExecutableDir();
  return !dir.empty() && IsDir(dir + "../lib/aia") ? dir + relative : "";
}

}  // namespace

std::string InstalledLibDir() {
  return InstalledDir(&InstalledDirs::lib, "../lib/aia/");
}

std::string InstalledDataDir() {
  return InstalledDir(&InstalledDirs::data, "../share/aia/");
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
