// CSV rows declared once (core/csv.h): the header, the writer and the reader
// walk one list of columns.
#include "aia/core/csv.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

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

}  // namespace
}  // namespace aia
