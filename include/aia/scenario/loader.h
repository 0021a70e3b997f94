// Scenario YAML -> Scenario, with strict validation (docs/scenarios.md), and
// back: the effective scenario (defaults filled in, overrides applied) as
// YAML. Every problem is an InputError naming the file, the line and the
// dotted key, or the command-line flag. Geometric checks that need the
// generated world (a start inside an obstacle, more robots than free lattice
// points) happen in world/.
#ifndef AIA_SCENARIO_LOADER_H_
#define AIA_SCENARIO_LOADER_H_

#include <string>
#include <vector>

#include "aia/core/field_io.h"
#include "aia/scenario/config.h"

namespace aia {

// One change to a scenario from the command line, applied to the document
// before it is read, so that it is checked like the file's own values.
struct Override {
  std::string flag;   // what errors name: "--set", "--seed", "--policy", ...
  std::string path;   // dotted key path, e.g. "targets.list[0].position"
  std::string value;  // a YAML value, e.g. "0.05" or "[30, 30]"
};

// `--set key.path=value` -> Override; InputError naming --set when the text
// has no '=' or the path is not a key path.
Override ParseSetFlag(const std::string& text);
// Every --set, in order, each checked by RefuseUndoing.
std::vector<Override> ParseSetFlags(const std::vector<std::string>& texts);
// InputError when `o` gives a key one of `before` gives, or a section after
// a key in it: the later would silently undo the earlier, where a key given
// twice in a file is an error (--set flags, Python's overrides).
void RefuseUndoing(const Override& o, const std::vector<Override>& before);

// Whether an override of `set_path` replaces a whole section holding the
// key `path` (mission holds mission.max_steps).
bool ReplacesSectionOf(const std::string& set_path, const std::string& path);

// InputError when `set` (a --set override) gives `path`, which the flag
// `flag` gives too: the same key, or a section holding it, which --set
// would replace with the flag's value lost. Either way one would silently
// win, so neither is guessed.
void RefuseSetOfFlagKey(const Override& set, const std::string& path,
                        const std::string& flag);

// Reads and validates a scenario file with the overrides applied in order.
// Relative paths inside it (the map, the model) are resolved against the
// file's directory. A change of policy.name drops the file's parameters
// (they belong to the policy it named) but keeps those set on the command
// line.
Scenario LoadScenario(const std::string& path,
                      const std::vector<Override>& overrides = {});

// A scenario file read once: its text, its name as errors give it, and the
// directory its relative paths are resolved against, made absolute. For
// callers that build the scenario again and again (Python's resets): those
// builds see neither an edit of the file nor a change of the working
// directory since.
struct ScenarioSource {
  std::string file, yaml, base_dir;
};
ScenarioSource ReadScenarioSource(const std::string& path);
Scenario LoadScenario(const ScenarioSource& source,
                      const std::vector<Override>& overrides = {});

// The same from YAML text; `file` is used in error messages and `base_dir`
// to resolve relative paths.
Scenario ParseScenario(const std::string& yaml, const std::string& file,
                       const std::string& base_dir,
                       const std::vector<Override>& overrides = {});

// A scenario (built in code, or loaded) with overrides applied: it is
// written as a document, changed and read back, so that it and the
// overrides are checked as in a file (also when there are none).
Scenario WithOverrides(const Scenario& scenario,
                       const std::vector<Override>& overrides);

// Prints the scenario's warnings (Scenario::warnings) to stderr, each as
// "warning: FILE:LINE: key: what" and each text once per process (an
// evaluation reads a scenario per world). Thread-safe.
void ReportWarnings(const Scenario& scenario);

// Every key of the scenario with its value, defaults included.
ConfigNode ScenarioNode(const Scenario& scenario);

// The effective scenario as YAML (effective.yaml): `header` (comment lines)
// then every key. LoadScenario() reads it back to the same scenario.
std::string EffectiveYaml(const Scenario& scenario, const std::string& header);

// One row per scenario key: type, default and meaning (docs/scenarios.md,
// `aia schema`).
std::vector<FieldDoc> ScenarioKeys();

// Markdown table of field docs: | key | type | default | meaning |.
std::string FieldTable(const std::vector<FieldDoc>& rows);

}  // namespace aia

#endif  // AIA_SCENARIO_LOADER_H_
