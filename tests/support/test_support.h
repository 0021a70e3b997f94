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

// A small tmpfs on a fresh folder, for full-disk tests: mounted when the
// tests run as root in a container that allows mounts (mounted() tells;
// skip the test otherwise); unmounted and removed when destroyed.
class SmallDisk {
 public:
  explicit SmallDisk(const std::string& size = "64k");
  ~SmallDisk();
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;
  bool mounted() const { return mounted_; }
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  bool mounted_ = false;
};

// Files that aia's writers leave when killed or failed: NAME.tmp.PID and
// .NAME.tmp.PID.EXT, anywhere under `dir`.
std::vector<std::string> Temporaries(const std::string& dir);

}  // namespace aia::testing

#endif  // AIA_TESTS_SUPPORT_TEST_SUPPORT_H_
