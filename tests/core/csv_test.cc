// CSV rows declared once (core/csv.h): the header, the writer and the reader
// walk one list of columns.
#include "aia/core/csv.h"

#include <gtest/gtest.h>
#include <locale.h>
#include <stdlib.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include "support/test_support.h"

namespace aia {
namespace {

struct Row {
  std::string name;
  std::uint64_t seed = 0;
  bool ok = false;
  int steps = -1;
  double share = 0.0;
  double exact = 0.0;
  template <typename C>
  void Columns(C* c) {
    c->Column("name", &name);
    c->Column("seed", &seed);
    c->Column("ok", &ok);
    c->Column("steps", &steps, CsvFormat::EmptyIs(-1));
    c->Column("share", &share, CsvFormat::Fixed(4));
    c->Column("exact", &exact);
  }
};

TEST(CsvTest, HeaderAndRowComeFromOneDeclarationAndRoundTrip) {
  EXPECT_EQ(CsvHeader<Row>(), "name,seed,ok,steps,share,exact");
  Row r{"greedy", 18446744073709551615ull, true, 12, 0.123456, 0.1};
  EXPECT_EQ(CsvLine(r), "greedy,18446744073709551615,1,12,0.1235,0.1\n");
  Row back;
  ASSERT_TRUE(
      ParseCsvLine("greedy,18446744073709551615,1,12,0.1235,0.1", &back));
  EXPECT_EQ(back.name, "greedy");
  EXPECT_EQ(back.seed, 18446744073709551615ull);
  EXPECT_TRUE(back.ok);
  EXPECT_EQ(back.steps, 12);
  EXPECT_EQ(back.share, 0.1235);
  EXPECT_EQ(back.exact, 0.1);
  // The empty cell stands for -1, both ways.
  r.steps = -1;
  EXPECT_EQ(CsvLine(r), "greedy,18446744073709551615,1,,0.1235,0.1\n");
  ASSERT_TRUE(ParseCsvLine("a,1,0,,0,0", &back));
  EXPECT_EQ(back.steps, -1);
}

TEST(CsvTest, OnlyWholeCellsOfTheRightCountAreARow) {
  Row r;
  EXPECT_FALSE(ParseCsvLine("a,1,0,3,0", &r));        // a cell short
  EXPECT_FALSE(ParseCsvLine("a,1,0,3,0,0,7", &r));    // one too many
  EXPECT_FALSE(ParseCsvLine("a,1,0,12abc,0,0", &r));  // not a whole number
  EXPECT_FALSE(ParseCsvLine("a,-1,0,3,0,0", &r));     // a negative seed
  EXPECT_FALSE(ParseCsvLine("a,18446744073709551616,0,3,0,0", &r));  // > 2^64
  EXPECT_FALSE(ParseCsvLine("a,1,2,3,0,0", &r));     // not 0 or 1
  EXPECT_FALSE(ParseCsvLine(",1,0,3,0,0", &r));      // an empty name
  EXPECT_FALSE(ParseCsvLine("a,1,0,3, 0.5,0", &r));  // a space
  EXPECT_FALSE(ParseCsvLine("a,1,0,3,0.5x,0", &r));
  EXPECT_FALSE(ParseCsvLine("a,1,0,3,0,", &r));  // an empty real
  EXPECT_TRUE(ParseCsvLine("a,1,0,-3,0.5,1e-3", &r));
  EXPECT_EQ(r.steps, -3);
  EXPECT_EQ(r.exact, 1e-3);
}

// Reals are written with printf's digits in the C locale (std::to_chars,
// which no LC_NUMERIC changes) and read back as strtod reads them.
TEST(CsvTest, RealsAreWrittenAsPrintfWritesThem) {
  using csv_internal::FormatReal;
  const double values[] = {0.0,
                           -0.0,
                           0.1,
                           1.0 / 3,
                           -2.5,
                           0.125,
                           1e-7,
                           123456789.987654321,
                           1e21,
                           1e300,
                           -4.9e-324,
                           0.95,
                           2.675,
                           1e15 + 0.3,
                           std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::quiet_NaN()};
  char want[400];
  for (const double v : values) {
    for (int digits = 0; digits <= 6; ++digits) {
      std::snprintf(want, sizeof want, "%.*f", digits, v);
      EXPECT_EQ(FormatReal(v, CsvFormat::Fixed(digits), false), want)
          << v << " " << digits;
    }
    for (int significant = 1; significant <= 17; ++significant) {
      std::snprintf(want, sizeof want, "%.*g", significant, v);
      EXPECT_EQ(FormatReal(v, CsvFormat::Significant(significant), false), want)
          << v << " " << significant;
    }
  }
  using csv_internal::ParseReal;
  EXPECT_EQ(ParseReal("+1.5"), 1.5);  // strtod's sign
  EXPECT_EQ(ParseReal("-0.25"), -0.25);
  EXPECT_EQ(ParseReal("1e999"), std::numeric_limits<double>::infinity());
  EXPECT_EQ(ParseReal("-1e999"), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(ParseReal("1e-400"), 0.0);
  EXPECT_TRUE(std::isnan(ParseReal("nan").value_or(0.0)));
  for (const char* bad : {"", "+", "+-1", "++1", " 1", "1 ", "1,5", "0x10"})
    EXPECT_FALSE(ParseReal(bad).has_value()) << "'" << bad << "'";
}

// A thread whose C library writes numbers with a comma (a Python program's
// other thread may set such a locale at any moment) writes and reads
// aia's CSV numbers with a point: the rows written under it failed their
// own check and ended aia.evaluate. The locale is made from this machine's
// locale sources (Debian's `locales`); without them the test is skipped.
TEST(CsvTest, RealsKeepTheirPointWhereTheLocaleHasAComma) {
  const std::string dir = testing::MakeTempDir("aia_locale_");
  const int made = std::system(
      ("localedef -i de_DE -f UTF-8 " + dir + "/de_DE.UTF-8 >/dev/null 2>&1")
          .c_str());
  ::setenv("LOCPATH", dir.c_str(), 1);
  const locale_t comma =
      made == 0 ? ::newlocale(LC_NUMERIC_MASK, "de_DE.UTF-8", locale_t{})
                : locale_t{};
  ::unsetenv("LOCPATH");
  if (comma == locale_t{}) {
    std::filesystem::remove_all(dir);
    GTEST_SKIP() << "no de_DE locale could be made (localedef, locales)";
  }
  const locale_t before = ::uselocale(comma);
  char printed[16];
  std::snprintf(printed, sizeof printed, "%.1f", 1.5);
  Row r{"greedy", 7, true, 12, 0.123456, 0.1};
  const std::string line = CsvLine(r);
  Row back;
  const bool parsed = ParseCsvLine("a,1,0,3,0.5,2.25", &back);
  ::uselocale(before);
  ::freelocale(comma);
  std::filesystem::remove_all(dir);
  EXPECT_EQ(std::string(printed), "1,5");  // the locale writes a comma
  EXPECT_EQ(line, "greedy,7,1,12,0.1235,0.1\n");
  ASSERT_TRUE(parsed);
  EXPECT_EQ(back.share, 0.5);
  EXPECT_EQ(back.exact, 2.25);
}

}  // namespace
}  // namespace aia
