// The archives that walk field declarations (core/fields.h):
//   FieldReader  ConfigNode -> struct, strict, with `FILE:LINE: key: what`
//                errors and "did you mean" hints;
//   FieldWriter  struct -> ConfigNode (the effective configuration);
//   FieldDocs    struct -> one row per key (type, default, meaning);
//   FieldFinder  the dotted key of a member, for errors raised later.
// One generic implementation per archive serves every struct: scenarios,
// sensor and communication settings, target dynamics, policy parameters.
#ifndef AIA_CORE_FIELD_IO_H_
#define AIA_CORE_FIELD_IO_H_

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#include "aia/core/check.h"
#include "aia/core/config_node.h"
#include "aia/core/error.h"
#include "aia/core/fields.h"
#include "aia/core/types.h"

namespace aia {

// Where a key of a configuration came from.
struct KeySource {
  int key_line = 0;    // line of the key
  int value_line = 0;  // line of its value (the key's line for an empty one)
  std::string origin;  // "" (the file) or the command-line flag that set it
};
using KeySources = std::map<std::string, KeySource>;

// The InputError about `key` (which need not have been given): blamed on the
// line of the key itself or of its nearest given parent (its value's line
// when `at_value`), or on the command-line flag that set it.
InputError KeyError(const std::string& file, const KeySources& sources,
                    const std::string& key, const std::string& what,
                    bool at_value = false);

// Text helpers shared by the archives.
namespace field_text {
// Whether a decimal literal lies beyond what a double holds.
enum class OutOfRange {
  kNo,
  kTooSmall,  // non-zero, below 4.9e-324 (1e-400): it reads as 0
  kTooLarge,  // beyond 1.8e308 (1e999): it reads as infinite
};
// The value of a plain numeric scalar (YAML 1.2 core schema spellings,
// possibly infinite or NaN); nullopt for anything else. A decimal literal
// too large for a double reads as infinite, one too small as 0, each said in
// *out_of_range.
std::optional<double> ParseReal(const ConfigNode& node,
                                OutOfRange* out_of_range = nullptr);
std::optional<long long> ParseInteger(const ConfigNode& node);
std::optional<std::uint64_t> ParseUnsigned(const ConfigNode& node);
// Shortest text that reads back as exactly `x` ("0.1", "20", "1e-06").
std::string ShortestReal(double x);
// "no", "one", "two", ... for counts in messages.
std::string CountWord(std::size_t n);
std::string Join(const std::vector<std::string>& items,
                 const std::string& separator = ", ");
std::size_t EditDistance(const std::string& a, const std::string& b);
// The closest of `names` to `name` within 2 edits, or "".
std::string ClosestName(const std::string& name,
                        const std::vector<std::string>& names);
// " >= 1", " in (0, 1]", "" for any number: the range after a noun.
std::string RangeSuffix(const NumberRange& range, bool integer);
// Whether `text` is well-formed UTF-8 (no overlong forms or surrogates).
bool IsUtf8(std::string_view text);
// The spellings the parsers above accept, scanned in linear time and
// constant stack (std::regex overflows the stack on long input):
//   IsDecimalLiteral   [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?
//   IsNonFiniteLiteral [-+]?\.?(inf|infinity)|\.?nan, any case
//   IsIntegerLiteral   [-+]?[0-9]+
//   IsYamlWord         true|false|null|yes|no|on|off|y|n|~, any case
bool IsDecimalLiteral(std::string_view text);
bool IsNonFiniteLiteral(std::string_view text);
bool IsIntegerLiteral(std::string_view text);
bool IsYamlWord(std::string_view text);
// "10x10" (separator 'x'), "0/4" ('/'): two counts of 1 to `max_digits`
// digits each around `separator`, and nothing else.
bool ParseCountPair(std::string_view text, char separator,
                    std::size_t max_digits, int* first, int* second);
}  // namespace field_text

namespace internal {

template <typename T>
inline constexpr bool kIsInteger =
    std::is_integral_v<T> && !std::is_same_v<T, bool>;
template <typename T>
inline constexpr bool kIsVec2 = std::is_same_v<T, Eigen::Vector2d>;

// The names of a struct's fields, and whether it keeps unknown keys.
class FieldNames {
 public:
  template <typename T>
  void Visit(const Field<T>& f) {
    if (f.rest) {
      has_rest = true;
    } else {
      names.emplace_back(f.name);
    }
  }
  std::vector<std::string> names;
  bool has_rest = false;
};

template <typename T>
FieldNames NamesOf(T* value) {
  FieldNames names;
  value->Serialize(&names);
  return names;
}

// "a | b | c" with separator " | "; with " or ": "a, b or c".
template <typename E>
std::string EnumChoices(const std::string& separator) {
  std::vector<std::string> names;
  for (const auto& n : EnumNames(E{})) names.emplace_back(n.name);
  if (separator != " or " || names.size() < 3)
    return field_text::Join(names, separator);
  const std::string last = names.back();
  names.pop_back();
  return field_text::Join(names, ", ") + " or " + last;
}

}  // namespace internal

// Finds the dotted key of a member inside a struct.
class FieldFinder {
 public:
  FieldFinder(const void* address, const std::type_info& type)
      : address_(address), type_(&type) {}

