#include "aia/core/field_values.h"

#include <limits>

#include "aia/core/field_io.h"

namespace aia {

std::optional<TeamSize> TeamSize::FromText(std::string_view text,
                                           std::string* why) {
  TeamSize s;
  if (!field_text::ParseCountPair(text, 'x', 5, &s.robots, &s.targets))
    return std::nullopt;
  if (s.robots < 1 || s.targets < 1) {
    *why = "robots and targets must be >= 1";
    return std::nullopt;
  }
  return s;
}

std::string TeamSize::ToText() const {
  return std::to_string(robots) + "x" + std::to_string(targets);
}

std::optional<Shard> Shard::FromText(std::string_view text, std::string* why) {
  Shard s;
  if (!field_text::ParseCountPair(text, '/', 4, &s.index, &s.count))
    return std::nullopt;
  if (s.index >= s.count) {
    *why = "need 0 <= K < N";
    return std::nullopt;
  }
  return s;
}

std::string Shard::ToText() const {
  return std::to_string(index) + "/" + std::to_string(count);
}

std::string SeedRangeProblem(std::uint64_t first, long long count,
                             std::string_view count_flag,
                             std::string_view first_flag) {
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  if (count < 1) return "";
  const std::uint64_t last = static_cast<std::uint64_t>(count - 1);
  if (last <= kMax - first) return "";
  return "seeds " + std::to_string(first) + " .. " + std::to_string(first) +
         " + " + std::to_string(last) +
         " do not fit in 64 bits (the largest seed is " + std::to_string(kMax) +
         "); with " + std::string(count_flag) + " " + std::to_string(count) +
         ", " + std::string(first_flag) + " must be at most " +
         std::to_string(kMax - last);
}

}  // namespace aia
