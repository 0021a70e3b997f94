#include "aia/core/field_io.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <locale>
#include <sstream>
#include <system_error>

namespace aia {

std::string FormatNumber(double x) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(12) << x;
  return out.str();
}

std::string FormatPair(double x, double y) {
  return "[" + FormatNumber(x) + ", " + FormatNumber(y) + "]";
}

bool field_text::IsUtf8(std::string_view text) {
  const auto* p = reinterpret_cast<const unsigned char*>(text.data());
  const auto* end = p + text.size();
  while (p < end) {
    const unsigned c = *p;
    int extra = 0;
    unsigned code = 0, min = 0;
    if (c < 0x80) {
      ++p;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      extra = 1, code = c & 0x1F, min = 0x80;
    } else if ((c & 0xF0) == 0xE0) {
      extra = 2, code = c & 0x0F, min = 0x800;
    } else if ((c & 0xF8) == 0xF0) {
      extra = 3, code = c & 0x07, min = 0x10000;
    } else {
      return false;
    }
    if (end - p <= extra) return false;
    for (int k = 1; k <= extra; ++k) {
      if ((p[k] & 0xC0) != 0x80) return false;
      code = (code << 6) | (p[k] & 0x3F);
    }
    if (code < min || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF))
      return false;
    p += extra + 1;
  }
  return true;
}

std::string NumberRange::Describe(bool plural) const {
  const std::string noun = plural ? "numbers" : "number";
  if (lo == -kInfinity && hi == kInfinity) return noun;
  if (lo == 0.0 && hi == kInfinity)
    return (lo_open ? "positive " : "non-negative ") + noun;
  if (hi == kInfinity)
    return noun + (lo_open ? " > " : " >= ") + FormatNumber(lo);
  if (lo == -kInfinity)
    return noun + (hi_open ? " < " : " <= ") + FormatNumber(hi);
  return noun + " in " + (lo_open ? "(" : "[") + FormatNumber(lo) + ", " +
         FormatNumber(hi) + (hi_open ? ")" : "]");
}

std::string NumberRange::DescribeInteger() const {
  if (lo == -kInfinity && hi == kInfinity) return "an integer";
  if (hi == kInfinity) return "an integer >= " + FormatNumber(lo);
  if (lo == -kInfinity) return "an integer <= " + FormatNumber(hi);
  return "an integer in [" + FormatNumber(lo) + ", " + FormatNumber(hi) + "]";
}

InputError KeyError(const std::string& file, const KeySources& sources,
                    const std::string& key, const std::string& what,
                    bool at_value) {
  std::string k = key;
  while (true) {
    const auto it = sources.find(k);
    if (it != sources.end()) {
      const KeySource& s = it->second;
      if (!s.origin.empty()) {
        // A key a --set gave is named as that flag; one under a mapping a
        // --set made (a default that clashes with what was set) by itself:
        // no flag named it.
        const std::string named = s.origin != "--set" ? s.origin
                                  : k == key          ? "--set " + key
                                                      : key;
        return InputError::Flag(named, what);
      }
      return InputError(file, at_value && k == key ? s.value_line : s.key_line,
                        key, what);
    }
    if (k.empty()) break;
    // Up one level: "a.b[2]" -> "a.b", "a[1].c" -> "a[1]", "a" -> "".
    const std::string::size_type cut = k.find_last_of(".[");
    k.resize(cut == std::string::npos ? 0 : cut);
  }
  return InputError(file, 0, key, what);
}

namespace field_text {
namespace {

// Hand-written scanners rather than std::regex: libstdc++'s regex matcher
// recurses once per character and overflows the stack on a literal of some
// 30 000 characters (a crash, not an error).

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// Moves *i past the digits at s[*i]; how many there were.
std::size_t SkipDigits(std::string_view s, std::size_t* i) {
  const std::size_t begin = *i;
  while (*i < s.size() && IsDigit(s[*i])) ++*i;
  return *i - begin;
}

bool EqualsIgnoringCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const char c = a[i] >= 'A' && a[i] <= 'Z' ? a[i] - 'A' + 'a' : a[i];
    if (c != b[i]) return false;
  }
  return true;
}