  // Searches `root` (found under `key`) and everything below it.
  template <typename T>
  bool Find(T* root, const std::string& key) {
    Check(root, key);
    return found_;
  }
  const std::string& key() const { return key_; }

  template <typename T>
  void Visit(const Field<T>& f) {
    if (!found_ && !f.rest)
      Check(f.value, ChildKey(prefix_, std::string(f.name)));
  }

 private:
  template <typename T>
  void Check(T* v, const std::string& key) {
    if (found_) return;
    if (static_cast<const void*>(v) == address_ && typeid(T) == *type_) {
      key_ = key;
      found_ = true;
      return;
    }
    if constexpr (internal::IsOptional<T>::value) {
      if (v->has_value()) Check(&v->value(), key);
    } else if constexpr (internal::IsVector<T>::value) {
      for (std::size_t i = 0; i < v->size() && !found_; ++i)
        Check(&(*v)[i], ItemKey(key, i));
    } else if constexpr (internal::HasSerialize<T>::value) {
      const std::string saved = prefix_;
      prefix_ = key;
      v->Serialize(this);
      prefix_ = saved;
    }
  }

  const void* address_;
  const std::type_info* type_;
  std::string prefix_, key_;
  bool found_ = false;
};

struct ReadOptions {
  std::string file;      // named in errors
  std::string base_dir;  // relative paths are resolved against it
  // Replaces "unknown key" for mappings read against a fixed set of names
  // (a policy's parameters), e.g. "unknown parameter for policy 'greedy'".
  std::string unknown_key_lead;
  // Where Validate()'s warnings go (FieldChecker::Warn), each "FILE:LINE:
  // key: what"; none kept when null.
  std::vector<std::string>* warnings = nullptr;
};

// Reads typed structs from a ConfigNode, strictly: unknown keys, wrong types
// (a float where an integer is expected, a quoted number, `yes` for a
// boolean), values out of range, missing required keys and empty list
// entries are InputErrors at the offending key and line.
class FieldReader {
 public:
  explicit FieldReader(ReadOptions options) : options_(std::move(options)) {}

  // Reads `node` (a mapping, or empty for all defaults), found under `key`
  // ("" for the whole document), into `value`, then runs its Validate().
  template <typename T>
  void ReadStruct(const ConfigNode& node, const std::string& key, T* value);

  // Every key read so far, with its lines and origin.
  const KeySources& sources() const { return sources_; }

  template <typename T>
  void Visit(const Field<T>& f);

 private:
  template <typename T>
  friend class StructChecker;

  [[noreturn]] void Fail(const ConfigNode& node, const std::string& key,
                         const std::string& what) const;
  [[noreturn]] void FailExpected(const ConfigNode& node, const std::string& key,
                                 const std::string& expected) const {
    Fail(node, key, "must be " + expected + ", got " + ShowNode(node));
  }
  [[noreturn]] void FailUnknownKey(const ConfigNode::Entry& entry,
                                   const std::string& key,
                                   const std::vector<std::string>& names) const;
  // Records a key read from `entry` (or a list item), for later errors.
  void Record(const std::string& key, int key_line, const ConfigNode& value);
  // A relative path from the file is resolved against base_dir; one given
  // by a command-line flag (the node's origin), against the working folder.
  std::string ResolvePath(const ConfigNode& node) const;

