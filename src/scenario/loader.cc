#include "aia/scenario/loader.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/scenario/yaml.h"

namespace aia {
namespace {

namespace fs = std::filesystem;

// Scenario files larger than this are not scenarios.
constexpr std::uintmax_t kMaxScenarioBytes = 16u << 20;

// The whole file, or an InputError carrying the reason.
std::string ReadText(const std::string& path) {
  try {
    return ReadFile(path, kMaxScenarioBytes);
  } catch (const std::runtime_error& e) {
    throw InputError(path, 0, "(file)", e.what());
  }
}

// One step of a key path: a mapping key or a list index.
struct Step {
  std::string name;  // empty: an index
  std::size_t index = 0;
};

std::string FlagKey(const Override& o, const std::string& key) {
  return o.flag == "--set" ? "--set " + key : o.flag;
}

// A key path: segments NAME[I][J]... joined by dots, NAME
// [A-Za-z_][A-Za-z0-9_]* and each index 1 to 9 digits. Scanned by hand: a
// std::regex overflows the stack on a path of some 30 000 characters.
std::vector<Step> ParsePath(const Override& o) {
  const auto refuse = [&o]() {
    return InputError::Flag(o.flag,
                            "'" + o.path +
                                "' is not a key path such as mission.eps or "
                                "targets.list[0].position");
  };
  const auto letter = [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
  };
  const auto digit = [](char c) { return c >= '0' && c <= '9'; };
  const std::string& p = o.path;
  std::vector<Step> steps;
  std::size_t i = 0;
  while (true) {
    if (i >= p.size() || !letter(p[i])) throw refuse();
    const std::size_t begin = i;
    while (i < p.size() && (letter(p[i]) || digit(p[i]))) ++i;
    steps.push_back({p.substr(begin, i - begin), 0});
    while (i < p.size() && p[i] == '[') {
      const std::size_t first = ++i;
      while (i < p.size() && digit(p[i])) ++i;
      if (i == first || i - first > 9 || i >= p.size() || p[i] != ']')
        throw refuse();
      steps.push_back({"", std::stoul(p.substr(first, i - first))});
      ++i;
    }
    if (i == p.size()) break;
    if (p[i] != '.') throw refuse();
    ++i;
  }
  return steps;
}

// The policy's name in a document, as read (the default when not given).
std::string PolicyName(const ConfigNode& root) {
  const ConfigNode* policy = root.IsMap() ? root.Find("policy") : nullptr;
  const ConfigNode* name =
      policy && policy->IsMap() ? policy->Find("name") : nullptr;
  return name && name->IsScalar() ? name->scalar : PolicyConfig{}.name;
}

void Apply(const Override& o, ConfigNode* root) {
  const std::vector<Step> steps = ParsePath(o);
  ConfigNode value = ParseYamlValue(o.value, o.flag, FlagKey(o, o.path));
  // A new policy drops the parameters the file gave the old one.
  if (o.path == "policy.name" && value.IsScalar() &&
      value.scalar != PolicyName(*root)) {
    if (ConfigNode* policy = root->Find("policy"); policy && policy->IsMap()) {
      std::vector<ConfigNode::Entry> kept;
      for (ConfigNode::Entry& e : policy->entries)
        if (e.key == "name" || e.key == "model" || !e.value.origin.empty())
          kept.push_back(std::move(e));
      policy->entries = std::move(kept);
    }
  }
  ConfigNode* node = root;
  std::string key;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const Step& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (!step.name.empty()) {
      if (node->IsNull()) {
        *node = ConfigNode::Map();
        node->origin = o.flag;
      }
      if (!node->IsMap()) {
        throw InputError::Flag(
            FlagKey(o, o.path),
            (key.empty() ? std::string("the document") : key) +
                " is not a mapping, so it has no key `" + step.name + "`");
      }
      key = ChildKey(key, step.name);
      ConfigNode* child = node->Find(step.name);
      if (last) {
        node->Set(step.name, std::move(value));
        return;
      }
      node = child ? child : &node->Set(step.name, ConfigNode{});
    } else {
      const std::string item = ItemKey(key, step.index);
      if (!node->IsList() || step.index >= node->items.size()) {
        throw InputError::Flag(
            FlagKey(o, o.path),
            node->IsList()
                ? key + " has " + std::to_string(node->items.size()) +
                      " entries, so it has no " + item
            : node->IsNull() ? key + " is not given, so it has no " + item
                             : key + " is not a list, so it has no " + item);
      }
      key = item;
      if (last) {
        node->items[step.index] = std::move(value);
        return;
      }
      node = &node->items[step.index];
    }
  }
}

Scenario Read(const ConfigNode& root, const std::string& file,
              const std::string& base_dir) {
  Scenario scenario;
  ReadOptions options;
  options.file = file;
  options.base_dir = base_dir;
  options.warnings = &scenario.warnings;
  scenario.sources = ReadFields(root, options, "", &scenario);
  scenario.file = file;
  return scenario;
}

std::string Cell(const std::string& text) {
  std::string out;
  for (const char c : text)
    out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

}  // namespace

Override ParseSetFlag(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw InputError::Flag(
        "--set",
        "'" + text + "' is not key.path=value (e.g. --set mission.eps=0.05)");
  }
  Override o{"--set", text.substr(0, eq), text.substr(eq + 1)};
  ParsePath(o);  // reports a malformed path now
  return o;
}

