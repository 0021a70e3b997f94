#include "aia/scenario/loader.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <locale>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "aia/core/error.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------
// Values and how they are shown in messages.

// A node of the document, the dotted key it was found under (e.g.
// "targets.list[1].dynamics.A") and the 1-based line to blame when it is
// wrong.
struct Value {
  YAML::Node node;
  std::string key;
  int line = 0;
};

std::string Child(const std::string& parent, const std::string& name) {
  return parent.empty() ? name : parent + "." + name;
}

std::string Item(const std::string& list, std::size_t index) {
  return list + "[" + std::to_string(index) + "]";
}

// yaml-cpp marks an empty value (`key:`) at the next token, often on a later
// line, so an empty value is blamed on the line of its key instead.
int LineOfNode(const YAML::Node& node, int fallback) {
  if (node.IsNull() || node.Mark().line < 0) return fallback;
  return node.Mark().line + 1;
}

// Quoted scalars get the tag "!", plain ones "?". Only plain scalars may be
// numbers or booleans, so that `count: "5"` is reported as a string.
bool IsPlainScalar(const YAML::Node& node) {
  return node.IsScalar() && node.Tag() == "?";
}

// The node as it looked in the file, roughly: enough to recognize it.
std::string Render(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: {
      std::string text;
      for (const char c : node.Scalar()) {
        text += c == '\n' ? std::string("\\n") : std::string(1, c);
      }
      if (IsPlainScalar(node)) return text;
      // Explicitly tagged (`!!float 0.1`): say so, since only plain scalars
      // are read as numbers and booleans.
      const std::string core = "tag:yaml.org,2002:";
      if (node.Tag().rfind(core, 0) == 0) {
        return "!!" + node.Tag().substr(core.size()) + " " + text;
      }
      return "\"" + text + "\"";
    }
    case YAML::NodeType::Sequence: {
      std::string out = "[";
      for (std::size_t i = 0; i < node.size(); ++i) {
        out += (i ? ", " : "") + Render(node[i]);
      }
      return out + "]";
    }
    case YAML::NodeType::Map: {
      std::string out = "{";
      bool first = true;
      for (const auto& kv : node) {
        out +=
            (first ? "" : ", ") + Render(kv.first) + ": " + Render(kv.second);
        first = false;
      }
      return out + "}";
    }
    default:
      return "null";
  }
}

// What a message says was found instead of what was expected.
std::string Show(const YAML::Node& node) {
  if (node.IsNull()) return "nothing";
  constexpr std::size_t kMaxChars = 60;
  std::string text = Render(node);
  if (text.size() > kMaxChars) text = text.substr(0, kMaxChars - 3) + "...";
  return text;
}

std::string Fmt(double x) {
  std::ostringstream out;
  out.imbue(std::locale::classic());
  out << std::setprecision(12) << x;
  return out.str();
}