  template <typename T>
  void ReadValue(const ConfigNode& node, const std::string& key,
                 const Field<T>& f, T* out);
  // A list of numbers; `size` 0: any length.
  Eigen::VectorXd ReadNumbers(const ConfigNode& node, const std::string& key,
                              std::size_t size, const NumberRange& range,
                              std::string_view shape) const;
  Eigen::MatrixXd ReadMatrix(const ConfigNode& node, const std::string& key,
                             const NumberRange& range) const;
  double ReadReal(const ConfigNode& node, const std::string& key,
                  const NumberRange& range, std::string_view expect) const;
  long long ReadInteger(const ConfigNode& node, const std::string& key,
                        const NumberRange& range, std::string_view expect,
                        std::string_view keyword, long long keyword_value,
                        long long lo, long long hi) const;

  ReadOptions options_;
  KeySources sources_;
  std::map<std::string, const ConfigNode*> nodes_;  // given keys
  const ConfigNode* map_ = nullptr;                 // the mapping being read
  const internal::FieldNames* names_ = nullptr;     // its declared keys
  std::string key_;                                 // its key
};

// FieldChecker of a struct being read: keys by address, lines from the
// reader.
template <typename T>
class StructChecker : public FieldChecker {
 public:
  StructChecker(const FieldReader* reader, T* root, std::string key)
      : reader_(reader), root_(root), key_(std::move(key)) {}

 protected:
  std::string KeyOf(const void* address,
                    const std::type_info& type) const override {
    FieldFinder finder(address, type);
    AIA_CHECK_MSG(finder.Find(root_, key_),
                  "Validate() reported a field outside its struct");
    return finder.key();
  }
  InputError ErrorAt(const std::string& key,
                     const std::string& what) const override {
    return KeyError(reader_->options_.file, reader_->sources_,
                    key.empty() ? "(document)" : key, what,
                    /*at_value=*/true);
  }
  bool GivenKey(const std::string& key) const override {
    return reader_->nodes_.count(key) > 0;
  }
  std::string ShownKey(const std::string& key) const override {
    const auto it = reader_->nodes_.find(key);
    return it == reader_->nodes_.end() ? std::string() : ShowNode(*it->second);
  }
  void WarnAt(const std::string& key, const std::string& what) const override {
    if (reader_->options_.warnings == nullptr) return;
    reader_->options_.warnings->push_back(ErrorAt(key, what).Format());
  }