void RefuseUndoing(const Override& o, const std::vector<Override>& before) {
  const std::string key = FlagKey(o, o.path);
  const std::string earlier = o.flag == "--set" ? "--set" : "key";
  for (const Override& b : before) {
    if (b.path == o.path)
      throw InputError::Flag(key, "given twice (=" + b.value +
                                      ", then =" + o.value + "); give it once");
    if (ReplacesSectionOf(o.path, b.path))
      throw InputError::Flag(
          key, "replaces the whole section, and an earlier " + earlier +
                   " gives " + b.path +
                   " in it; give the section once, or its keys one "
                   "by one");
  }
}

std::vector<Override> ParseSetFlags(const std::vector<std::string>& texts) {
  std::vector<Override> out;
  for (const std::string& text : texts) {
    Override o = ParseSetFlag(text);
    RefuseUndoing(o, out);
    out.push_back(std::move(o));
  }
  return out;
}

bool ReplacesSectionOf(const std::string& set_path, const std::string& path) {
  return path.rfind(set_path + ".", 0) == 0;
}

void RefuseSetOfFlagKey(const Override& set, const std::string& path,
                        const std::string& flag) {
  if (set.path == path)
    throw InputError::Flag("--set " + set.path,
                           "is also given by " + flag + "; give one of them");
  if (ReplacesSectionOf(set.path, path))
    throw InputError::Flag(
        "--set " + set.path,
        "replaces the whole section, and " + flag + " gives " + path +
            " in it; set the section's keys one by one (--set " + set.path +
            ".KEY=VALUE) or drop " + flag);
}

Scenario LoadScenario(const std::string& path,
                      const std::vector<Override>& overrides) {
  return ParseScenario(ReadText(path), path,
                       fs::path(path).parent_path().string(), overrides);
}

ScenarioSource ReadScenarioSource(const std::string& path) {
  ScenarioSource source{path, ReadText(path), ""};
  const fs::path dir = fs::path(path).parent_path();
  std::error_code error;
  const fs::path absolute =
      dir.empty() ? fs::current_path(error) : fs::absolute(dir, error);
  if (error) throw InputError(path, 0, "(file)", error.message());
  source.base_dir = absolute.string();
  return source;
}

Scenario LoadScenario(const ScenarioSource& source,
                      const std::vector<Override>& overrides) {
  return ParseScenario(source.yaml, source.file, source.base_dir, overrides);
}

Scenario ParseScenario(const std::string& yaml, const std::string& file,
                       const std::string& base_dir,
                       const std::vector<Override>& overrides) {
  ConfigNode root = ParseYaml(yaml, file);
  // A document that is not a mapping is the file's error, not that of the
  // first flag that sets a key in it.
  if (!root.IsMap() && !root.IsNull() && !overrides.empty())
    Read(root, file, base_dir);
  for (const Override& o : overrides) Apply(o, &root);
  return Read(root, file, base_dir);
}

Scenario WithOverrides(const Scenario& scenario,
                       const std::vector<Override>& overrides) {
  ConfigNode root = ScenarioNode(scenario);
  for (const Override& o : overrides) Apply(o, &root);
  return Read(root, scenario.file, "");
}

ConfigNode ScenarioNode(const Scenario& scenario) {
  return FieldWriter::WriteStruct(scenario);
}

std::string EffectiveYaml(const Scenario& scenario, const std::string& header) {
  return header + EmitYaml(ScenarioNode(scenario));
}

void ReportWarnings(const Scenario& scenario) {
  static std::mutex mu;
  static std::set<std::string> shown;
  const std::lock_guard<std::mutex> lock(mu);
  for (const std::string& w : scenario.warnings)
    if (shown.insert(w).second)
      std::fprintf(stderr, "warning: %s\n", w.c_str());
}

std::vector<FieldDoc> ScenarioKeys() { return FieldDocs::Of(Scenario{}); }

std::string FieldTable(const std::vector<FieldDoc>& rows) {
  std::string out = "| key | type | default | meaning |\n|---|---|---|---|\n";
  for (const FieldDoc& r : rows) {
    const bool word = r.default_value.empty() ||
                      r.default_value == "required" ||
                      r.default_value == "none";
    out += "| `" + Cell(r.key) + "` | " + Cell(r.type) + " | " +
           (word ? r.default_value : "`" + Cell(r.default_value) + "`") +
           " | " + Cell(r.doc) + " |\n";
  }
  return out;
}

}  // namespace aia
