// CSV rows declared once. A row struct lists its columns in one function,
// in file order, and the header, the writer and the reader all walk that
// list, so that a column cannot be added to one and forgotten in another:
//
//   struct EvalRow {
//     std::string size;
//     int flowtime = -1;
//     double wall_s = 0.0;
//     template <typename C>
//     void Columns(C* c) {
//       c->Column("size", &size);
//       c->Column("flowtime", &flowtime, CsvFormat::EmptyIs(-1));
//       c->Column("wall_s", &wall_s, CsvFormat::Fixed(4));
//     }
//   };
//
// Cells: integers in decimal (an unsigned one never negative), booleans as
// 0 or 1, reals with a fixed number of decimals or significant digits (or
// the shortest text that reads back exactly), strings as they are
// (non-empty, no comma, quote or line break: the rows hold names, not
// text). A reader takes whole cells only: "12abc" is not 12. The exact line
// (ExactLine) is the same row, space-separated, every real in the shortest
// text that reads back exactly (NaN as "nan"): for files a program reads
// back, such as a checkpoint's log.
#ifndef AIA_CORE_CSV_H_
#define AIA_CORE_CSV_H_

#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace aia {

struct CsvFormat {
  int digits = -1;                    // reals: decimals; -1: see below
  int significant = -1;               // reals: significant digits (%g)
  bool nan_empty = false;             // reals: NaN is an empty cell
  std::optional<long long> empty_is;  // integers: the value an empty cell is
  static CsvFormat Fixed(int decimals, bool nan_empty = false) {
    return {decimals, -1, nan_empty, std::nullopt};
  }
  static CsvFormat Significant(int digits) {
    return {-1, digits, false, std::nullopt};
  }
  static CsvFormat EmptyIs(long long value) { return {-1, -1, false, value}; }
};

namespace csv_internal {

std::string FormatReal(double v, const CsvFormat& f, bool exact);
// The whole cell as a number, or nullopt.
std::optional<long long> ParseInteger(const std::string& cell);
std::optional<std::uint64_t> ParseUnsigned(const std::string& cell);
std::optional<double> ParseReal(const std::string& cell);
// The line's cells (a trailing comma makes an empty last cell).
std::vector<std::string> SplitCells(const std::string& line, char separator);

class HeaderWriter {
 public:
  template <typename T>
  void Column(const char* name, T*, CsvFormat = {}) {
    if (!text.empty()) text += ',';
    text += name;
  }
  std::string text;
};

class CellWriter {
 public:
  CellWriter(char separator, bool exact)
      : separator_(separator), exact_(exact) {}
  template <typename T>
  void Column(const char*, T* value, CsvFormat f = {}) {
    if (!first_) text += separator_;
    first_ = false;
    if constexpr (std::is_same_v<T, bool>) {
      text += *value ? "1" : "0";
    } else if constexpr (std::is_integral_v<T>) {
      if (exact_ ||
          !(f.empty_is && static_cast<long long>(*value) == *f.empty_is))
        text += std::to_string(*value);
    } else if constexpr (std::is_floating_point_v<T>) {
      text += FormatReal(*value, f, exact_);
    } else {
      static_assert(std::is_same_v<T, std::string>, "a CSV column type");
      text += *value;
    }
  }
  std::string text;

 private:
  char separator_;
  bool exact_;
  bool first_ = true;
};

class CellReader {
 public:
  explicit CellReader(std::vector<std::string> cells)
      : cells_(std::move(cells)) {}
  template <typename T>
  void Column(const char*, T* value, CsvFormat f = {}) {
    if (next_ >= cells_.size()) {
      ok_ = false;
      return;
    }
    const std::string& cell = cells_[next_++];
    if constexpr (std::is_same_v<T, bool>) {
      if (cell == "0" || cell == "1")
        *value = cell == "1";
      else
        ok_ = false;
    } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
      const auto v = ParseUnsigned(cell);
      if (v && *v <= static_cast<std::uint64_t>(~T{0}))
        *value = static_cast<T>(*v);
      else
        ok_ = false;
    } else if constexpr (std::is_integral_v<T>) {
      if (cell.empty() && f.empty_is) {
        *value = static_cast<T>(*f.empty_is);
        return;
      }
      const auto v = ParseInteger(cell);
      if (v && *v >= static_cast<long long>(std::numeric_limits<T>::min()) &&
          *v <= static_cast<long long>(std::numeric_limits<T>::max()))
        *value = static_cast<T>(*v);
      else
        ok_ = false;
    } else if constexpr (std::is_floating_point_v<T>) {
      if (cell.empty() && f.nan_empty) {
        *value = std::numeric_limits<T>::quiet_NaN();
        return;
      }
      const auto v = ParseReal(cell);
      if (v)
        *value = static_cast<T>(*v);
      else
        ok_ = false;
    } else {
      static_assert(std::is_same_v<T, std::string>, "a CSV column type");
      if (cell.empty()) ok_ = false;
      *value = cell;
    }
  }
  bool ok() const { return ok_ && next_ == cells_.size(); }

 private:
  std::vector<std::string> cells_;
  std::size_t next_ = 0;
  bool ok_ = true;
};

}  // namespace csv_internal

// "size,seed,..." (no line break).
template <typename Row>
std::string CsvHeader() {
  csv_internal::HeaderWriter w;
  Row().Columns(&w);
  return w.text;
}

// The row's cells, with a line break.
template <typename Row>
std::string CsvLine(const Row& row) {
  csv_internal::CellWriter w(',', /*exact=*/false);
  const_cast<Row&>(row).Columns(&w);
  return w.text + "\n";
}

// Reads a line (without its line break) into *row; false when it is not a
// row of this layout (another count of cells, a cell that does not parse).
template <typename Row>
bool ParseCsvLine(const std::string& line, Row* row) {
  csv_internal::CellReader r(csv_internal::SplitCells(line, ','));
  row->Columns(&r);
  return r.ok();
}

// The exact line: space-separated, reals that read back exactly, with a
// line break; and back.
template <typename Row>
std::string ExactLine(const Row& row) {
  csv_internal::CellWriter w(' ', /*exact=*/true);
  const_cast<Row&>(row).Columns(&w);
  return w.text + "\n";
}
template <typename Row>
bool ParseExactLine(const std::string& line, Row* row) {
  csv_internal::CellReader r(csv_internal::SplitCells(line, ' '));
  row->Columns(&r);
  return r.ok();
}

}  // namespace aia

#endif  // AIA_CORE_CSV_H_
