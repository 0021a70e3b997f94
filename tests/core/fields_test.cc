// The field archives on a small struct: every kind of field read strictly,
// written back, documented and found by address.
#include <gtest/gtest.h>

#include <array>
#include <regex>
#include <string>
#include <vector>

#include "aia/core/field_io.h"
#include "aia/core/field_values.h"

namespace aia {
namespace {

enum class Shape { kRound, kSquare };
constexpr std::array<EnumName<Shape>, 2> EnumNames(Shape) {
  return {{{Shape::kRound, "round"}, {Shape::kSquare, "square"}}};
}

struct Inner {
  int count = 1;
  Vec2 at{0.0, 0.0};
  template <typename A>
  void Serialize(A* a) {
    a->Visit(AIA_FIELD(count).In(AtLeast(0)).Doc("how many"));
    a->Visit(AIA_FIELD(at).Doc("where"));
  }
};

struct Outer {
  double rate = 0.5;
  int who = -1;
  bool on = true;
  std::string label = "x";
  Shape shape = Shape::kRound;
  std::optional<Inner> extra;
  std::vector<Inner> items;
  Inner inner;
  int needed = 0;
  ConfigNode rest;
  int validated = 0;

  template <typename A>
  void Serialize(A* a) {
    a->Visit(AIA_FIELD(rate).In(kHalfOpenUnit).Doc("a rate"));
    a->Visit(AIA_FIELD(who).In(AtLeast(0)).Keyword("anyone", -1).Doc("who"));
    a->Visit(AIA_FIELD(on));
    a->Visit(AIA_FIELD(label));
    a->Visit(AIA_FIELD(shape));
    a->Visit(AIA_FIELD(extra));
    a->Visit(AIA_FIELD(items));
    a->Visit(AIA_FIELD(inner));
    a->Visit(AIA_FIELD(needed).Required("a number we need"));
    a->Visit(AIA_FIELD(rest).Rest());
  }
  void Validate(const FieldChecker& check) {
    ++validated;
    if (!items.empty() && items[0].count > inner.count)
      check.Fail(items[0].count, "must not exceed inner.count, got " +
                                     check.Shown(items[0].count));
  }
};

ConfigNode Scalar(const std::string& text, int line) {
  ConfigNode n = ConfigNode::Scalar(text);
  n.line = line;
  return n;
}

// {needed: 3, ...} with one key per line from line 1.
ConfigNode Doc(std::vector<std::pair<std::string, ConfigNode>> entries) {
  ConfigNode map = ConfigNode::Map();
  int line = 1;
  for (auto& [k, v] : entries) {
    if (v.line == 0) v.line = line;
    map.entries.push_back({k, line++, std::move(v)});
  }
  return map;
}

Outer Read(const ConfigNode& node) {
  Outer out;
  ReadOptions options;
  options.file = "f.yaml";
  ReadFields(node, options, "", &out);
  return out;
}

InputError ErrorOf(const ConfigNode& node) {
  try {
    Read(node);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return InputError("", 0, "", "");
}

TEST(FieldReaderTest, ReadsEveryKindOfField) {
  ConfigNode items = ConfigNode::List();
  items.items.push_back(Doc({{"count", Scalar("0", 0)}}));
  ConfigNode at = ConfigNode::List();
  at.items = {Scalar("1.5", 0), Scalar("-2", 0)};
  const Outer o =
      Read(Doc({{"rate", Scalar("1", 0)},
                {"who", Scalar("anyone", 0)},
                {"on", Scalar("false", 0)},
                {"label", ConfigNode::Scalar("5", ConfigNode::Style::kQuoted)},
                {"shape", Scalar("square", 0)},
                {"extra", ConfigNode{}},
                {"items", items},
                {"inner", Doc({{"at", at}})},
                {"needed", Scalar("3", 0)},
                {"colour", Scalar("red", 0)}}));
  EXPECT_EQ(o.rate, 1.0);
  EXPECT_EQ(o.who, -1);
  EXPECT_FALSE(o.on);
  EXPECT_EQ(o.label, "5");
  EXPECT_EQ(o.shape, Shape::kSquare);
  ASSERT_TRUE(o.extra.has_value());  // an empty value: all defaults
  EXPECT_EQ(o.extra->count, 1);
  ASSERT_EQ(o.items.size(), 1u);
  EXPECT_EQ(o.items[0].count, 0);
  EXPECT_EQ(o.inner.at, Vec2(1.5, -2.0));
  EXPECT_EQ(o.needed, 3);
  ASSERT_EQ(o.rest.entries.size(), 1u);  // unknown keys kept by Rest()
  EXPECT_EQ(o.rest.entries[0].key, "colour");
  EXPECT_EQ(o.validated, 1);
}

TEST(FieldReaderTest, ErrorsNameTheKeyLineAndWhatIsAllowed) {
  EXPECT_EQ(ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"rate", Scalar("0", 0)}}))
                .Format(),
            "f.yaml:2: rate: must be a number in (0, 1], got 0");
  EXPECT_EQ(ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"who", Scalar("-2", 0)}}))
                .message(),
            "must be an integer >= 0 or anyone, got -2");
  EXPECT_EQ(
      ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"shape", Scalar("oval", 0)}}))
          .message(),
      "must be round or square, got oval");
  EXPECT_EQ(ErrorOf(Doc({{"needed", ConfigNode::Scalar(
                                        "1", ConfigNode::Style::kQuoted)}}))
                .message(),
            "must be an integer, got \"1\"");
  EXPECT_EQ(ErrorOf(Doc({})).Format(),
            "f.yaml: needed: is required: a number we need");
  EXPECT_EQ(ErrorOf(Doc({{"needed", Scalar("1", 0)},
                         {"inner", Doc({{"cuont", Scalar("1", 0)}})}}))
                .message(),
            "unknown key (did you mean `count`?); valid keys under inner: "
            "count, at");
}

