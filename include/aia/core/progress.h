// A progress line on stderr for long jobs (`aia run`, `eval`, `dataset`,
// `train`): redrawn in place, and drawn only when stderr is a terminal, so
// that logs and pipes get only the lines that stay.
#ifndef AIA_CORE_PROGRESS_H_
#define AIA_CORE_PROGRESS_H_

#include <cstddef>
#include <string>

namespace aia {

class ProgressLine {
 public:
  explicit ProgressLine(bool enabled);
  // Redraws the line with `text` (nothing when disabled).
  void Update(const std::string& text);
  // Ends the drawn line, leaving it on screen.
  void Finish();
  // A line that stays, written whether or not stderr is a terminal: it
  // replaces the drawn progress line, if any.
  void Print(const std::string& text);

 private:
  bool enabled_;
  std::size_t last_width_ = 0;
};

}  // namespace aia

#endif  // AIA_CORE_PROGRESS_H_
