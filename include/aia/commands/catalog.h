// `aia policies` and `aia schema`: what can be configured, generated from the
// declarations themselves (each policy's parameters, each scenario key), as
// text for the terminal or as the Markdown tables of docs/scenarios.md.
#ifndef AIA_COMMANDS_CATALOG_H_
#define AIA_COMMANDS_CATALOG_H_

#include <string>

#include "aia/planning/registry.h"

namespace aia {

// Every registered policy: name, scope (distributed or centralized),
// description and parameters (type, default, meaning).
std::string PolicyCatalog(const PolicyRegistry& registry, bool markdown);

// Every scenario key: type, default, meaning.
std::string ScenarioSchema(bool markdown);

}  // namespace aia

#endif  // AIA_COMMANDS_CATALOG_H_
