#include "aia/core/progress.h"

#include <unistd.h>

#include <cstdio>

namespace aia {

ProgressLine::ProgressLine(bool enabled)
    : enabled_(enabled && ::isatty(STDERR_FILENO)) {}

void ProgressLine::Update(const std::string& text) {
  if (!enabled_) return;
  std::string line = "\r" + text;
  if (text.size() < last_width_)
    line += std::string(last_width_ - text.size(), ' ');
  last_width_ = text.size();
  std::fputs(line.c_str(), stderr);
  std::fflush(stderr);
}

void ProgressLine::Finish() {
  if (enabled_ && last_width_ > 0) std::fputs("\n", stderr);
  last_width_ = 0;
}

void ProgressLine::Print(const std::string& text) {
  if (enabled_) {
    Update(text);
    Finish();
    return;
  }
  std::fputs((text + "\n").c_str(), stderr);
}

}  // namespace aia
