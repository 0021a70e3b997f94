#include "support/test_support.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "aia/scenario/loader.h"

namespace aia::testing {

std::string SourcePath(const std::string& relative) {
  return std::string(AIA_SOURCE_DIR) + "/" + relative;
}

Scenario ScenarioFromYaml(const std::string& yaml, const std::string& name) {
  return ParseScenario(yaml, name, std::filesystem::current_path().string());
}

std::string MakeTempDir(const std::string& prefix) {
  std::string templ =
      (std::filesystem::temp_directory_path() / (prefix + "XXXXXX")).string();
  char* dir = mkdtemp(templ.data());
  if (dir == nullptr) std::abort();
  return dir;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

namespace {
std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}
}  // namespace

CommandResult RunCommand(const std::string& command_line) {
  const std::string dir = MakeTempDir("aia_cmd_");
  const std::string out_path = dir + "/out", err_path = dir + "/err";
  const std::string full =
      command_line + " >" + out_path + " 2>" + err_path + " </dev/null";
  const int status = std::system(full.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadFile(out_path);
  r.err = ReadFile(err_path);
  std::filesystem::remove_all(dir);
  return r;
}

SmallDisk::SmallDisk(const std::string& size) : dir_(MakeTempDir("aia_full_")) {
  mounted_ =
      RunCommand("mount -t tmpfs -o size=" + size + " tmpfs " + Quote(dir_))
          .exit_code == 0;
}

SmallDisk::~SmallDisk() {
  if (mounted_) RunCommand("umount " + Quote(dir_));
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

std::vector<std::string> Temporaries(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (std::filesystem::recursive_directory_iterator it(dir, ec), end;
       !ec && it != end; it.increment(ec))
    if (it->path().filename().string().find(".tmp.") != std::string::npos)
      out.push_back(it->path().string());
  return out;
}

CommandResult RunAia(const std::vector<std::string>& args) {
  std::string cmd = Quote(AIA_BINARY);
  for (const auto& a : args) cmd += " " + Quote(a);
  return RunCommand(cmd);
}

}  // namespace aia::testing
