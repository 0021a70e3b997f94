// YAML text <-> ConfigNode. The only place that knows YAML: everything else
// reads and writes ConfigNode trees (core/config_node.h).
#ifndef AIA_SCENARIO_YAML_H_
#define AIA_SCENARIO_YAML_H_

#include <string>

#include "aia/core/config_node.h"

namespace aia {

// Parses one YAML document. InputError (at `file` and the line) for invalid
// YAML, more than one document, duplicate keys, keys that are not names, or
// a document that expands (through aliases) to more than a million nodes.
ConfigNode ParseYaml(const std::string& text, const std::string& file);

// Parses the value of a command-line flag (`--set key=[1, 2]`): one YAML
// value in UTF-8; every node gets `flag` as its origin. Errors name `key`
// ("--set mission.eps"), or `flag` when it is empty.
ConfigNode ParseYamlValue(const std::string& text, const std::string& flag,
                          const std::string& key = "");

// YAML text for a tree: block mappings, short lists and mappings of scalars
// in flow style, strings quoted where YAML would read them otherwise.
// ParseYaml(EmitYaml(n)) gives n back (lines aside).
std::string EmitYaml(const ConfigNode& node);

}  // namespace aia

#endif  // AIA_SCENARIO_YAML_H_
