// build/aia: the command line (commands/cli.h).
#include "aia/commands/cli.h"
#include "aia/learning/network.h"

// jemalloc (linked into build/aia) keeps freed pages instead of returning
// them to the kernel on every libtorch call, which halves libtorch's speed
// on glibc's allocator (docs/learning.md, Network).
extern "C" {
const char* malloc_conf = "dirty_decay_ms:-1,muzzy_decay_ms:-1";
}

int main(int argc, char** argv) {
  aia::PreferShortOpenMpSpin();  // before any thread: no setenv later
  return aia::CliMain(argc, argv);
}
