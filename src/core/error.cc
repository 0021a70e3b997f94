#include "aia/core/error.h"

#include <utility>

namespace aia {

InputError::InputError(std::string file, int line, std::string key,
                       std::string what)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + key + ": " +
                         what),
      file_(std::move(file)),
      line_(line),
      key_(std::move(key)),
      message_(std::move(what)) {}

std::string InputError::Format() const {
  std::string out = file_;
  if (line_ > 0) out += ":" + std::to_string(line_);
  out += ": ";
  if (!key_.empty()) out += key_ + ": ";
  out += message_;
  return OneLine(out);
}

std::string OneLine(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else {
      static const char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[u >> 4];
      out += kHex[u & 15];
    }
  }
  return out;
}

}  // namespace aia
