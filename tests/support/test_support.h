// Helpers shared by the tests.
#ifndef AIA_TESTS_SUPPORT_TEST_SUPPORT_H_
#define AIA_TESTS_SUPPORT_TEST_SUPPORT_H_

#include <string>
#include <vector>

#include "aia/scenario/config.h"

namespace aia::testing {

// Absolute path of a file in the source tree, e.g.
// SourcePath("scenarios/default.yaml").
std::string SourcePath(const std::string& relative);

// Parses a scenario given as YAML text (errors name `name`).
Scenario ScenarioFromYaml(const std::string& yaml,
                          const std::string& name = "test.yaml");

// A fresh empty directory under the system temp dir.
std::string MakeTempDir(const std::string& prefix);

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};
// Runs build/aia with the given arguments.
CommandResult RunAia(const std::vector<std::string>& args);
// Runs a shell command line.
CommandResult RunCommand(const std::string& command_line);

std::string ReadFile(const std::string& path);

}  // namespace aia::testing

#endif  // AIA_TESTS_SUPPORT_TEST_SUPPORT_H_
