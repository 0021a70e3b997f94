// aia's command line: `aia run`, `aia eval`, ... (docs/design.md). A
// program of its own (docs/extending.md) adds its policies with
// RegisterPolicies (runtime/policies.h) and calls CliMain from main() to get
// every command with them.
#ifndef AIA_COMMANDS_CLI_H_
#define AIA_COMMANDS_CLI_H_

namespace aia {

// Parses the arguments, runs the command and returns the exit code: 0, 2
// for bad input (one `error:` line on stderr), 130 when interrupted, 1 for
// other failures.
int CliMain(int argc, char** argv);

}  // namespace aia

#endif  // AIA_COMMANDS_CLI_H_