// The decimal order of magnitude of a decimal literal (IsDecimalLiteral):
// k with 10^(k-1) <= |x| < 10^k, saturated far beyond double's range, or
// nullopt when x is zero. Only its sign is used, to tell an overflow from an
// underflow.
std::optional<long long> DecimalOrder(std::string_view s) {
  constexpr long long kCap = 1LL << 40;
  std::size_t i = (s[0] == '+' || s[0] == '-') ? 1 : 0;
  long long order = 0;
  bool nonzero = false;
  for (; i < s.size() && IsDigit(s[i]); ++i) {
    nonzero = nonzero || s[i] != '0';
    if (nonzero) order = std::min(order + 1, kCap);
  }
  if (i < s.size() && s[i] == '.') {
    for (++i; i < s.size() && IsDigit(s[i]); ++i) {
      if (nonzero) continue;
      if (s[i] == '0') {
        order = std::max(order - 1, -kCap);
      } else {
        nonzero = true;
      }
    }
  }
  if (!nonzero) return std::nullopt;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    const bool negative = s[i] == '-';
    if (s[i] == '+' || s[i] == '-') ++i;
    long long e = 0;
    for (; i < s.size(); ++i) e = std::min(e * 10 + (s[i] - '0'), kCap);
    order += negative ? -e : e;
  }
  return order;
}

}  // namespace

bool IsDecimalLiteral(std::string_view s) {
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  if (i < s.size() && s[i] == '.') {
    ++i;
    if (SkipDigits(s, &i) == 0) return false;
  } else {
    if (SkipDigits(s, &i) == 0) return false;
    if (i < s.size() && s[i] == '.') {
      ++i;
      SkipDigits(s, &i);
    }
  }
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (SkipDigits(s, &i) == 0) return false;
  }
  return i == s.size();
}

bool IsNonFiniteLiteral(std::string_view s) {
  std::size_t i = 0;
  const bool sign = !s.empty() && (s[0] == '+' || s[0] == '-');
  if (sign) ++i;
  if (i < s.size() && s[i] == '.') ++i;
  const std::string_view word = s.substr(i);
  return EqualsIgnoringCase(word, "inf") ||
         EqualsIgnoringCase(word, "infinity") ||
         (!sign && EqualsIgnoringCase(word, "nan"));
}

bool IsIntegerLiteral(std::string_view s) {
  std::size_t i = 0;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  return SkipDigits(s, &i) > 0 && i == s.size();
}

bool IsYamlWord(std::string_view s) {
  for (const char* word :
       {"true", "false", "null", "yes", "no", "on", "off", "y", "n", "~"})
    if (EqualsIgnoringCase(s, word)) return true;
  return false;
}

bool ParseCountPair(std::string_view text, char separator,
                    std::size_t max_digits, int* first, int* second) {
  std::size_t i = 0;
  const auto count = [&](int* out) {
    const std::size_t begin = i;
    *out = 0;
    for (; i < text.size() && IsDigit(text[i]) && i - begin < max_digits; ++i)
      *out = *out * 10 + (text[i] - '0');
    return i > begin;
  };
  if (!count(first) || i >= text.size() || text[i] != separator) return false;
  ++i;
  return count(second) && i == text.size();
}

std::optional<double> ParseReal(const ConfigNode& node,
                                OutOfRange* out_of_range) {
  if (out_of_range) *out_of_range = OutOfRange::kNo;
  if (!node.IsPlainScalar()) return std::nullopt;
  const std::string& s = node.scalar;
  const bool negative = !s.empty() && s[0] == '-';
  if (IsNonFiniteLiteral(s)) {
    if (s.find_first_of("nN") != std::string::npos &&
        s.find_first_of("aA") != std::string::npos) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    return negative ? -kInfinity : kInfinity;
  }
  if (!IsDecimalLiteral(s)) return std::nullopt;
  const char* begin = s.data() + (s[0] == '+' ? 1 : 0);
  double x = 0.0;
  const auto [end, ec] = std::from_chars(begin, s.data() + s.size(), x);
  if (ec == std::errc::result_out_of_range) {
    // Too large (1e999) is not finite; too small (1e-999, 0.000...01) is
    // zero. The readers refuse both, saying which.
    const std::optional<long long> order = DecimalOrder(s);
    if (!order) return 0.0;
    const bool small = *order <= 0;
    if (out_of_range)
      *out_of_range = small ? OutOfRange::kTooSmall : OutOfRange::kTooLarge;
    if (small) return 0.0;
    return negative ? -kInfinity : kInfinity;
  }
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return x;
}

