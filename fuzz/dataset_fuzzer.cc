// libFuzzer: bytes as a dataset shard (SQLite) -> ReadDataset. A file that
// is not a dataset of this format is an InputError; nothing else escapes.
#include <cstddef>
#include <cstdint>

#include "aia/core/error.h"
#include "aia/learning/dataset.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const aia::fuzz::TempFile file(data, size, ".sqlite");
  try {
    aia::ReadDataset({file.path()}, "--data");
  } catch (const aia::InputError&) {
  }
  return 0;
}