TEST(FieldReaderTest, ValidateBlamesTheFieldItReports) {
  ConfigNode items = ConfigNode::List();
  items.items.push_back(Doc({{"count", Scalar("7", 4)}}));
  items.items[0].line = 4;
  const InputError e =
      ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"items", items}}));
  EXPECT_EQ(e.key(), "items[0].count");
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.message(), "must not exceed inner.count, got 7");
}

TEST(FieldReaderTest, CommandLineValuesAreBlamedOnTheirFlag) {
  ConfigNode rate = Scalar("2", 0);
  rate.origin = "--set";
  EXPECT_EQ(ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"rate", rate}})).Format(),
            "command line: --set rate: must be a number in (0, 1], got 2");
}

TEST(FieldWriterTest, WritesEveryFieldAndReadsBackTheSame) {
  Outer o;
  o.rate = 0.1;
  o.who = 4;
  o.label = "true";  // a string that YAML would read as a boolean
  o.items = {Inner{}, Inner{2, {3, 4}}};
  o.needed = 9;
  const ConfigNode node = FieldWriter::WriteStruct(o);
  EXPECT_EQ(node.Find("rate")->scalar, "0.1");
  EXPECT_EQ(node.Find("who")->scalar, "4");
  EXPECT_EQ(node.Find("label")->style, ConfigNode::Style::kQuoted);
  EXPECT_EQ(node.Find("extra"), nullptr);  // nullopt is not written
  const Outer back = Read(node);
  EXPECT_EQ(back.rate, o.rate);
  EXPECT_EQ(back.label, "true");
  ASSERT_EQ(back.items.size(), 2u);
  EXPECT_EQ(back.items[1].at, Vec2(3, 4));
  Outer keyword;
  keyword.needed = 1;
  EXPECT_EQ(FieldWriter::WriteStruct(keyword).Find("who")->scalar, "anyone");
}

