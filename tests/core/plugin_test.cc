#include "aia/core/plugin.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace aia {
namespace {

std::string LoadError(const std::string& path, const char* symbol) {
  try {
    LoadPluginTable(path, symbol, PluginHeader{1, 16}, "the tests");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(PluginTest, AMissingPluginIsOneLineNamingItsPurposeAndWhereItWasLooked) {
  const std::string why = LoadError("/nonexistent/libaia_nothing.so", "f");
  EXPECT_EQ(why.rfind("cannot load libaia_nothing.so (the tests; build it", 0),
            0u)
      << why;
  EXPECT_NE(why.find("/nonexistent/libaia_nothing.so: "), std::string::npos)
      << why;
  EXPECT_EQ(std::count(why.begin(), why.end(), '\n'), 0) << why;
}

// A shared object that loads but does not export the table's symbol (the C
// library's maths) is not taken for a plugin.
TEST(PluginTest, ALibraryWithoutTheTableIsNotThisBuildsPlugin) {
  const std::string why = LoadError("libm.so.6", "aia_no_such_table");
  EXPECT_NE(why.find("libm.so.6: not this build's plugin"), std::string::npos)
      << why;
}

}  // namespace
}  // namespace aia
