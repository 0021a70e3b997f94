// Content hashes: what a result was made from (a learned model's file), so
// that repeating it can tell when that file has changed since.
#ifndef AIA_CORE_HASH_H_
#define AIA_CORE_HASH_H_

#include <string>
#include <string_view>

namespace aia {

// SHA-256 (FIPS 180-4) of `bytes` as 64 lower-case hexadecimal digits, the
// same text as `sha256sum` prints.
std::string Sha256Hex(std::string_view bytes);

// Whether `text` looks like Sha256Hex's output (64 lower-case hex digits).
bool IsSha256Hex(std::string_view text);

// A file by its path and its content.
struct FileIdentity {
  std::string path;    // absolute
  std::string sha256;  // Sha256Hex of its bytes
};

}  // namespace aia

#endif  // AIA_CORE_HASH_H_
