#include "aia/core/csv.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "aia/core/field_io.h"

namespace aia {
namespace csv_internal {

std::string FormatReal(double v, const CsvFormat& f, bool exact) {
  if (exact) return std::isnan(v) ? "nan" : field_text::ShortestReal(v);
  if (f.nan_empty && std::isnan(v)) return "";
  char buf[64];
  if (f.digits >= 0) {
    std::snprintf(buf, sizeof buf, "%.*f", f.digits, v);
  } else if (f.significant > 0) {
    std::snprintf(buf, sizeof buf, "%.*g", f.significant, v);
  } else {
    return field_text::ShortestReal(v);
  }
  return buf;
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
  if (cell.empty() || std::isspace(static_cast<unsigned char>(cell[0])))
    return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  if (end != cell.c_str() + cell.size()) return std::nullopt;
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
