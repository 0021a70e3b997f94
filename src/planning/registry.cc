#include "aia/planning/registry.h"

#include "aia/core/error.h"
#include "aia/planning/decsb.h"
#include "aia/planning/expert.h"
#include "aia/planning/greedy.h"
#include "aia/planning/random_policy.h"

namespace aia {

void PolicyRegistry::Add(const std::string& name,
                         const std::string& description,
                         PolicyFactory factory) {
  for (auto& e : entries_) {
    if (e.name == name) {
      e.description = description;
      e.factory = std::move(factory);
      return;
    }
  }
  entries_.push_back({name, description, std::move(factory)});
}

bool PolicyRegistry::Has(const std::string& name) const {
  for (const auto& e : entries_)
    if (e.name == name) return true;
  return false;
}

std::unique_ptr<Policy> PolicyRegistry::Create(const std::string& name,
                                               const Scenario& scenario) const {
  for (const auto& e : entries_)
    if (e.name == name) return e.factory(scenario);
  throw InputError(scenario.file, scenario.LineOf("policy.name"), "policy.name",
                   "unknown policy '" + name + "' (valid: " + NameList() + ")");
}

std::vector<std::string> PolicyRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& e : entries_) names.push_back(e.name);
  return names;
}

std::string PolicyRegistry::Description(const std::string& name) const {
  for (const auto& e : entries_)
    if (e.name == name) return e.description;
  return {};
}

std::string PolicyRegistry::NameList() const {
  std::string out;
  for (const auto& e : entries_) out += (out.empty() ? "" : ", ") + e.name;
  return out;
}

PolicyRegistry BuiltinPolicies() {
  PolicyRegistry r;
  r.Add("random", "a uniformly random valid move per robot (Random-Walker)",
        [](const Scenario& s) { return std::make_unique<RandomPolicy>(s); });
  r.Add("greedy",
        "one-step largest drop of the robot's own log det, else BFS to the "
        "nearest unlocalized target",
        [](const Scenario& s) { return std::make_unique<GreedyPolicy>(s); });
  r.Add("expert",
        "C-SB: centralized sampling-based tree over the team and the "
        "centralized filter",
        [](const Scenario& s) { return std::make_unique<ExpertPolicy>(s); });
  r.Add("decsb",
        "Dec-SB: one receding-horizon sampling tree per robot on its own DKF "
        "belief",
        [](const Scenario& s) { return std::make_unique<DecSbPolicy>(s); });
  return r;
}

}  // namespace aia