std::string Fmt(const Vec2& v) {
  return "[" + Fmt(v.x()) + ", " + Fmt(v.y()) + "]";
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

// Levenshtein distance, for "did you mean" hints on misspelt keys.
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

// ---------------------------------------------------------------------------
// Numbers. yaml-cpp's as<int>() and as<double>() accept more than a scenario
// should (as<int>() of "2.5" in some versions, hex, trailing text), so plain
// scalars are matched against the YAML 1.2 core-schema spellings here.

bool IsIntegerText(const std::string& s) {
  static const std::regex kInteger("[-+]?[0-9]+");
  return std::regex_match(s, kInteger);
}

// The value of a plain numeric scalar, possibly NaN or infinite; nullopt for
// anything that is not a number.
std::optional<double> ToDouble(const YAML::Node& node) {
  if (!IsPlainScalar(node)) return std::nullopt;
  static const std::regex kReal(
      R"([-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?)");
  static const std::regex kNonFinite(R"([-+]?\.?(inf|infinity)|\.?nan)",
                                     std::regex::icase);
  const std::string& s = node.Scalar();
  const bool negative = !s.empty() && s[0] == '-';
  if (std::regex_match(s, kNonFinite)) {
    if (s.find_first_of("nN") != std::string::npos &&
        s.find_first_of("aA") != std::string::npos) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    return negative ? -kInf : kInf;
  }
  if (!std::regex_match(s, kReal)) return std::nullopt;
  const char* begin = s.data() + (s[0] == '+' ? 1 : 0);
  double x = 0.0;
  const auto [end, ec] = std::from_chars(begin, s.data() + s.size(), x);
  if (ec == std::errc::result_out_of_range) {
    // Too large (1e999) is not finite; too small (1e-999) is zero.
    const std::string::size_type e = s.find_first_of("eE");
    if (e != std::string::npos && s[e + 1] == '-') return 0.0;
    return negative ? -kInf : kInf;
  }
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return x;
}

template <typename T>
std::optional<T> ToInteger(const YAML::Node& node) {
  if (!IsPlainScalar(node) || !IsIntegerText(node.Scalar()))
    return std::nullopt;
  const std::string& s = node.Scalar();
  const char* begin = s.data() + (s[0] == '+' ? 1 : 0);
  T x{};
  const auto [end, ec] = std::from_chars(begin, s.data() + s.size(), x);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return x;
}

// Allowed values of a real-valued key, open or closed at either end.
struct Range {
  double lo = -kInf;
  double hi = kInf;
  bool lo_open = false;
  bool hi_open = false;

  bool Contains(double x) const {
    return (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
};

constexpr Range kAnyNumber{};
constexpr Range kPositive{0.0, kInf, true, false};
constexpr Range kNonNegative{0.0, kInf, false, false};
constexpr Range kOpenUnit{0.0, 1.0, true, true};       // (0, 1)
constexpr Range kHalfOpenUnit{0.0, 1.0, true, false};  // (0, 1]

// "positive numbers", "numbers in (0, 1]", ...
std::string Describe(const Range& r, bool plural) {
  const std::string noun = plural ? "numbers" : "number";
  if (r.lo == -kInf && r.hi == kInf) return noun;
  if (r.lo == 0.0 && r.hi == kInf) {
    return (r.lo_open ? "positive " : "non-negative ") + noun;
  }
  if (r.hi == kInf) return noun + (r.lo_open ? " > " : " >= ") + Fmt(r.lo);
  return noun + " in " + (r.lo_open ? "(" : "[") + Fmt(r.lo) + ", " +
         Fmt(r.hi) + (r.hi_open ? ")" : "]");
}

std::string DescribeInt(int lo, int hi) {
  if (lo == INT_MIN && hi == INT_MAX) return "an integer";
  if (hi == INT_MAX) return "an integer >= " + std::to_string(lo);
  return "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
         "]";
}

std::string CountWord(std::size_t n) {
  static const char* const kWords[] = {"no", "one", "two", "three", "four"};
  return n < 5 ? kWords[n] : std::to_string(n);
}

// ---------------------------------------------------------------------------
// Mappings.

// The entries of one YAML mapping, in document order.
class Fields {
 public:
  explicit Fields(std::string key) : key_(std::move(key)) {}

  void Add(const std::string& name, Value value) {
    entries_.emplace_back(name, std::move(value));
  }

  // The entry `name`, or nullptr when the file does not give it.
  const Value* Get(const std::string& name) const {
    for (const auto& [n, v] : entries_) {
      if (n == name) return &v;
    }
    return nullptr;
  }

  // The entry `name`, or an empty value standing for it: for sections whose
  // absence means "all defaults" but whose required keys must still be
  // reported (robots.count, targets).
  Value GetOrEmpty(const std::string& name) const {
    const Value* v = Get(name);
    return v ? *v : Value{YAML::Node(), Child(key_, name), 0};
  }

  const std::vector<std::pair<std::string, Value>>& entries() const {
    return entries_;
  }

 private:
  std::string key_;
  std::vector<std::pair<std::string, Value>> entries_;
};

// ---------------------------------------------------------------------------
// The parser: typed readers that throw InputError at the right key and line,
// and one function per section of SPEC section 10.

class Parser {
 public:
  Parser(std::string file, std::string base_dir, Scenario& out)
      : file_(std::move(file)), base_dir_(std::move(base_dir)), out_(out) {}

  void Parse(const YAML::Node& root) {
    const Fields f =
        ReadMap(Value{root, "", LineOfNode(root, 0)},
                {"name", "seed", "workspace", "robots", "sensor", "targets",
                 "mission", "communication", "policy", "physics", "render"});
    if (const Value* v = f.Get("name")) out_.name = ReadString(*v);
    if (const Value* v = f.Get("seed")) out_.seed = ReadUint64(*v);
    // Workspace first and robots next: later checks need the workspace size
    // and the number of robots.
    ParseWorkspace(f.GetOrEmpty("workspace"));
    ParseRobots(f.GetOrEmpty("robots"));
    ParseSensor(f.GetOrEmpty("sensor"));
    ParseTargets(f.GetOrEmpty("targets"));
    ParseMission(f.GetOrEmpty("mission"));
    ParseCommunication(f.GetOrEmpty("communication"));
    ParsePolicy(f.GetOrEmpty("policy"));
    ParsePhysics(f.GetOrEmpty("physics"));
    ParseRender(f.GetOrEmpty("render"));
  }

 private:
  // --- Errors --------------------------------------------------------------

  [[noreturn]] void Fail(const Value& v, const std::string& what) const {
    throw InputError(file_, v.line, v.key.empty() ? "(document)" : v.key, what);
  }

  // For checks across keys, made after a section is read: blames the key's
  // line, or its section's when the key is absent and a default is at fault.
  [[noreturn]] void FailAt(const std::string& key,
                           const std::string& what) const {
    throw InputError(file_, out_.LineOf(key), key, what);
  }

  [[noreturn]] void FailExpected(const Value& v,
                                 const std::string& expected) const {
    Fail(v, "must be " + expected + ", got " + Show(v.node));
  }

  // --- Structure -----------------------------------------------------------

  // Reads a mapping whose keys must be among `keys` (any key when `open`),
  // recording the line of each. An empty value reads as an empty mapping, so
  // that `random:` alone asks for random obstacles with default settings.
  Fields ReadMap(const Value& v, const std::vector<std::string>& keys,
                 bool open = false) {
    Fields fields(v.key);
    if (v.node.IsNull()) return fields;
    if (!v.node.IsMap()) {
      FailExpected(v, "a mapping with keys among " + Join(keys));
    }
    std::vector<std::pair<std::string, int>> seen;
    for (const auto& kv : v.node) {
      const int key_line = LineOfNode(kv.first, v.line);
      if (!kv.first.IsScalar()) {
        Fail(Value{kv.first, v.key, key_line},
             "keys must be names, got " + Show(kv.first));
      }
      const std::string name = kv.first.Scalar();
      const std::string key = Child(v.key, name);
      for (const auto& [n, line] : seen) {
        if (n == name) {
          Fail(Value{kv.first, key, key_line},
               "duplicate key (first given at line " + std::to_string(line) +
                   "); give each key once");
        }
      }
      seen.emplace_back(name, key_line);
      if (!open && std::find(keys.begin(), keys.end(), name) == keys.end()) {
        FailUnknownKey(Value{kv.first, key, key_line}, name, keys);
      }
      out_.lines[key] = key_line;
      fields.Add(name, Value{kv.second, key, LineOfNode(kv.second, key_line)});
    }
    return fields;
  }

  [[noreturn]] void FailUnknownKey(const Value& v, const std::string& name,
                                   const std::vector<std::string>& keys) const {
    std::string what = "unknown key";
    const std::string* best = nullptr;
    std::size_t best_distance = 3;  // more edits than this is not a typo
    for (const std::string& k : keys) {
      const std::size_t d = EditDistance(name, k);
      if (d < best_distance) {
        best = &k;
        best_distance = d;
      }
    }
    if (best) what += " (did you mean `" + *best + "`?)";
    const std::string::size_type dot = v.key.find_last_of('.');
    what += dot == std::string::npos
                ? "; valid top-level keys: "
                : "; valid keys under " + v.key.substr(0, dot) + ": ";
    Fail(v, what + Join(keys));
  }

  // Reads a list, recording the line of each item as `key[i]`.
  std::vector<Value> ReadList(const Value& v) {
    if (!v.node.IsSequence()) FailExpected(v, "a list");
    std::vector<Value> items;
    for (std::size_t i = 0; i < v.node.size(); ++i) {
      const YAML::Node node = v.node[i];
      Value item{node, Item(v.key, i), LineOfNode(node, v.line)};
      // An empty entry (a bare `-`) would otherwise become a default box or
      // failure without the user having asked for one.
      if (node.IsNull()) Fail(item, "list entries must not be empty");
      out_.lines[item.key] = item.line;
      items.push_back(std::move(item));
    }
    return items;
  }

  // --- Typed values --------------------------------------------------------

  double ReadDouble(const Value& v, const Range& range = kAnyNumber) const {
    const std::optional<double> x = ToDouble(v.node);
    if (x && !std::isfinite(*x)) FailExpected(v, "a finite number");
    if (!x || !range.Contains(*x))
      FailExpected(v, "a " + Describe(range, false));
    return *x;
  }

  // `expected` replaces the generic "an integer in [lo, hi]" where the bounds
  // need explaining (robot indices).
  int ReadInt(const Value& v, int lo = INT_MIN, int hi = INT_MAX,
              const std::string& expected = "") const {
    const std::optional<int> x = ToInteger<int>(v.node);
    if (!x || *x < lo || *x > hi) {
      FailExpected(v, expected.empty() ? DescribeInt(lo, hi) : expected);
    }
    return *x;
  }

  std::uint64_t ReadUint64(const Value& v) const {
    const std::optional<std::uint64_t> x = ToInteger<std::uint64_t>(v.node);
    if (!x) FailExpected(v, "an integer >= 0");
    return *x;
  }

  bool ReadBool(const Value& v) const {
    if (IsPlainScalar(v.node) && v.node.Scalar() == "true") return true;
    if (IsPlainScalar(v.node) && v.node.Scalar() == "false") return false;
    FailExpected(v, "true or false");
  }

  std::string ReadString(const Value& v) const {
    if (!v.node.IsScalar()) FailExpected(v, "a string");
    return v.node.Scalar();
  }

  // A non-empty path, made absolute against the scenario's directory.
  std::string ReadPath(const Value& v) const {
    const std::string text = ReadString(v);
    if (text.empty()) FailExpected(v, "a file path");
    fs::path path(text);
    if (path.is_relative()) path = fs::path(base_dir_) / path;
    return fs::absolute(path).lexically_normal().string();
  }

  // A list of exactly `size` numbers within `range`; `shape` names the
  // entries for the message, e.g. "[width, height]".
  Eigen::VectorXd ReadVector(const Value& v, std::size_t size,
                             const Range& range,
                             const std::string& shape) const {
    const std::string expected =
        CountWord(size) + " " + Describe(range, size != 1) + " " + shape;
    if (!v.node.IsSequence() || v.node.size() != size)
      FailExpected(v, expected);
    Eigen::VectorXd out(size);
    for (std::size_t i = 0; i < size; ++i) {
      const std::optional<double> x = ToDouble(v.node[i]);
      if (x && !std::isfinite(*x)) FailExpected(v, "finite numbers " + shape);
      if (!x || !range.Contains(*x)) FailExpected(v, expected);
      out[static_cast<Eigen::Index>(i)] = *x;
    }
    return out;
  }

  Vec2 ReadVec2(const Value& v, const Range& range = kAnyNumber,
                const std::string& shape = "[x, y]") const {
    return ReadVector(v, 2, range, shape);
  }

  // A matrix written as a list of rows of finite numbers.
  Eigen::MatrixXd ReadMatrix(const Value& v) const {
    const std::string expected =
        "a matrix given as a list of rows of numbers, e.g. [[1, 0], [0, 1]]";
    if (!v.node.IsSequence() || v.node.size() == 0) FailExpected(v, expected);
    const std::size_t rows = v.node.size();
    const std::size_t cols = v.node[0].IsSequence() ? v.node[0].size() : 0;
    if (cols == 0) FailExpected(v, expected);
    Eigen::MatrixXd m(rows, cols);
    for (std::size_t i = 0; i < rows; ++i) {
      const YAML::Node row = v.node[i];
      if (!row.IsSequence()) FailExpected(v, expected);
      if (row.size() != cols) {
        Fail(v, "rows must all have the same length; row " + std::to_string(i) +
                    " has " + std::to_string(row.size()) +
                    " entries but row 0 has " + std::to_string(cols) +
                    ", got " + Show(v.node));
      }
      for (std::size_t j = 0; j < cols; ++j) {
        const std::optional<double> x = ToDouble(row[j]);
        if (!x || !std::isfinite(*x)) {
          Fail(v, "entries must be finite numbers, got " + Show(row[j]) +
                      " in row " + std::to_string(i));
        }
        m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = *x;
      }
    }
    return m;
  }

  // Obstacles are checked against positions in world/; here only the
  // workspace bounds [0, size] are.
  void CheckInsideWorkspace(const Value& v, const Vec2& p) const {
    const Vec2& size = out_.workspace.size;
    if (p.x() < 0.0 || p.y() < 0.0 || p.x() > size.x() || p.y() > size.y()) {
      Fail(v, "must lie inside the workspace [0, " + Fmt(size.x()) +
                  "] x [0, " + Fmt(size.y()) + "], got " + Show(v.node));
    }
  }

  std::string RobotIndexText() const {
    return "[0, " + std::to_string(out_.robots.count - 1) +
           "] (robots.count is " + std::to_string(out_.robots.count) + ")";
  }

  // --- Sections ------------------------------------------------------------

  void ParseWorkspace(const Value& v) {
    WorkspaceConfig& ws = out_.workspace;
    const Fields f = ReadMap(v, {"size", "cell", "obstacles"});
    if (const Value* x = f.Get("size")) {
      ws.size = ReadVec2(*x, kPositive, "[width, height]");
    }
    if (const Value* x = f.Get("cell")) ws.cell = ReadDouble(*x, kPositive);
    if (ws.cell > ws.size.minCoeff()) {
      FailAt("workspace.cell",
             "must not be larger than the smaller workspace side (" +
                 Fmt(ws.size.minCoeff()) + "), got " + Fmt(ws.cell));
    }
    if (const Value* x = f.Get("obstacles")) ParseObstacles(*x);
  }

  void ParseObstacles(const Value& v) {
    WorkspaceConfig& ws = out_.workspace;
    const Fields f = ReadMap(v, {"random", "boxes", "map", "map_threshold"});
    if (const Value* x = f.Get("random")) ws.random = ParseRandomObstacles(*x);
    if (const Value* x = f.Get("boxes")) {
      for (const Value& item : ReadList(*x)) ws.boxes.push_back(ParseBox(item));
    }
    if (const Value* x = f.Get("map")) {
      // Only existence here: the image is decoded by world/, which owns the
      // occupancy grid.
      ws.map = ReadPath(*x);
      std::error_code ec;
      if (!fs::exists(ws.map, ec)) {
        Fail(*x, "map file does not exist: " + ws.map +
                     " (relative paths are resolved against the scenario's "
                     "directory)");
      }
      if (!fs::is_regular_file(ws.map, ec))
        Fail(*x, "map is not a file: " + ws.map);
    }
    if (const Value* x = f.Get("map_threshold")) {
      ws.map_threshold = ReadDouble(*x, kOpenUnit);
    }
  }

  RandomObstaclesConfig ParseRandomObstacles(const Value& v) {
    RandomObstaclesConfig r;
    const Fields f = ReadMap(v, {"count", "min_size", "max_size"});
    if (const Value* x = f.Get("count")) r.count = ReadInt(*x, 0);
    if (const Value* x = f.Get("min_size")) {
      r.min_size = ReadVec2(*x, kPositive, "[width, height]");
    }
    if (const Value* x = f.Get("max_size")) {
      r.max_size = ReadVec2(*x, kPositive, "[width, height]");
    }
    if ((r.min_size.array() > r.max_size.array()).any()) {
      FailAt(Child(v.key, "min_size"),
             "must not exceed max_size " + Fmt(r.max_size) +
                 " in either component, got " + Fmt(r.min_size));
    }
    const Vec2& size = out_.workspace.size;
    if ((r.max_size.array() > size.array()).any()) {
      FailAt(Child(v.key, "max_size"),
             "must not be larger than the workspace " + Fmt(size) + ", got " +
                 Fmt(r.max_size));
    }
    return r;
  }

  BoxConfig ParseBox(const Value& v) {
    BoxConfig box;
    const Fields f = ReadMap(v, {"center", "size"});
    if (const Value* x = f.Get("center")) box.center = ReadVec2(*x);
    if (const Value* x = f.Get("size")) {
      box.size = ReadVec2(*x, kPositive, "[width, height]");
    }
    return box;
  }

  void ParseRobots(const Value& v) {
    RobotsConfig& r = out_.robots;
    const Fields f = ReadMap(v, {"count", "radius", "step", "start"});
    const Value* count = f.Get("count");
    if (!count) {
      FailAt("robots.count",
             "is required: the number of robots, an integer >= 1");
    }
    r.count = ReadInt(*count, 1);
    if (const Value* x = f.Get("radius")) r.radius = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("step")) r.step = ReadDouble(*x, kPositive);
    if (!(r.radius < r.step / 2)) {
      FailAt("robots.radius", "must be less than half of robots.step (" +
                                  Fmt(r.step / 2) +
                                  ") so that robots on neighbouring lattice "
                                  "points do not touch, got " +
                                  Fmt(r.radius));
    }
    if (const Value* x = f.Get("start")) {
      const std::vector<Value> items = ReadList(*x);
      if (static_cast<int>(items.size()) != r.count) {
        Fail(*x,
             "has " + std::to_string(items.size()) +
                 " positions but robots.count is " + std::to_string(r.count) +
                 "; give one [x, y] per robot, or omit start for random ones");
      }
      for (const Value& item : items) {
        const Vec2 p = ReadVec2(item);
        CheckInsideWorkspace(item, p);
        r.start.push_back(p);
      }
    }
  }

  void ParseSensor(const Value& v) {
    SensorConfig& s = out_.sensor;
    const Fields f = ReadMap(v, {"range", "eta", "sigma0", "line_of_sight"});
    if (const Value* x = f.Get("range")) s.range = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("eta")) s.eta = ReadDouble(*x, kNonNegative);
    if (const Value* x = f.Get("sigma0")) s.sigma0 = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("line_of_sight")) s.line_of_sight = ReadBool(*x);
  }

  void ParseTargets(const Value& v) {
    TargetsConfig& t = out_.targets;
    const Fields f =
        ReadMap(v, {"count", "list", "prior_sigma", "prior_offset"});
    const Value* count = f.Get("count");
    const Value* list = f.Get("list");
    if (count) t.count = ReadInt(*count, 0);
    if (const Value* x = f.Get("prior_sigma"))
      t.prior_sigma = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("prior_offset")) {
      t.prior_offset = ReadDouble(*x, kNonNegative);
    }
    if (list) {
      for (const Value& item : ReadList(*list))
        t.list.push_back(ParseTarget(item));
    }
    if (count && list && t.count != static_cast<int>(t.list.size())) {
      Fail(*count, "is " + std::to_string(t.count) + " but targets.list has " +
                       std::to_string(t.list.size()) +
                       " targets; give count (random targets) or list, or make "
                       "them agree");
    }
    if (out_.NumTargets() == 0) {
      FailAt(
          count  ? "targets.count"
          : list ? "targets.list"
                 : "targets",
          "at least one target is required: give targets.count (random static "
          "targets) or targets.list");
    }
  }

  TargetConfig ParseTarget(const Value& v) {
    TargetConfig t;
    const Fields f = ReadMap(
        v, {"position", "velocity", "prior_mean", "prior_sigma", "dynamics"});
    const Value* position = f.Get("position");
    if (!position) {
      FailAt(Child(v.key, "position"),
             "is required: the target's true position [x, y]");
    }
    t.position = ReadVec2(*position);
    CheckInsideWorkspace(*position, t.position);
    if (const Value* x = f.Get("prior_mean")) t.prior_mean = ReadVec2(*x);
    if (const Value* x = f.Get("prior_sigma"))
      t.prior_sigma = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("dynamics")) t.dynamics = ParseDynamics(*x);
    if (const Value* x = f.Get("velocity")) {
      t.velocity = ReadVec2(*x, kAnyNumber, "[vx, vy]");
      // With a 2-D state the velocity would be silently ignored.
      if (t.dynamics.dim() != 4) {
        Fail(*x,
             "needs 4x4 dynamics.A (state [px, py, vx, vy]); this target's "
             "state "
             "is its position only");
      }
    }
    return t;
  }

  DynamicsConfig ParseDynamics(const Value& v) {
    DynamicsConfig d;
    const Fields f = ReadMap(v, {"A", "b", "q"});
    if (const Value* x = f.Get("A")) {
      d.A = ReadMatrix(*x);
      const std::string got =
          std::to_string(d.A.rows()) + "x" + std::to_string(d.A.cols());
      if (d.A.rows() != d.A.cols()) {
        Fail(*x,
             "must be a square matrix (2x2 for a state [px, py], 4x4 for "
             "[px, py, vx, vy]), got " +
                 std::to_string(d.A.rows()) + " rows of " +
                 std::to_string(d.A.cols()) + " columns");
      }
      if (d.dim() != 2 && d.dim() != 4) {
        Fail(*x,
             "must be 2x2 (state [px, py]) or 4x4 (state [px, py, vx, vy]), "
             "got " +
                 got);
      }
    }
    d.b = Eigen::VectorXd::Zero(d.dim());
    if (const Value* x = f.Get("b")) {
      d.b = ReadVector(*x, static_cast<std::size_t>(d.dim()), kAnyNumber,
                       "(one per row of A)");
    }
    if (const Value* x = f.Get("q")) d.q = ReadDouble(*x, kNonNegative);
    return d;
  }

  void ParseMission(const Value& v) {
    MissionConfig& m = out_.mission;
    const Fields f = ReadMap(v, {"eps", "max_steps", "stop_at_success"});
    if (const Value* x = f.Get("eps")) m.eps = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("max_steps")) m.max_steps = ReadInt(*x, 1);
    if (const Value* x = f.Get("stop_at_success"))
      m.stop_at_success = ReadBool(*x);
  }

  void ParseCommunication(const Value& v) {
    CommunicationConfig& c = out_.communication;
    const Fields f = ReadMap(
        v, {"mode", "range", "kappa_self", "packet_loss_lambda", "failures"});
    if (const Value* x = f.Get("mode")) {
      const std::string mode = ReadString(*x);
      if (mode == "full") {
        c.mode = CommMode::kFull;
      } else if (mode == "range") {
        c.mode = CommMode::kRange;
      } else {
        FailExpected(*x, "full or range");
      }
    }
    if (const Value* x = f.Get("range")) c.range = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("kappa_self")) {
      c.kappa_self = ReadDouble(*x, kHalfOpenUnit);
    }
    if (const Value* x = f.Get("packet_loss_lambda")) {
      c.packet_loss_lambda = ReadDouble(*x, kNonNegative);
    }
    if (const Value* x = f.Get("failures")) {
      for (const Value& item : ReadList(*x))
        c.failures.push_back(ParseFailure(item));
    }
  }

  FailureConfig ParseFailure(const Value& v) {
    FailureConfig failure;
    const Fields f = ReadMap(v, {"robot", "step"});
    if (const Value* x = f.Get("robot")) {
      if (IsPlainScalar(x->node) && x->node.Scalar() == "random") {
        failure.robot = -1;
      } else {
        failure.robot =
            ReadInt(*x, 0, out_.robots.count - 1,
                    "a robot index in " + RobotIndexText() + " or random");
      }
    }
    if (const Value* x = f.Get("step")) failure.step = ReadInt(*x, 0);
    return failure;
  }

  void ParsePolicy(const Value& v) {
    PolicyConfig& p = out_.policy;
    // Open: any other key is a numeric parameter for the planner. The name is
    // checked against the registry by runtime/, at lines["policy.name"].
    const Fields f = ReadMap(v, {"name", "model"}, /*open=*/true);
    for (const auto& [name, x] : f.entries()) {
      if (name == "name") {
        p.name = ReadString(x);
        if (p.name.empty()) FailExpected(x, "a policy name such as greedy");
      } else if (name == "model") {
        p.model = ReadPath(x);
      } else {
        if (!ToDouble(x.node)) {
          FailExpected(x,
                       "a number (keys under policy other than name and model "
                       "are numeric planner parameters)");
        }
        p.params[name] = ReadDouble(x);
      }
    }
  }

  void ParsePhysics(const Value& v) {
    PhysicsConfig& p = out_.physics;
    const Fields f = ReadMap(
        v, {"timestep", "kp", "robot_mass", "tolerance", "step_timeout"});
    if (const Value* x = f.Get("timestep"))
      p.timestep = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("kp")) p.kp = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("robot_mass"))
      p.robot_mass = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("tolerance"))
      p.tolerance = ReadDouble(*x, kPositive);
    if (const Value* x = f.Get("step_timeout")) {
      p.step_timeout = ReadDouble(*x, kPositive);
    }
  }

  void ParseRender(const Value& v) {
    RenderConfig& r = out_.render;
    const Fields f = ReadMap(v, {"width", "height", "fps", "follow_robot"});
    if (const Value* x = f.Get("width")) r.width = ReadInt(*x, 1);
    if (const Value* x = f.Get("height")) r.height = ReadInt(*x, 1);
    if (const Value* x = f.Get("fps")) r.fps = ReadInt(*x, 1);
    if (const Value* x = f.Get("follow_robot")) {
      r.follow_robot =
          ReadInt(*x, -1, out_.robots.count - 1,
                  "-1 (no robot) or a robot index in " + RobotIndexText());
    }
  }

  std::string file_;
  std::string base_dir_;
  Scenario& out_;
};