namespace {

template <typename T>
std::optional<T> ParseWhole(const ConfigNode& node) {
  if (!node.IsPlainScalar() || !IsIntegerLiteral(node.scalar))
    return std::nullopt;
  const std::string& s = node.scalar;
  const char* begin = s.data() + (s[0] == '+' ? 1 : 0);
  T x{};
  const auto [end, ec] = std::from_chars(begin, s.data() + s.size(), x);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return x;
}

}  // namespace

std::optional<long long> ParseInteger(const ConfigNode& node) {
  return ParseWhole<long long>(node);
}

std::optional<std::uint64_t> ParseUnsigned(const ConfigNode& node) {
  return ParseWhole<std::uint64_t>(node);
}

std::string ShortestReal(double x) {
  char buf[64];
  const auto result = std::to_chars(buf, buf + sizeof(buf), x);
  AIA_CHECK(result.ec == std::errc());
  return std::string(buf, result.ptr);
}

std::string CountWord(std::size_t n) {
  static const char* const kWords[] = {"no", "one", "two", "three", "four"};
  return n < 5 ? kWords[n] : std::to_string(n);
}

std::string Join(const std::vector<std::string>& items,
                 const std::string& separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i)
    out += (i ? separator : "") + items[i];
  return out;
}

std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1,
                         diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

std::string ClosestName(const std::string& name,
                        const std::vector<std::string>& names) {
  std::string best;
  std::size_t best_distance = 3;  // more edits than two is not a typo
  for (const std::string& n : names) {
    const std::size_t d = EditDistance(name, n);
    if (d < best_distance) {
      best = n;
      best_distance = d;
    }
  }
  return best;
}

std::string RangeSuffix(const NumberRange& r, bool integer) {
  if (r.lo == -kInfinity && r.hi == kInfinity) return "";
  if (r.hi == kInfinity) {
    if (r.lo == 0.0 && !integer) return r.lo_open ? " > 0" : " >= 0";
    return (r.lo_open ? " > " : " >= ") + FormatNumber(r.lo);
  }
  if (r.lo == -kInfinity)
    return (r.hi_open ? " < " : " <= ") + FormatNumber(r.hi);
  return std::string(" in ") + (r.lo_open ? "(" : "[") + FormatNumber(r.lo) +
         ", " + FormatNumber(r.hi) + (r.hi_open ? ")" : "]");
}

}  // namespace field_text

namespace {

// What is wrong with a literal beyond a double's range ("1e-400 is too
// small: ..."), which would otherwise read as 0 (silently) or as infinite.
std::string BeyondDouble(field_text::OutOfRange r) {
  return r == field_text::OutOfRange::kTooSmall
             ? "is too small: it underflows to 0 (non-zero magnitudes start "
               "at 4.9e-324)"
             : "is too large: it overflows (magnitudes end at 1.8e308)";
}

}  // namespace

void FieldReader::Fail(const ConfigNode& node, const std::string& key,
                       const std::string& what) const {
  if (!node.origin.empty()) {
    throw InputError::Flag(
        node.origin == "--set" ? "--set " + key : node.origin, what);
  }
  throw InputError(options_.file, node.line, key.empty() ? "(document)" : key,
                   what);
}

