// Settings declared once per field, after Drake's name-value pairs: a struct
// that is read from a configuration lists its fields in one Serialize()
// function, each with its key (the member's own name), its allowed values and
// a line of documentation; the default is the member's initializer.
//
//   struct SensorModel {
//     double range = 2.0;
//     template <typename Archive>
//     void Serialize(Archive* a) {
//       a->Visit(AIA_FIELD(range).In(kPositive).Doc("metres"));
//     }
//     void Validate(const FieldChecker& c);  // optional: relations
//   };
//
// Archives (core/field_io.h) walk these declarations to read a ConfigNode
// with `error: FILE:LINE: key: what` messages, to write the effective
// configuration back, to document every key, and to find a field's key for
// an error raised later. A struct may add `void Validate(const FieldChecker&)`
// for checks across its fields (or dependent defaults); readers call it after
// the fields are read.
#ifndef AIA_CORE_FIELDS_H_
#define AIA_CORE_FIELDS_H_

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#include "aia/core/error.h"

namespace aia {

// Allowed values of a number, open or closed at either end.
struct NumberRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;

  constexpr bool Contains(double x) const {
    return (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
  // "positive number", "numbers in (0, 1]", ... (without an article).
  std::string Describe(bool plural = false) const;
  // "an integer >= 1", "an integer in [0, 10]".
  std::string DescribeInteger() const;
};

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
inline constexpr NumberRange kAnyNumber{};
inline constexpr NumberRange kPositive{0.0, kInfinity, true, false};
inline constexpr NumberRange kNonNegative{0.0, kInfinity, false, false};
inline constexpr NumberRange kOpenUnit{0.0, 1.0, true, true};       // (0, 1)
inline constexpr NumberRange kHalfOpenUnit{0.0, 1.0, true, false};  // (0, 1]
inline constexpr NumberRange kUnit{0.0, 1.0, false, false};         // [0, 1]
constexpr NumberRange AtLeast(double lo) { return {lo, kInfinity}; }
constexpr NumberRange Between(double lo, double hi) { return {lo, hi}; }

// One declared field: its key, where its value lives, and how it is checked
// and documented. Built by AIA_FIELD(member) and refined with the chainable
// setters.
template <typename T>
struct Field {
  Field(std::string_view field_name, T* field_value)
      : name(field_name), value(field_value) {}

  std::string_view name;
  T* value;
  std::string_view doc;
  // Numbers: the value's range; vectors, lists and matrices: each entry's.
  NumberRange range;
  // How a vector's entries read in messages and docs, e.g. "[x, y]".
  std::string_view shape;
  // Non-empty: the key must be given; says what it is, for the message
  // "is required: <required>".
  std::string_view required;
  // Replaces the generic description of the allowed values in messages.
  std::string_view expect;
  // Optional fields: the default docs show when none is given, where that
  // is a value the reader takes ("reserve"); "none" when empty.
  std::string_view unset;
  // Integers: a word accepted in place of `keyword_value` ("random").
  std::string_view keyword;
  long long keyword_value = 0;
  bool path = false;       // strings: a file path, made absolute
  bool non_empty = false;  // strings: "" is not allowed
  bool rest = false;  // a ConfigNode that collects the mapping's other keys

  Field& Doc(std::string_view text) {
    doc = text;
    return *this;
  }
  Field& In(NumberRange r) {
    range = r;
    return *this;
  }
  Field& Shape(std::string_view text) {
    shape = text;
    return *this;
  }
  Field& Required(std::string_view what) {
    required = what;
    return *this;
  }
  Field& Expect(std::string_view text) {
    expect = text;
    return *this;
  }
  Field& Unset(std::string_view text) {
    unset = text;
    return *this;
  }
  Field& Keyword(std::string_view word, long long stands_for) {
    keyword = word;
    keyword_value = stands_for;
    return *this;
  }
  // A file path: relative paths are resolved against the configuration
  // file's directory; an empty path means "none" and is not written back.
  Field& Path() {
    path = true;
    return *this;
  }
  Field& NonEmpty() {
    non_empty = true;
    return *this;
  }
  Field& Rest() {
    rest = true;
    return *this;
  }

  // The same options for another value (an item of a list, the value of an
  // optional).
  template <typename U>
  Field<U> For(U* other) const {
    Field<U> f(name, other);
    f.doc = doc;
    f.range = range;
    f.shape = shape;
    f.expect = expect;
    f.keyword = keyword;
    f.keyword_value = keyword_value;
    f.path = path;
    f.non_empty = non_empty;
    return f;
  }
};

// Declares the member `m` as the field with key "m".
#define AIA_FIELD(m) \
  ::aia::Field<std::remove_reference_t<decltype(m)>>(#m, &(m))

// Enumerations are read and written by name: a type E declares its names
// with a function found by argument-dependent lookup,
//   constexpr std::array<EnumName<E>, N> EnumNames(E) { return {...}; }
template <typename E>
struct EnumName {
  E value;
  const char* name;
};

// The name `value` is declared with (the first, when it has several).
template <typename E>
const char* EnumNameOf(E value) {
  for (const auto& n : EnumNames(E{}))
    if (n.value == value) return n.name;
  return "?";
}
// The value declared as `text`; false (and *value unchanged) for any other
// text.
template <typename E>
bool ParseEnumName(std::string_view text, E* value) {
  for (const auto& n : EnumNames(E{})) {
    if (text == n.name) {
      *value = n.value;
      return true;
    }
  }
  return false;
}

// What Validate() functions use to report a field: the reader knows each
// field's key, the line it came from and how it was written.
class FieldChecker {
 public:
  virtual ~FieldChecker() = default;

  // Throws the InputError of `field` (a member of the struct being
  // validated, or of one inside it): its key, and its line in the file.
  template <typename F>
  [[noreturn]] void Fail(const F& field, const std::string& what) const {
    throw ErrorAt(KeyOf(&field, typeid(F)), what);
  }
  // Whether the configuration gave the field (else it has its default).
  template <typename F>
  bool Given(const F& field) const {
    return GivenKey(KeyOf(&field, typeid(F)));
  }
  // The field as written (`[25.0, 1.0]`); "" when it was not given.
  template <typename F>
  std::string Shown(const F& field) const {
    return ShownKey(KeyOf(&field, typeid(F)));
  }
  // Its dotted key, e.g. "robots.start[1]".
  template <typename F>
  std::string Key(const F& field) const {
    return KeyOf(&field, typeid(F));
  }
  // Notes a problem that does not stop the read, e.g. a key given a value
  // that nothing uses where it stands: the reader keeps it as "FILE:LINE:
  // key: what" (ReadOptions::warnings) for the command to print.
  template <typename F>
  void Warn(const F& field, const std::string& what) const {
    WarnAt(KeyOf(&field, typeid(F)), what);
  }

 protected:
  virtual std::string KeyOf(const void* address,
                            const std::type_info& type) const = 0;
  virtual InputError ErrorAt(const std::string& key,
                             const std::string& what) const = 0;
  virtual bool GivenKey(const std::string& key) const = 0;
  virtual std::string ShownKey(const std::string& key) const = 0;
  virtual void WarnAt(const std::string& key,
                      const std::string& what) const = 0;
};

// A number as messages show it: up to 12 significant digits ("0.1", "20").
std::string FormatNumber(double x);
// "[x, y]" with FormatNumber.
std::string FormatPair(double x, double y);

namespace internal {

// Detects T::Serialize(Archive*) without naming an archive.
struct AnyArchive {
  template <typename T>
  void Visit(const Field<T>&) {}
};
template <typename T, typename = void>
struct HasSerialize : std::false_type {};
template <typename T>
struct HasSerialize<T, std::void_t<decltype(std::declval<T&>().Serialize(
                           std::declval<AnyArchive*>()))>> : std::true_type {};

template <typename T, typename = void>
struct HasValidate : std::false_type {};
template <typename T>
struct HasValidate<T, std::void_t<decltype(std::declval<T&>().Validate(
                          std::declval<const FieldChecker&>()))>>
    : std::true_type {};

// Detects a value written as one token (core/field_values.h).
template <typename T, typename = void>
struct HasTextForm : std::false_type {};
template <typename T>
struct HasTextForm<
    T, std::void_t<decltype(T::FromText(std::declval<std::string_view>(),
                                        std::declval<std::string*>()))>>
    : std::true_type {};

template <typename T>
struct IsOptional : std::false_type {};
template <typename U>
struct IsOptional<std::optional<U>> : std::true_type {};

template <typename T>
struct IsVector : std::false_type {};
template <typename U>
struct IsVector<std::vector<U>> : std::true_type {};

}  // namespace internal
}  // namespace aia

#endif  // AIA_CORE_FIELDS_H_