TEST(FieldDocsTest, OneRowPerKeyWithTypeAndDefault) {
  const std::vector<FieldDoc> rows = FieldDocs::Of(Outer{});
  std::vector<std::string> keys;
  for (const FieldDoc& r : rows) keys.push_back(r.key);
  EXPECT_EQ(keys,
            (std::vector<std::string>{
                "rate", "who", "on", "label", "shape", "extra", "extra.count",
                "extra.at", "items", "items[i].count", "items[i].at",
                "inner.count", "inner.at", "needed", "<parameter>"}));
  EXPECT_EQ(rows[0].type, "number in (0, 1]");
  EXPECT_EQ(rows[0].default_value, "0.5");
  EXPECT_EQ(rows[1].type, "integer >= 0 or anyone");
  EXPECT_EQ(rows[1].default_value, "anyone");
  EXPECT_EQ(rows[4].type, "round | square");
  EXPECT_EQ(rows[5].default_value, "none");
  EXPECT_EQ(rows[13].default_value, "required");
}

TEST(FieldFinderTest, FindsNestedMembersByAddress) {
  Outer o;
  o.items.resize(3);
  FieldFinder f(&o.items[2].at, typeid(Vec2));
  ASSERT_TRUE(f.Find(&o, "root"));
  EXPECT_EQ(f.key(), "root.items[2].at");
  // The same address as another type is not a match: a struct and its
  // first member.
  FieldFinder g(&o.inner, typeid(Inner));
  ASSERT_TRUE(g.Find(&o, ""));
  EXPECT_EQ(g.key(), "inner");
  FieldFinder h(&o.inner.count, typeid(int));
  ASSERT_TRUE(h.Find(&o, ""));
  EXPECT_EQ(h.key(), "inner.count");
}

TEST(KeyErrorTest, BlamesTheNearestGivenKey) {
  KeySources sources;
  sources["a"] = {2, 3, ""};
  sources["a.b"] = {4, 5, ""};
  sources["c"] = {6, 6, "--seed"};
  EXPECT_EQ(KeyError("f", sources, "a.b", "x").line(), 4);
  EXPECT_EQ(KeyError("f", sources, "a.b", "x", true).line(), 5);
  EXPECT_EQ(KeyError("f", sources, "a.z[1]", "x").line(), 2);
  EXPECT_EQ(KeyError("f", sources, "q", "x").line(), 0);
  EXPECT_EQ(KeyError("f", sources, "c.d", "x").Format(),
            "command line: --seed: x");
  // A key a --set gave is that flag; a default under a mapping a --set made
  // is named by itself, not as a flag nobody passed.
  sources["g"] = {0, 0, "--set"};
  sources["g.type"] = {0, 0, "--set"};
  EXPECT_EQ(KeyError("f", sources, "g.type", "x").Format(),
            "command line: --set g.type: x");
  EXPECT_EQ(KeyError("f", sources, "g.size", "x").Format(),
            "command line: g.size: x");
}

// Literals beyond a double's range are refused as such, not read as 0 or as
// "not finite".
TEST(FieldReaderTest, LiteralsBeyondADoubleAreOutOfRange) {
  EXPECT_EQ(
      ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"rate", Scalar("1e-400", 0)}}))
          .Format(),
      "f.yaml:2: rate: must be a number in (0, 1], got 1e-400, which is too "
      "small: it underflows to 0 (non-zero magnitudes start at 4.9e-324)");
  const std::string tiny = "0." + std::string(400, '0') + "1";
  EXPECT_NE(
      ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"rate", Scalar(tiny, 0)}}))
          .message()
          .find("which is too small: it underflows to 0"),
      std::string::npos);
  EXPECT_EQ(
      ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"rate", Scalar("-1e999", 0)}}))
          .message(),
      "must be a number in (0, 1], got -1e999, which is too large: it "
      "overflows (magnitudes end at 1.8e308)");
  ConfigNode at = ConfigNode::List();
  at.items = {Scalar("1e-400", 0), Scalar("2", 0)};
  EXPECT_EQ(
      ErrorOf(Doc({{"needed", Scalar("1", 0)}, {"inner", Doc({{"at", at}})}}))
          .message(),
      "must be two numbers [x, y], got [1e-400, 2]; 1e-400 is too "
      "small: it underflows to 0 (non-zero magnitudes start at "
      "4.9e-324)");
  // The smallest subnormal still reads, and zero is zero however written.
  EXPECT_EQ(field_text::ParseReal(Scalar("4.9e-324", 0)).value_or(-1),
            4.9e-324);
  field_text::OutOfRange beyond = field_text::OutOfRange::kTooLarge;
  EXPECT_EQ(
      field_text::ParseReal(Scalar("0.000e-99999", 0), &beyond).value_or(-1),
      0.0);
  EXPECT_EQ(beyond, field_text::OutOfRange::kNo);
}