void FieldReader::FailUnknownKey(const ConfigNode::Entry& entry,
                                 const std::string& key,
                                 const std::vector<std::string>& names) const {
  const bool custom = !options_.unknown_key_lead.empty();
  std::string what = custom ? options_.unknown_key_lead : "unknown key";
  const std::string closest = field_text::ClosestName(entry.key, names);
  if (!closest.empty()) what += " (did you mean `" + closest + "`?)";
  if (custom) {
    what += " (valid: " +
            (names.empty() ? std::string("none") : field_text::Join(names)) +
            ")";
  } else {
    // The parent is the path before this entry's own key (which may hold
    // a dot itself: a YAML key "sensor.range" is one key, not a path).
    const std::string parent =
        key.size() > entry.key.size() + 1
            ? key.substr(0, key.size() - entry.key.size() - 1)
            : "";
    if (entry.key.find('.') != std::string::npos)
      what +=
          " (a key with a dot is one key, not a path: nest it as a "
          "mapping)";
    what += parent.empty() ? "; valid top-level keys: "
                           : "; valid keys under " + parent + ": ";
    what += field_text::Join(names);
  }
  ConfigNode at = entry.value;  // blamed at the key's line
  at.line = entry.key_line;
  Fail(at, key, what);
}

void FieldReader::Record(const std::string& key, int key_line,
                         const ConfigNode& value) {
  KeySource s;
  s.key_line = key_line;
  s.value_line = value.IsNull() || value.line <= 0 ? key_line : value.line;
  s.origin = value.origin;
  sources_[key] = s;
  nodes_[key] = &value;
}

std::string FieldReader::ResolvePath(const ConfigNode& node) const {
  namespace fs = std::filesystem;
  fs::path path(node.scalar);
  if (path.is_relative() && node.origin.empty())
    path = fs::path(options_.base_dir) / path;
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec);
  return (ec ? path : absolute).lexically_normal().string();
}

double FieldReader::ReadReal(const ConfigNode& node, const std::string& key,
                             const NumberRange& range,
                             std::string_view expect) const {
  field_text::OutOfRange beyond = field_text::OutOfRange::kNo;
  const std::optional<double> x = field_text::ParseReal(node, &beyond);
  const std::string expected =
      expect.empty() ? "a " + range.Describe(false) : std::string(expect);
  if (beyond != field_text::OutOfRange::kNo) {
    Fail(node, key,
         "must be " + expected + ", got " + ShowNode(node) + ", which " +
             BeyondDouble(beyond));
  }
  if (x && !std::isfinite(*x)) FailExpected(node, key, "a finite number");
  if (!x || !range.Contains(*x)) FailExpected(node, key, expected);
  return *x;
}

long long FieldReader::ReadInteger(
    const ConfigNode& node, const std::string& key, const NumberRange& range,
    std::string_view expect, std::string_view keyword, long long keyword_value,
    long long lo, long long hi) const {
  if (!keyword.empty() && node.IsPlainScalar() && node.scalar == keyword)
    return keyword_value;
  const std::optional<long long> x = field_text::ParseInteger(node);
  if (!x || *x < lo || *x > hi || !range.Contains(static_cast<double>(*x))) {
    std::string expected =
        expect.empty() ? range.DescribeInteger() : std::string(expect);
    if (expect.empty() && !keyword.empty())
      expected += " or " + std::string(keyword);
    // An integer the declared range allows but the field's type cannot
    // hold: its bound is said, not only the range's ("must be an integer
    // >= 1, got 99999999999" read as if the value were fine).
    if (expect.empty() && node.IsPlainScalar() &&
        field_text::IsIntegerLiteral(node.scalar)) {
      const bool negative = node.scalar[0] == '-';
      const bool above = x ? *x > hi : !negative;
      const bool below = x ? *x < lo : negative;
      const auto bits = [](long long bound) -> std::string {
        if (bound == std::numeric_limits<int>::max() ||
            bound == std::numeric_limits<int>::min())
          return " that fits in 32 bits";
        if (bound == std::numeric_limits<long long>::max() ||
            bound == std::numeric_limits<long long>::min())
          return " that fits in 64 bits";
        return "";
      };
      if (above && range.hi > static_cast<double>(hi))
        FailExpected(
            node, key,
            expected + bits(hi) + " (at most " + std::to_string(hi) + ")");
      if (below && range.lo < static_cast<double>(lo))
        FailExpected(
            node, key,
            expected + bits(lo) + " (at least " + std::to_string(lo) + ")");
    }
    FailExpected(node, key, expected);
  }
  return *x;
}

