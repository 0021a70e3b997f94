#include "aia/runtime/outputs.h"

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <new>

#include "aia/core/error.h"
#include "aia/core/io.h"

namespace aia {

void LockOutput(const std::string& path, const std::string& flag) {
  // Held until the process ends (the kernel releases it on any exit); a
  // path this process holds already is not locked again.
  static std::mutex mu;
  static std::map<std::string, std::unique_ptr<FileLock>> held;
  std::error_code ec;
  std::string key = std::filesystem::weakly_canonical(path, ec).string();
  if (ec) key = path;
  const std::lock_guard<std::mutex> guard(mu);
  if (held.count(key)) return;
  try {
    held.emplace(key, std::make_unique<FileLock>(path));
  } catch (const std::runtime_error& e) {
    throw InputError::Flag(flag, e.what());
  }
}

void CheckOutputFile(const std::string& path, const std::string& flag) {
  try {
    CheckReplaceableFile(path);
  } catch (const std::runtime_error& e) {
    throw InputError::Flag(flag, e.what());
  }
  if (std::string longer = TemporaryNameProblem(path); !longer.empty())
    throw InputError::Flag(flag, longer);
}

void CheckOutputFiles(const std::vector<std::string>& paths,
                      const std::string& flag, const std::string& written) {
  for (const std::string& path : paths) {
    const std::string why = OutputFileProblem(path, written);
    if (!why.empty()) throw InputError::Flag(flag, why);
  }
}

void MakeOutputDir(const std::string& dir, const std::string& flag, bool lock) {
  if (dir.empty()) return;
  // An output folder that is a FIFO, device or file: say what it is.
  if (const std::string kind = NonRegularKind(dir);
      !kind.empty() && kind != "a folder")
    throw InputError::Flag(flag, "'" + dir + "' is " + kind + ", not a folder");
  try {
    MakeDirs(dir);
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is not bad input (cli.cc says it)
  } catch (const std::exception& e) {
    throw InputError::Flag(flag, e.what());
  }
  if (const std::string why = UnwritableDirProblem(dir); !why.empty())
    throw InputError::Flag(flag, why);
  if (!lock) return;
  LockOutput(dir, flag);
  RemoveStaleTemporaries(dir);
}

}  // namespace aia