// The scanners accept exactly the languages of the regular expressions they
// replaced (std::regex overflowed the stack on literals of some 30 000
// characters): a table of the edge cases, then every short string over the
// characters that matter, compared with the expressions themselves.
TEST(FieldTextTest, ScannersAcceptWhatTheFormerRegexesAccepted) {
  const std::regex decimal(
      R"([-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?)");
  const std::regex non_finite(R"([-+]?\.?(inf|infinity)|\.?nan)",
                              std::regex::icase);
  const std::regex integer("[-+]?[0-9]+");
  const std::regex word("true|false|null|yes|no|on|off|y|n|~",
                        std::regex::icase);
  struct Row {
    const char* text;
    bool decimal, non_finite, integer, word;
  };
  const Row table[] = {
      {"0", true, false, true, false},
      {"5", true, false, true, false},
      {"-17", true, false, true, false},
      {"+3", true, false, true, false},
      {"007", true, false, true, false},
      {".5", true, false, false, false},
      {"5.", true, false, false, false},
      {"-.5", true, false, false, false},
      {"+1e-3", true, false, false, false},
      {"2.5E+10", true, false, false, false},
      {"1e5", true, false, false, false},
      {".5e1", true, false, false, false},
      {"5.e1", true, false, false, false},
      {"1e", false, false, false, false},
      {"1e+", false, false, false, false},
      {"e5", false, false, false, false},
      {".e5", false, false, false, false},
      {".", false, false, false, false},
      {"-", false, false, false, false},
      {"+", false, false, false, false},
      {"", false, false, false, false},
      {"--1", false, false, false, false},
      {"+-1", false, false, false, false},
      {"1.2.3", false, false, false, false},
      {"1e5.5", false, false, false, false},
      {"0x10", false, false, false, false},
      {"1_000", false, false, false, false},
      {" 1", false, false, false, false},
      {"1 ", false, false, false, false},
      {"inf", false, true, false, false},
      {"INF", false, true, false, false},
      {".inf", false, true, false, false},
      {"-.Inf", false, true, false, false},
      {"+.inf", false, true, false, false},
      {"-Infinity", false, true, false, false},
      {"infinity", false, true, false, false},
      {".infinity", false, true, false, false},
      {"nan", false, true, false, false},
      {".NaN", false, true, false, false},
      {"NAN", false, true, false, false},
      {"-nan", false, false, false, false},
      {"+.nan", false, false, false, false},
      {"..inf", false, false, false, false},
      {"+-inf", false, false, false, false},
      {"infinit", false, false, false, false},
      {"infinityy", false, false, false, false},
      {"in", false, false, false, false},
      {"nan.", false, false, false, false},
      {"yes", false, false, false, true},
      {"No", false, false, false, true},
      {"TRUE", false, false, false, true},
      {"Off", false, false, false, true},
      {"y", false, false, false, true},
      {"N", false, false, false, true},
      {"~", false, false, false, true},
      {"null", false, false, false, true},
      {"nul", false, false, false, false},
      {"yess", false, false, false, false},
      {"~~", false, false, false, false},
  };
  for (const Row& r : table) {
    SCOPED_TRACE(std::string("'") + r.text + "'");
    EXPECT_EQ(field_text::IsDecimalLiteral(r.text), r.decimal);
    EXPECT_EQ(field_text::IsNonFiniteLiteral(r.text), r.non_finite);
    EXPECT_EQ(field_text::IsIntegerLiteral(r.text), r.integer);
    EXPECT_EQ(field_text::IsYamlWord(r.text), r.word);
    EXPECT_EQ(std::regex_match(r.text, decimal), r.decimal);
    EXPECT_EQ(std::regex_match(r.text, non_finite), r.non_finite);
    EXPECT_EQ(std::regex_match(r.text, integer), r.integer);
    EXPECT_EQ(std::regex_match(r.text, word), r.word);
  }
  // Every string of up to 5 characters over "05.eE+-": 19 608 of them.
  const std::string alphabet = "05.eE+-";
  std::vector<std::string> texts = {""};
  for (std::size_t begin = 0, length = 0; length < 5; ++length) {
    const std::size_t end = texts.size();
    for (std::size_t i = begin; i < end; ++i)
      for (const char c : alphabet) texts.push_back(texts[i] + c);
    begin = end;
  }
  for (const std::string& t : texts) {
    EXPECT_EQ(field_text::IsDecimalLiteral(t), std::regex_match(t, decimal))
        << "'" << t << "'";
    EXPECT_EQ(field_text::IsIntegerLiteral(t), std::regex_match(t, integer))
        << "'" << t << "'";
  }
  // And over the letters of the words, with signs and points.
  const std::string letters = "infatyINF.+-";
  texts = {""};
  for (std::size_t begin = 0, length = 0; length < 4; ++length) {
    const std::size_t end = texts.size();
    for (std::size_t i = begin; i < end; ++i)
      for (const char c : letters) texts.push_back(texts[i] + c);
    begin = end;
  }
  for (const std::string& t : texts) {
    EXPECT_EQ(field_text::IsNonFiniteLiteral(t),
              std::regex_match(t, non_finite))
        << "'" << t << "'";
  }
}

