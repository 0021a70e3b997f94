#include "aia/commands/catalog.h"

#include <algorithm>

#include "aia/scenario/loader.h"

namespace aia {
namespace {

// Rows as aligned columns: key, type, default, then the meaning.
std::string Columns(const std::vector<FieldDoc>& rows,
                    const std::string& indent) {
  std::size_t key = 3, type = 4, def = 7;
  for (const FieldDoc& r : rows) {
    key = std::max(key, r.key.size());
    type = std::max(type, r.type.size());
    def = std::max(def, r.default_value.size());
  }
  const auto pad = [](const std::string& s, std::size_t w) {
    return s + std::string(w - s.size() + 2, ' ');
  };
  std::string out;
  for (const FieldDoc& r : rows)
    out += indent + pad(r.key, key) + pad(r.type, type) +
           pad(r.default_value, def) + r.doc + "\n";
  return out;
}

}  // namespace

std::string PolicyCatalog(const PolicyRegistry& registry, bool markdown) {
  std::string out;
  for (const PolicyInfo& p : registry.Describe()) {
    const std::string scope = p.centralized ? "centralized" : "distributed";
    if (markdown) {
      out +=
          "### `" + p.name + "` (" + scope + ")\n\n" + p.description + ".\n\n";
      out +=
          p.params.empty() ? "No parameters.\n\n" : FieldTable(p.params) + "\n";
    } else {
      out += p.name + " (" + scope + "): " + p.description + "\n";
      out += p.params.empty() ? "  no parameters\n" : Columns(p.params, "  ");
      out += "\n";
    }
  }
  if (!markdown) {
    out +=
        "Parameters go under the scenario's policy: section (policy: {name: "
        "expert, p_v: 0.8}) or on the command line (--set policy.p_v=0.8).\n";
  }
  return out;
}

std::string ScenarioSchema(bool markdown) {
  const std::vector<FieldDoc> rows = ScenarioKeys();
  return markdown ? FieldTable(rows) : Columns(rows, "");
}

}  // namespace aia
