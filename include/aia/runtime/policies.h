// The registry of every policy aia knows, for the commands.
#ifndef AIA_RUNTIME_POLICIES_H_
#define AIA_RUNTIME_POLICIES_H_

#include "aia/planning/registry.h"

namespace aia {

// planning's built-ins (random, greedy, expert, decsb), the learned ones
// (igbnet), then those added by RegisterPolicies, in the order added.
PolicyRegistry AllPolicies();

// The extension point for policies outside aia (docs/extending.md): a
// program that links aia calls this before it runs a command (say
// CliMain), and every command's registry (`aia policies`, eval, run, ...)
// has the policies `add` puts in. Not static self-registration: the program
// says what it adds.
using PolicyAdder = void (*)(PolicyRegistry* registry);
void RegisterPolicies(PolicyAdder add);

}  // namespace aia

#endif  // AIA_RUNTIME_POLICIES_H_
