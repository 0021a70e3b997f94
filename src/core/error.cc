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

InputError InputError::Flag(std::string flag, std::string what) {
  return InputError("command line", 0, std::move(flag), std::move(what));
}

std::string InputError::Format() const {
  std::string out = file_;
  if (line_ > 0) out += ":" + std::to_string(line_);
  out += ": ";
  if (!key_.empty()) out += key_ + ": ";
  out += message_;
  return OneLine(out);
}

namespace {

// The length of the well-formed UTF-8 sequence at text[i] (a byte of 0x80
// or more), or 0 where none starts there (RFC 3629: no overlong forms, no
// surrogates, nothing past U+10FFFF).
std::size_t Utf8Length(const std::string& text, std::size_t i) {
  const auto at = [&](std::size_t k) {
    return k < text.size() ? static_cast<unsigned char>(text[k]) : 0u;
  };
  const unsigned lead = at(i);
  std::size_t n = 0;
  unsigned lo = 0x80, hi = 0xbf;  // the second byte's range
  if (lead >= 0xc2 && lead <= 0xdf) {
    n = 2;
  } else if (lead >= 0xe0 && lead <= 0xef) {
    n = 3;
    if (lead == 0xe0) lo = 0xa0;
    if (lead == 0xed) hi = 0x9f;
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    n = 4;
    if (lead == 0xf0) lo = 0x90;
    if (lead == 0xf4) hi = 0x8f;
  } else {
    return 0;
  }
  if (at(i + 1) < lo || at(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (at(i + k) < 0x80 || at(i + k) > 0xbf) return 0;
  return n;
}

}  // namespace

std::string OneLine(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const auto u = static_cast<unsigned char>(c);
    // Bytes that are not UTF-8 (a path or value in another encoding) are
    // shown as escapes, as control characters are: never raw on a terminal.
    const std::size_t utf8 = u >= 0x80 ? Utf8Length(text, i) : 0;
    if (utf8 > 0) {
      out.append(text, i, utf8);
      i += utf8 - 1;
    } else if (u >= 0x20 && u < 0x7f) {
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
