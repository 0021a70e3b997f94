// Values a field holds as one token of text, which the archives
// (core/field_io.h) and the command-line flags read and write as they do
// numbers:
//   TeamSize  "10x10": robots x targets of a generated world;
//   Shard     "0/4": the share K of N that one process writes.
// Such a type has
//   static constexpr std::string_view kForm;    // its form in docs
//   static constexpr std::string_view kExpect;  // "a size ... such as 10x10"
//   static std::optional<T> FromText(std::string_view text, std::string* why);
//   std::string ToText() const;                 // reads back as the value
// FromText returns nullopt for text not of the form (why left empty: the
// reader says `must be <kExpect>, got ...`) or of the form with values out of
// range (why says what is wrong).
#ifndef AIA_CORE_FIELD_VALUES_H_
#define AIA_CORE_FIELD_VALUES_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace aia {

struct TeamSize {
  int robots = 1;
  int targets = 1;

  static constexpr std::string_view kForm = "ROBOTSxTARGETS";
  static constexpr std::string_view kExpect =
      "a size ROBOTSxTARGETS such as 10x10";
  // Counts of 1 to 5 decimal digits, each at least 1.
  static std::optional<TeamSize> FromText(std::string_view text,
                                          std::string* why);
  std::string ToText() const;  // "10x10"

  friend bool operator==(const TeamSize& a, const TeamSize& b) {
    return a.robots == b.robots && a.targets == b.targets;
  }
  friend bool operator!=(const TeamSize& a, const TeamSize& b) {
    return !(a == b);
  }
};

struct Shard {
  int index = 0;  // K
  int count = 1;  // N

  static constexpr std::string_view kForm = "K/N";
  static constexpr std::string_view kExpect = "K/N such as 0/4";
  // Counts of 1 to 4 decimal digits with 0 <= K < N.
  static std::optional<Shard> FromText(std::string_view text, std::string* why);
  std::string ToText() const;  // "0/4"

  friend bool operator==(const Shard& a, const Shard& b) {
    return a.index == b.index && a.count == b.count;
  }
};

// "" when the seeds first .. first + count - 1 fit in 64 bits; else what is
// wrong, for the flag of `first`: "seeds F .. F + n do not fit in 64 bits
// (...); with --seeds N, --seed-base must be at most M".
std::string SeedRangeProblem(std::uint64_t first, long long count,
                             std::string_view count_flag,
                             std::string_view first_flag);

}  // namespace aia

#endif  // AIA_CORE_FIELD_VALUES_H_