 private:
  const FieldReader* reader_;
  T* root_;
  std::string key_;
};

template <typename T>
void FieldReader::ReadStruct(const ConfigNode& node, const std::string& key,
                             T* value) {
  static_assert(internal::HasSerialize<T>::value,
                "ReadStruct needs a struct with Serialize()");
  const internal::FieldNames names = internal::NamesOf(value);
  // A section given nothing on the command line (--set mission=) would
  // read as absent, every key at its default: refused, as a key given
  // nothing is. (In a file, `mission:` with nothing under it is an empty
  // section.)
  if ((!node.IsNull() && !node.IsMap()) ||
      (node.IsNull() && !node.origin.empty())) {
    FailExpected(node, key,
                 "a mapping with keys among " + field_text::Join(names.names));
  }
  // Keys first, in document order, so that a misspelt key is reported
  // before the values next to it.
  for (const ConfigNode::Entry& e : node.entries) {
    const std::string child = ChildKey(key, e.key);
    bool known = false;
    for (const std::string& n : names.names) known = known || n == e.key;
    if (!known && !names.has_rest) FailUnknownKey(e, child, names.names);
    Record(child, e.key_line, e.value);
  }
  const ConfigNode* saved_map = map_;
  const internal::FieldNames* saved_names = names_;
  std::string saved_key = std::move(key_);
  map_ = &node;
  names_ = &names;
  key_ = key;
  value->Serialize(this);
  map_ = saved_map;
  names_ = saved_names;
  key_ = std::move(saved_key);
  if constexpr (internal::HasValidate<T>::value) {
    value->Validate(StructChecker<T>(this, value, key));
  }
}

template <typename T>
void FieldReader::Visit(const Field<T>& f) {
  const std::string name(f.name);
  if (f.rest) {
    if constexpr (std::is_same_v<T, ConfigNode>) {
      // The keys no other field declares, as written.
      *f.value = ConfigNode::Map();
      f.value->line = map_->line;
      f.value->origin = map_->origin;
      for (const ConfigNode::Entry& e : map_->entries) {
        bool declared = false;
        for (const std::string& n : names_->names)
          declared = declared || n == e.key;
        if (!declared) f.value->entries.push_back(e);
      }
    } else {
      AIA_CHECK_MSG(false, "Rest() needs a ConfigNode field");
    }
    return;
  }
  const ConfigNode* node = map_->IsMap() ? map_->Find(name) : nullptr;
  const std::string key = ChildKey(key_, name);
  if (node == nullptr) {
    if (!f.required.empty()) {
      throw KeyError(options_.file, sources_, key,
                     "is required: " + std::string(f.required));
    }
    // An absent section still has its required keys and its checks.
    if constexpr (internal::HasSerialize<T>::value) {
      static const ConfigNode kEmpty;
      ReadStruct(kEmpty, key, f.value);
    }
    return;
  }
  ReadValue(*node, key, f, f.value);
}

template <typename T>
void FieldReader::ReadValue(const ConfigNode& node, const std::string& key,
                            const Field<T>& f, T* out) {
  if constexpr (std::is_same_v<T, bool>) {
    if (node.IsPlainScalar() && node.scalar == "true") {
      *out = true;
    } else if (node.IsPlainScalar() && node.scalar == "false") {
      *out = false;
    } else {
      FailExpected(node, key, "true or false");
    }
  } else if constexpr (std::is_same_v<T, std::uint64_t>) {
    // The full unsigned range (seeds).
    const std::optional<std::uint64_t> u = field_text::ParseUnsigned(node);
    if (!u) {
      const std::string expected =
          f.expect.empty() ? "an integer >= 0" : std::string(f.expect);
      if (node.IsPlainScalar() && field_text::IsIntegerLiteral(node.scalar) &&
          node.scalar[0] != '-') {
        Fail(node, key,
             "must be " + expected +
                 " that fits in 64 bits (at most "
                 "18446744073709551615), got " +
                 ShowNode(node));
      }
      FailExpected(node, key, expected);
    }
    *out = *u;
  } else if constexpr (internal::kIsInteger<T>) {
    static_assert(sizeof(T) <= sizeof(long long) && std::is_signed_v<T>);
    *out = static_cast<T>(
        ReadInteger(node, key, f.range, f.expect, f.keyword, f.keyword_value,
                    static_cast<long long>(std::numeric_limits<T>::min()),
                    static_cast<long long>(std::numeric_limits<T>::max())));
  } else if constexpr (std::is_floating_point_v<T>) {
    *out = ReadReal(node, key, f.range, f.expect);
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!node.IsScalar()) FailExpected(node, key, "a string");
    if ((f.non_empty || f.path) && node.scalar.empty()) {
      FailExpected(node, key,
                   !f.expect.empty() ? std::string(f.expect)
                   : f.path          ? std::string("a file path")
                                     : std::string("a non-empty string"));
    }
    if (!field_text::IsUtf8(node.scalar))
      FailExpected(node, key, "text in UTF-8");
    // C's file and text functions end a string at a NUL: "a.pt\0x" would
    // open a.pt, and MuJoCo's XML parser stops there.
    if (node.scalar.find('\0') != std::string::npos)
      Fail(node, key,
           "holds a NUL character (\\0 at character " +
               std::to_string(node.scalar.find('\0') + 1) +
               "); no text may hold one");
    *out = f.path ? ResolvePath(node) : node.scalar;
  } else if constexpr (std::is_enum_v<T>) {
    if (node.IsPlainScalar()) {
      for (const auto& n : EnumNames(T{})) {
        if (node.scalar == n.name) {
          *out = n.value;
          return;
        }
      }
    }
    FailExpected(node, key, internal::EnumChoices<T>(" or "));
  } else if constexpr (internal::kIsVec2<T>) {
    *out = ReadNumbers(node, key, 2, f.range,
                       f.shape.empty() ? std::string_view("[x, y]") : f.shape);
  } else if constexpr (std::is_same_v<T, Eigen::VectorXd>) {
    *out = ReadNumbers(node, key, 0, f.range, f.shape);
  } else if constexpr (std::is_same_v<T, Eigen::MatrixXd>) {
    *out = ReadMatrix(node, key, f.range);
  } else if constexpr (internal::IsOptional<T>::value) {
    using U = typename T::value_type;
    out->emplace();
    ReadValue(node, key, f.template For<U>(&out->value()), &out->value());
  } else if constexpr (internal::IsVector<T>::value) {
    using U = typename T::value_type;
    if (!node.IsList()) FailExpected(node, key, "a list");
    out->clear();
    out->resize(node.items.size());
    for (std::size_t i = 0; i < node.items.size(); ++i) {
      const ConfigNode& item = node.items[i];
      const std::string item_key = ItemKey(key, i);
      Record(item_key, item.line, item);
      // An empty entry (a bare `-`) would otherwise become a default box
      // or failure that nobody asked for.
      if (item.IsNull()) Fail(item, item_key, "list entries must not be empty");
      ReadValue(item, item_key, f.template For<U>(&(*out)[i]), &(*out)[i]);
    }
  } else if constexpr (internal::HasTextForm<T>::value) {
    std::string why;
    std::optional<T> v;
    if (node.IsScalar()) v = T::FromText(node.scalar, &why);
    if (!v) {
      if (why.empty()) FailExpected(node, key, std::string(T::kExpect));
      Fail(node, key, why + ", got " + ShowNode(node));
    }
    *out = *v;
  } else if constexpr (internal::HasSerialize<T>::value) {
    ReadStruct(node, key, out);
  } else if constexpr (std::is_same_v<T, ConfigNode>) {
    *out = node;
  } else {
    static_assert(sizeof(T) == 0, "no reader for this field type");
  }
}

