// Errors for bad input. Every user-facing error names the file, the line and
// the key at fault so that it prints as `error: FILE:LINE: key: what is wrong`.
#ifndef AIA_CORE_ERROR_H_
#define AIA_CORE_ERROR_H_

#include <stdexcept>
#include <string>

namespace aia {

// Thrown for bad input (scenario files, map images, model files, flags).
// Caught in tools/, printed with Format() and turned into exit code 2.
class InputError : public std::runtime_error {
 public:
  // `line` is 1-based; 0 when no line applies (e.g. a command-line flag).
  InputError(std::string file, int line, std::string key, std::string what);

  // A bad command-line flag (or a value a flag gave): file "command line",
  // no line, the flag as the key.
  static InputError Flag(std::string flag, std::string what);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }
  const std::string& message() const { return message_; }

  // "FILE:LINE: key: what" (or "FILE: key: what" when line is 0), on one
  // line (OneLine).
  std::string Format() const;

 private:
  std::string file_;
  int line_;
  std::string key_;
  std::string message_;
};

// `text` with its control characters written as escapes (\n, \t, \x00):
// an error is one line however odd the input it quotes (a file name, a
// parser's message quoting a byte).
std::string OneLine(const std::string& text);

}  // namespace aia

#endif  // AIA_CORE_ERROR_H_
