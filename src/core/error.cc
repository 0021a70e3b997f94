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
  return out;
}

}  // namespace aia
