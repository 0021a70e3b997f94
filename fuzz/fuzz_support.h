// Shared by the libFuzzer harnesses: input bytes as a temporary file for
// readers that take paths, and the one rule every harness checks: bad input
// is an aia::InputError (or a documented std::invalid_argument), anything
// else escaping is a bug.
#ifndef AIA_FUZZ_FUZZ_SUPPORT_H_
#define AIA_FUZZ_FUZZ_SUPPORT_H_

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace aia::fuzz {

// A file holding the bytes, removed when it goes out of scope.
class TempFile {
 public:
  TempFile(const std::uint8_t* data, std::size_t size,
           const std::string& suffix) {
    const char* dir = std::getenv("TMPDIR");
    path_ = std::string(dir ? dir : "/tmp") + "/aia_fuzz_" +
            std::to_string(::getpid()) + suffix;
    std::FILE* f = std::fopen(path_.c_str(), "wb");
    if (f == nullptr) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
  }
  ~TempFile() { std::remove(path_.c_str()); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace aia::fuzz

#endif  // AIA_FUZZ_FUZZ_SUPPORT_H_
