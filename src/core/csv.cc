#include "aia/core/csv.h"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include "aia/core/check.h"
#include "aia/core/field_io.h"

namespace aia {
namespace csv_internal {

// std::to_chars and from_chars, not printf and strtod: the same digits as
// printf's in the C locale, whatever the process's LC_NUMERIC (a Python
// program's other thread that set a comma-decimal locale while
// aia.evaluate ran had the rows written with commas, which failed their
// own check and ended the process).
std::string FormatReal(double v, const CsvFormat& f, bool exact) {
  if (exact) return std::isnan(v) ? "nan" : field_text::ShortestReal(v);
  if (f.nan_empty && std::isnan(v)) return "";
  char buf[400];  // fixed: up to 309 digits before the point
  std::to_chars_result r;
  if (f.digits >= 0) {
    r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed,
                      f.digits);
  } else if (f.significant > 0) {
    r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general,
                      f.significant);
  } else {
    return field_text::ShortestReal(v);
  }
  AIA_CHECK(r.ec == std::errc());
  return std::string(buf, r.ptr);
}

std::optional<long long> ParseInteger(const std::string& cell) {
  const std::size_t start = !cell.empty() && cell[0] == '-' ? 1 : 0;
  if (cell.size() == start || cell.size() - start > 18) return std::nullopt;
  for (std::size_t i = start; i < cell.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(cell[i]))) return std::nullopt;
  return std::stoll(cell);
}

std::optional<std::uint64_t> ParseUnsigned(const std::string& cell) {
  if (cell.empty() || cell.size() > 20) return std::nullopt;
  for (char c : cell)
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
  errno = 0;
  const unsigned long long v = std::strtoull(cell.c_str(), nullptr, 10);
  if (errno == ERANGE) return std::nullopt;
  return static_cast<std::uint64_t>(v);
}

std::optional<double> ParseReal(const std::string& cell) {
  const char* begin = cell.data();
  const char* const last = cell.data() + cell.size();
  const bool plus = begin != last && *begin == '+';  // strtod's sign
  if (plus) ++begin;                                 // (from_chars: '-' only)
  if (begin == last || *begin == '+' || (plus && *begin == '-') ||
      std::isspace(static_cast<unsigned char>(*begin)))
    return std::nullopt;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(begin, last, v);
  if (end != last) return std::nullopt;
  if (ec == std::errc::result_out_of_range) {
    // Beyond the doubles: strtod's answer (inf, or 0 and the subnormals),
    // which has no decimal point to misread but where it has one.
    return std::strtod(cell.c_str(), nullptr);
  }
  if (ec != std::errc()) return std::nullopt;
  return v;
}

std::vector<std::string> SplitCells(const std::string& line, char separator) {
  std::vector<std::string> cells(1);
  for (char c : line) {
    if (c == separator)
      cells.emplace_back();
    else
      cells.back() += c;
  }
  return cells;
}

}  // namespace csv_internal
}  // namespace aia
