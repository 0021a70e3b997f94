// Every file in tests/data/bad/ is a scenario with one problem, announced by
// its first line:
//   # expect: LINE: KEY: SUBSTRING
// LoadScenario must reject it with an InputError at that line (0: none) and
// key, whose message contains SUBSTRING.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/scenario/loader.h"
#include "support/test_support.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> BadFiles() {
  std::vector<std::string> files;
  for (const auto& entry :
       fs::directory_iterator(testing::SourcePath("tests/data/bad"))) {
    if (entry.path().extension() == ".yaml")
      files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

struct Expectation {
  int line = -1;
  std::string key;
  std::string substring;
};

bool ReadExpectation(const std::string& path, Expectation* out) {
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  static const std::regex kHeader(R"(# expect: (\d+): ([^:]+): (.+))");
  std::smatch m;
  if (!std::regex_match(first, m, kHeader)) return false;
  out->line = std::stoi(m[1]);
  out->key = m[2];
  out->substring = m[3];
  return true;
}

class BadScenarioTest : public ::testing::TestWithParam<std::string> {};

TEST_P(BadScenarioTest, IsRejectedWithTheExpectedError) {
  const std::string& path = GetParam();
  Expectation expect;
  ASSERT_TRUE(ReadExpectation(path, &expect))
      << path << ": first line must be `# expect: LINE: KEY: SUBSTRING`";
  try {
    LoadScenario(path);
    FAIL() << path << ": loaded without error";
  } catch (const InputError& e) {
    SCOPED_TRACE(e.Format());
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), expect.line);
    EXPECT_EQ(e.key(), expect.key);
    EXPECT_NE(e.message().find(expect.substring), std::string::npos)
        << "message lacks \"" << expect.substring << "\"";
  }
}

std::string TestName(const ::testing::TestParamInfo<std::string>& info) {
  std::string name = fs::path(info.param).stem().string();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadScenarioTest,
                         ::testing::ValuesIn(BadFiles()), TestName);

TEST(BadScenarioCorpus, HoldsEnoughFiles) { EXPECT_GE(BadFiles().size(), 60u); }

}  // namespace
}  // namespace aia
