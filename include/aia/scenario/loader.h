// Scenario YAML -> Scenario, with strict validation (SPEC section 10). Every
// problem is an InputError naming the file, the line and the dotted key.
// Geometric checks that need the generated world (a start inside an
// obstacle, more robots than free lattice points) happen in world/.
#ifndef AIA_SCENARIO_LOADER_H_
#define AIA_SCENARIO_LOADER_H_

#include <string>

#include "aia/scenario/config.h"

namespace aia {

// Reads and validates a scenario file. Relative paths inside it (the map,
// the model) are resolved against the file's directory.
Scenario LoadScenario(const std::string& path);

// The same from YAML text; `file` is used in error messages and `base_dir`
// to resolve relative paths.
Scenario ParseScenario(const std::string& yaml, const std::string& file,
                       const std::string& base_dir);

}  // namespace aia

#endif  // AIA_SCENARIO_LOADER_H_
