// The registry of every policy aia knows, for the commands.
#ifndef AIA_RUNTIME_POLICIES_H_
#define AIA_RUNTIME_POLICIES_H_

#include "aia/planning/registry.h"

namespace aia {

// planning's built-ins (random, greedy, expert, decsb) plus the learned
// ones (igbnet).
PolicyRegistry AllPolicies();

}  // namespace aia

#endif  // AIA_RUNTIME_POLICIES_H_
