// libFuzzer: PGM/PNG bytes -> decoded map -> obstacle boxes. A bad image is
// a std::invalid_argument with a reason; nothing else may escape.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "aia/world/world.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const aia::GrayImage img = aia::DecodeMapImage(bytes);
    const auto boxes =
        aia::BoxesFromImage(img.pixels, img.cols, img.rows,
                            aia::Vec2(20.0, 20.0), 0.5, aia::kMaxBodies);
    for (const aia::Box& b : boxes)
      if (!(b.lo.x() <= b.hi.x() && b.lo.y() <= b.hi.y())) __builtin_trap();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
