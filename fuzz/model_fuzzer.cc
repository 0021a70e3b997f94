// libFuzzer: bytes as a model file (TorchScript zip) -> IgbNet::Load. A file
// that is not a model, or whose tensors do not match its metadata, is an
// InputError; nothing else escapes.
#include <cstddef>
#include <cstdint>

#include "aia/core/error.h"
#include "aia/learning/network.h"
#include "fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const aia::fuzz::TempFile file(data, size, ".pt");
  try {
    aia::IgbNet::Load(file.path(), "fuzz.yaml", 1, "policy.model");
  } catch (const aia::InputError&) {
  }
  return 0;
}
