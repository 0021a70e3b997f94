#include "aia/core/check.h"

#include <cstdio>
#include <cstdlib>

namespace aia::internal {

void CheckFailed(const char* expr, const char* file, int line,
                 const char* msg) {
  std::fprintf(stderr, "aia: internal check failed: %s at %s:%d%s%s\n", expr,
               file, line, msg[0] ? ": " : "", msg);
  std::abort();
}

}  // namespace aia::internal