Eigen::VectorXd FieldReader::ReadNumbers(const ConfigNode& node,
                                         const std::string& key,
                                         std::size_t size,
                                         const NumberRange& range,
                                         std::string_view shape) const {
  const std::string suffix = shape.empty() ? "" : " " + std::string(shape);
  const std::string expected = size > 0 ? field_text::CountWord(size) + " " +
                                              range.Describe(size != 1) + suffix
                                        : "a list of " + range.Describe(true);
  if (!node.IsList() || (size > 0 && node.items.size() != size))
    FailExpected(node, key, expected);
  Eigen::VectorXd out(static_cast<Eigen::Index>(node.items.size()));
  for (std::size_t i = 0; i < node.items.size(); ++i) {
    field_text::OutOfRange beyond = field_text::OutOfRange::kNo;
    const std::optional<double> x =
        field_text::ParseReal(node.items[i], &beyond);
    if (beyond != field_text::OutOfRange::kNo) {
      Fail(node, key,
           "must be " + expected + ", got " + ShowNode(node) + "; " +
               ShowNode(node.items[i]) + " " + BeyondDouble(beyond));
    }
    if (x && !std::isfinite(*x)) {
      FailExpected(node, key,
                   size > 0 ? "finite numbers" + suffix
                            : std::string("a list of finite numbers"));
    }
    if (!x || !range.Contains(*x)) FailExpected(node, key, expected);
    out[static_cast<Eigen::Index>(i)] = *x;
  }
  return out;
}

Eigen::MatrixXd FieldReader::ReadMatrix(const ConfigNode& node,
                                        const std::string& key,
                                        const NumberRange& range) const {
  const std::string expected =
      "a matrix given as a list of rows of numbers, e.g. [[1, 0], [0, 1]]";
  if (!node.IsList() || node.items.empty()) FailExpected(node, key, expected);
  const std::size_t rows = node.items.size();
  const std::size_t cols =
      node.items[0].IsList() ? node.items[0].items.size() : 0;
  if (cols == 0) FailExpected(node, key, expected);
  // Every row's shape before the matrix is allocated: rows * cols is only
  // bounded once the rows agree.
  for (std::size_t i = 0; i < rows; ++i) {
    const ConfigNode& row = node.items[i];
    if (!row.IsList()) FailExpected(node, key, expected);
    if (row.items.size() != cols) {
      Fail(node, key,
           "rows must all have the same length; row " + std::to_string(i) +
               " has " + std::to_string(row.items.size()) +
               " entries but row 0 has " + std::to_string(cols) + ", got " +
               ShowNode(node));
    }
  }
  Eigen::MatrixXd m(rows, cols);
  for (std::size_t i = 0; i < rows; ++i) {
    const ConfigNode& row = node.items[i];
    for (std::size_t j = 0; j < cols; ++j) {
      field_text::OutOfRange beyond = field_text::OutOfRange::kNo;
      const std::optional<double> x =
          field_text::ParseReal(row.items[j], &beyond);
      if (beyond != field_text::OutOfRange::kNo) {
        Fail(node, key,
             "entries must be " + range.Describe(true) + ", got " +
                 ShowNode(row.items[j]) + " in row " + std::to_string(i) +
                 ", which " + BeyondDouble(beyond));
      }
      if (!x || !std::isfinite(*x)) {
        Fail(node, key,
             "entries must be finite numbers, got " + ShowNode(row.items[j]) +
                 " in row " + std::to_string(i));
      }
      if (!range.Contains(*x)) {
        Fail(node, key,
             "entries must be " + range.Describe(true) + ", got " +
                 ShowNode(row.items[j]) + " in row " + std::to_string(i));
      }
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = *x;
    }
  }
  return m;
}

std::string FlagName(std::string_view key) {
  const std::string_view::size_type dot = key.find_last_of('.');
  std::string flag =
      "--" +
      std::string(dot == std::string_view::npos ? key : key.substr(dot + 1));
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

void SetFlagOrigins(ConfigNode* node) {
  for (ConfigNode::Entry& e : node->entries) {
    if (e.value.IsMap())
      SetFlagOrigins(&e.value);
    else
      e.value.SetOrigin(FlagName(e.key));
  }
}

}  // namespace aia