// struct -> ConfigNode: every field, defaults included; nullopt optionals and
// empty paths ("none") are left out, so that the result reads back as the
// same struct.
class FieldWriter {
 public:
  template <typename T>
  void Visit(const Field<T>& f) {
    if (f.rest) {
      if constexpr (std::is_same_v<T, ConfigNode>) {
        for (const ConfigNode::Entry& e : f.value->entries)
          out_.Set(e.key, e.value);
      }
      return;
    }
    std::optional<ConfigNode> node = Write(*f.value, f);
    if (node) out_.Set(std::string(f.name), std::move(*node));
  }

  // The node of a whole struct.
  template <typename T>
  static ConfigNode WriteStruct(const T& value) {
    FieldWriter w;
    w.out_ = ConfigNode::Map();
    const_cast<T&>(value).Serialize(&w);
    return std::move(w.out_);
  }

  // The node of one value with the options of its field; nullopt: not
  // written.
  template <typename T>
  static std::optional<ConfigNode> Write(const T& v, const Field<T>& f) {
    if constexpr (std::is_same_v<T, bool>) {
      return ConfigNode::Scalar(v ? "true" : "false");
    } else if constexpr (internal::kIsInteger<T>) {
      if (!f.keyword.empty() && static_cast<long long>(v) == f.keyword_value)
        return ConfigNode::Scalar(std::string(f.keyword));
      return ConfigNode::Scalar(std::to_string(v));
    } else if constexpr (std::is_floating_point_v<T>) {
      return ConfigNode::Scalar(field_text::ShortestReal(v));
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (f.path && v.empty()) return std::nullopt;
      return ConfigNode::Scalar(v, ConfigNode::Style::kQuoted);
    } else if constexpr (std::is_enum_v<T>) {
      for (const auto& n : EnumNames(T{}))
        if (n.value == v) return ConfigNode::Scalar(n.name);
      AIA_CHECK_MSG(false, "enum value without a name");
    } else if constexpr (internal::kIsVec2<T> ||
                         std::is_same_v<T, Eigen::VectorXd>) {
      ConfigNode list = ConfigNode::List();
      for (Eigen::Index i = 0; i < v.size(); ++i)
        list.items.push_back(
            ConfigNode::Scalar(field_text::ShortestReal(v[i])));
      return list;
    } else if constexpr (std::is_same_v<T, Eigen::MatrixXd>) {
      ConfigNode rows = ConfigNode::List();
      for (Eigen::Index r = 0; r < v.rows(); ++r) {
        ConfigNode row = ConfigNode::List();
        for (Eigen::Index c = 0; c < v.cols(); ++c)
          row.items.push_back(
              ConfigNode::Scalar(field_text::ShortestReal(v(r, c))));
        rows.items.push_back(std::move(row));
      }
      return rows;
    } else if constexpr (internal::IsOptional<T>::value) {
      using U = typename T::value_type;
      if (!v.has_value()) return std::nullopt;
      return Write<U>(*v, f.template For<U>(nullptr));
    } else if constexpr (internal::IsVector<T>::value) {
      using U = typename T::value_type;
      ConfigNode list = ConfigNode::List();
      for (const U& item : v) {
        std::optional<ConfigNode> n =
            Write<U>(item, f.template For<U>(nullptr));
        if (n) list.items.push_back(std::move(*n));
      }
      return list;
    } else if constexpr (internal::HasTextForm<T>::value) {
      return ConfigNode::Scalar(v.ToText());
    } else if constexpr (internal::HasSerialize<T>::value) {
      return WriteStruct(v);
    } else if constexpr (std::is_same_v<T, ConfigNode>) {
      return v;
    } else {
      static_assert(sizeof(T) == 0, "no writer for this field type");
    }
  }