// Literals far longer than the stack would allow a recursive matcher: read
// (or refused) in linear time.
TEST(FieldTextTest, LongLiteralsAreScannedWithoutRecursion) {
  const std::string digits(100000, '7');
  field_text::OutOfRange beyond = field_text::OutOfRange::kNo;
  EXPECT_EQ(field_text::ParseReal(Scalar(digits, 0), &beyond).value_or(-1),
            kInfinity);
  EXPECT_EQ(beyond, field_text::OutOfRange::kTooLarge);
  EXPECT_EQ(field_text::ParseReal(Scalar("0." + digits, 0)).value_or(-1),
            0.7777777777777778);
  EXPECT_FALSE(field_text::ParseInteger(Scalar(digits, 0)).has_value());
  EXPECT_TRUE(field_text::IsIntegerLiteral(digits));
  EXPECT_FALSE(field_text::IsDecimalLiteral(digits + "x"));
  EXPECT_FALSE(field_text::IsNonFiniteLiteral(digits));
}

TEST(FieldTextTest, ParseCountPairTakesTwoBoundedCounts) {
  int a = -1, b = -1;
  EXPECT_TRUE(field_text::ParseCountPair("10x20", 'x', 5, &a, &b));
  EXPECT_EQ(a, 10);
  EXPECT_EQ(b, 20);
  EXPECT_TRUE(field_text::ParseCountPair("0/4", '/', 4, &a, &b));
  EXPECT_EQ(a, 0);
  EXPECT_EQ(b, 4);
  EXPECT_TRUE(field_text::ParseCountPair("99999x00001", 'x', 5, &a, &b));
  for (const char* bad : {"", "x", "1x", "x1", "123456x1", "1x123456", "1x1x1",
                          "-1x1", "+1x1", "1 x1", "1x1 ", "1X1", "a x b"})
    EXPECT_FALSE(field_text::ParseCountPair(bad, 'x', 5, &a, &b)) << bad;
  EXPECT_FALSE(field_text::ParseCountPair(std::string(100000, '1') + "x1", 'x',
                                          5, &a, &b));
}

// Values written as one token: read, written back, documented, refused
// with the reader's error form.
struct Job {
  std::vector<TeamSize> sizes{{10, 10}, {20, 20}};
  Shard shard;
  template <typename A>
  void Serialize(A* a) {
    a->Visit(AIA_FIELD(sizes).Doc("sizes"));
    a->Visit(AIA_FIELD(shard).Doc("share"));
  }
};

