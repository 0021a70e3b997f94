// libFuzzer: scenario YAML -> Scenario. Every input either loads or is an
// InputError; a crash, a sanitizer report or any other exception is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "aia/core/error.h"
#include "aia/scenario/loader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const aia::Scenario s =
        aia::ParseScenario(text, "fuzz.yaml", AIA_FUZZ_BASE_DIR);
    // The effective scenario reads back (what effective.yaml promises).
    const std::string yaml = aia::EffectiveYaml(s, "");
    aia::ParseScenario(yaml, "effective.yaml", AIA_FUZZ_BASE_DIR);
  } catch (const aia::InputError&) {
  }
  return 0;
}