 private:
  ConfigNode out_;
};

// One documented key.
struct FieldDoc {
  std::string key;            // "targets.list[i].dynamics.q"
  std::string type;           // "number >= 0"
  std::string default_value;  // "0", "required", "none"
  std::string doc;
};

// One row per key of a struct, nested structs and list items included
// (items as `key[i]`), in declaration order.
class FieldDocs {
 public:
  template <typename T>
  static std::vector<FieldDoc> Of(const T& defaults,
                                  const std::string& prefix = "") {
    FieldDocs d;
    d.prefix_ = prefix;
    const_cast<T&>(defaults).Serialize(&d);
    return std::move(d.rows_);
  }

  // "number in [0, 1]", "integer >= 1", "[x, y]", "list of mappings", ...
  template <typename T>
  static std::string TypeText(const Field<T>& f) {
    if constexpr (std::is_same_v<T, bool>) {
      return "true or false";
    } else if constexpr (internal::kIsInteger<T>) {
      NumberRange r = f.range;
      if (std::is_unsigned_v<T> && r.lo < 0) r.lo = 0;
      std::string t = "integer" + field_text::RangeSuffix(r, true);
      if (!f.keyword.empty()) t += " or " + std::string(f.keyword);
      return t;
    } else if constexpr (std::is_floating_point_v<T>) {
      return "number" + field_text::RangeSuffix(f.range, false);
    } else if constexpr (std::is_same_v<T, std::string>) {
      return f.path ? "path" : "string";
    } else if constexpr (std::is_enum_v<T>) {
      return internal::EnumChoices<T>(" | ");
    } else if constexpr (internal::kIsVec2<T>) {
      std::string t = f.shape.empty() ? "[x, y]" : std::string(f.shape);
      if (f.range.lo != kAnyNumber.lo || f.range.hi != kAnyNumber.hi)
        t += ", " + f.range.Describe(true);
      return t;
    } else if constexpr (std::is_same_v<T, Eigen::VectorXd>) {
      return "list of numbers";
    } else if constexpr (std::is_same_v<T, Eigen::MatrixXd>) {
      return "matrix, a list of rows";
    } else if constexpr (internal::IsOptional<T>::value) {
      using U = typename T::value_type;
      return TypeText<U>(f.template For<U>(nullptr));
    } else if constexpr (internal::IsVector<T>::value) {
      using U = typename T::value_type;
      if constexpr (internal::HasSerialize<U>::value) {
        return "list of mappings";
      } else {
        return "list of " + TypeText<U>(f.template For<U>(nullptr));
      }
    } else if constexpr (internal::HasTextForm<T>::value) {
      return std::string(T::kForm);
    } else if constexpr (internal::HasSerialize<T>::value) {
      return "mapping";
    } else {
      return "parameters";
    }
  }