// The whole file, or an InputError carrying the system's reason.
std::string ReadText(const std::string& path) {
  const auto fail = [&path](int err) {
    return InputError(path, 0, "(file)",
                      std::string("cannot read file: ") + std::strerror(err));
  };
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(
      std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw fail(errno);
  std::string text;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f.get())) > 0)
    text.append(buffer, n);
  // A directory opens but fails to read (EISDIR).
  if (std::ferror(f.get())) throw fail(errno);
  return text;
}

}  // namespace

Scenario LoadScenario(const std::string& path) {
  return ParseScenario(ReadText(path), path,
                       fs::path(path).parent_path().string());
}

Scenario ParseScenario(const std::string& yaml, const std::string& file,
                       const std::string& base_dir) {
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(yaml);
  } catch (const YAML::Exception& e) {
    const bool has_mark = e.mark.line >= 0;
    throw InputError(
        file, has_mark ? e.mark.line + 1 : 0, "(yaml)",
        "invalid YAML: " + e.msg +
            (has_mark ? " (column " + std::to_string(e.mark.column + 1) + ")"
                      : ""));
  }
  // YAML::Load would silently drop every document after the first.
  if (docs.size() > 1) {
    throw InputError(file, LineOfNode(docs[1], 0), "(yaml)",
                     "a scenario file holds one YAML document, found " +
                         std::to_string(docs.size()) + " (separated by ---)");
  }
  Scenario scenario;
  scenario.file = file;
  Parser(file, base_dir, scenario).Parse(docs.empty() ? YAML::Node() : docs[0]);
  return scenario;
}

}  // namespace aia