TEST(FieldValuesTest, SizesAndShardsReadWriteAndDocument) {
  ConfigNode sizes = ConfigNode::List();
  for (const char* s : {"2x3", "040x1"}) sizes.items.push_back(Scalar(s, 2));
  Job job;
  ReadFields(Doc({{"sizes", sizes}, {"shard", Scalar("3/4", 0)}}),
             ReadOptions{"f.yaml", "", ""}, "", &job);
  ASSERT_EQ(job.sizes.size(), 2u);
  EXPECT_EQ(job.sizes[0], (TeamSize{2, 3}));
  EXPECT_EQ(job.sizes[1], (TeamSize{40, 1}));
  EXPECT_EQ(job.shard, (Shard{3, 4}));
  // Written in the canonical form, which reads back as the same values.
  const ConfigNode written = FieldWriter::WriteStruct(job);
  EXPECT_EQ(ShowNode(written), "{sizes: [2x3, 40x1], shard: 3/4}");
  Job back;
  ReadFields(written, ReadOptions{"f.yaml", "", ""}, "", &back);
  EXPECT_EQ(back.sizes, job.sizes);
  EXPECT_EQ(back.shard, job.shard);
  const std::vector<FieldDoc> rows = FieldDocs::Of(Job{});
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].type, "list of ROBOTSxTARGETS");
  EXPECT_EQ(rows[0].default_value, "[10x10, 20x20]");
  EXPECT_EQ(rows[1].type, "K/N");
  EXPECT_EQ(rows[1].default_value, "0/1");

  const auto error = [](const std::string& key, const std::string& text) {
    ConfigNode value = Scalar(text, 3);
    if (key == "sizes") {
      value = ConfigNode::List();
      value.items.push_back(Scalar(text, 3));
    }
    Job j;
    try {
      ReadFields(Doc({{key, value}}), ReadOptions{"f.yaml", "", ""}, "", &j);
    } catch (const InputError& e) {
      return e.Format();
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("sizes", "10"),
            "f.yaml:3: sizes[0]: must be a size ROBOTSxTARGETS such as 10x10, "
            "got 10");
  EXPECT_EQ(error("sizes", "0x4"),
            "f.yaml:3: sizes[0]: robots and targets must be >= 1, got 0x4");
  EXPECT_EQ(error("sizes", "123456x1"),
            "f.yaml:3: sizes[0]: must be a size ROBOTSxTARGETS such as 10x10, "
            "got 123456x1");
  EXPECT_EQ(error("shard", "4/4"), "f.yaml:3: shard: need 0 <= K < N, got 4/4");
  EXPECT_EQ(error("shard", "0/0"), "f.yaml:3: shard: need 0 <= K < N, got 0/0");
  EXPECT_EQ(error("shard", "1 of 4"),
            "f.yaml:3: shard: must be K/N such as 0/4, got 1 of 4");
  EXPECT_EQ(error("shard", "-1/4"),
            "f.yaml:3: shard: must be K/N such as 0/4, got -1/4");
}

TEST(FieldValuesTest, SeedRangesThatPass64BitsAreNamed) {
  EXPECT_EQ(SeedRangeProblem(18446744073709551615u, 1, "--n", "--first"), "");
  EXPECT_EQ(SeedRangeProblem(5, 0, "--n", "--first"), "");
  EXPECT_EQ(SeedRangeProblem(18446744073709551614u, 3, "--n", "--first"),
            "seeds 18446744073709551614 .. 18446744073709551614 + 2 do not fit "
            "in 64 bits (the largest seed is 18446744073709551615); with --n "
            "3, --first must be at most 18446744073709551613");
}

TEST(FieldTextTest, ShortestRealReadsBackExactly) {
  for (double x : {0.1, 1.0 / 3.0, 1e-300, 123456789.125, -0.0, 4e-4}) {
    const std::string text = field_text::ShortestReal(x);
    const std::optional<double> back =
        field_text::ParseReal(ConfigNode::Scalar(text));
    ASSERT_TRUE(back.has_value()) << text;
    EXPECT_EQ(*back, x) << text;
  }
}

}  // namespace
}  // namespace aia