  template <typename T>
  void Visit(const Field<T>& f) {
    const std::string key = ChildKey(prefix_, std::string(f.name));
    if (f.rest) {
      rows_.push_back({ChildKey(prefix_, "<parameter>"), "parameters", "",
                       std::string(f.doc)});
      return;
    }
    if constexpr (internal::HasSerialize<T>::value) {
      Nested(*f.value, key);  // a section: its keys only, no row of its own
      return;
    }
    FieldDoc row{key, TypeText(f), DefaultText(f), std::string(f.doc)};
    if constexpr (internal::IsOptional<T>::value) {
      using U = typename T::value_type;
      if constexpr (internal::HasSerialize<U>::value) {
        rows_.push_back(std::move(row));
        Nested(U{}, key);
        return;
      }
    } else if constexpr (internal::IsVector<T>::value) {
      using U = typename T::value_type;
      if constexpr (internal::HasSerialize<U>::value) {
        rows_.push_back(std::move(row));
        Nested(U{}, key + "[i]");
        return;
      }
    }
    rows_.push_back(std::move(row));
  }

 private:
  template <typename T>
  static std::string DefaultText(const Field<T>& f) {
    if (!f.required.empty()) return "required";
    if constexpr (internal::IsOptional<T>::value) {
      if (!f.value->has_value())
        return f.unset.empty() ? "none" : std::string(f.unset);
    }
    if constexpr (std::is_same_v<T, std::string>) {
      if (f.path && f.value->empty()) return "none";
      return f.value->empty() ? "\"\"" : *f.value;
    }
    const std::optional<ConfigNode> node = FieldWriter::Write(*f.value, f);
    if (!node) return "none";
    return ShowNode(*node, 200);
  }

  template <typename U>
  void Nested(const U& value, const std::string& key) {
    const std::string saved = prefix_;
    prefix_ = key;
    const_cast<U&>(value).Serialize(this);
    prefix_ = saved;
  }

  std::string prefix_;
  std::vector<FieldDoc> rows_;
};

// Reads a whole struct from `node` (see FieldReader), returning the keys'
// sources.
template <typename T>
KeySources ReadFields(const ConfigNode& node, const ReadOptions& options,
                      const std::string& key, T* value) {
  FieldReader reader(options);
  reader.ReadStruct(node, key, value);
  return reader.sources();
}

// Command-line flags declared by a struct's fields: the flag of key
// "a.stem_stride" is "--stem-stride" (its last name, '-' for '_').
std::string FlagName(std::string_view key);
// Marks every value below `node` (a mapping) as set by its key's flag.
void SetFlagOrigins(ConfigNode* node);

// Checks a struct whose fields were set from command-line flags against
// their declarations (ranges, types, Validate()): it is written and read
// back with each key standing for its flag, so that an error reads
// `command line: --flag: what`, as for the scenario's keys.
template <typename T>
void CheckFlags(T* value) {
  ConfigNode node = FieldWriter::WriteStruct(*value);
  SetFlagOrigins(&node);
  ReadFields(node, ReadOptions{"command line", "", ""}, "", value);
}

// The names of a struct's own fields whose value differs from `unset`'s (as
// written: a nested struct counts as one field), in declaration order.
template <typename T>
std::vector<std::string> ChangedFields(const T& value, const T& unset) {
  const ConfigNode a = FieldWriter::WriteStruct(value);
  const ConfigNode b = FieldWriter::WriteStruct(unset);
  std::vector<std::string> changed;
  for (const ConfigNode::Entry& e : a.entries) {
    const ConfigNode* other = b.Find(e.key);
    if (other == nullptr || !SameValue(e.value, *other))
      changed.push_back(e.key);
  }
  for (const ConfigNode::Entry& e : b.entries)
    if (a.Find(e.key) == nullptr) changed.push_back(e.key);
  return changed;
}

}  // namespace aia

#endif  // AIA_CORE_FIELD_IO_H_
