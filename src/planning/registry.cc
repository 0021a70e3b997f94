#include "aia/planning/registry.h"

#include <atomic>

#include "aia/core/error.h"
#include "aia/planning/decsb.h"
#include "aia/planning/expert.h"
#include "aia/planning/greedy.h"
#include "aia/planning/random_policy.h"

namespace aia {

std::uint64_t NewKnowledgeStamp() {
  static std::atomic<std::uint64_t> last{0};
  return last.fetch_add(1, std::memory_order_relaxed) + 1;
}

std::string_view PolicyStatusName(PolicyStatus status) {
  switch (status) {
    case PolicyStatus::kOk:
      return "ok";
    case PolicyStatus::kNoValidMove:
      return "no_valid_move";
    case PolicyStatus::kBudgetExhausted:
      return "budget_exhausted";
  }
  return "unknown";
}

void PolicyRegistry::Put(Entry entry) {
  for (Entry& e : entries_) {
    if (e.info.name == entry.info.name) {
      e = std::move(entry);
      return;
    }
  }
  entries_.push_back(std::move(entry));
}

std::vector<FieldDoc> PolicyRegistry::ModelFieldDocs(
    const std::string& default_model) {
  std::vector<FieldDoc> docs;
  for (FieldDoc& d : FieldDocs::Of(PolicyConfig{}, "policy")) {
    if (d.key == "policy.model") d.default_value = default_model;
    if (d.key == "policy.model" || d.key == "policy.model_sha256")
      docs.push_back(std::move(d));
  }
  return docs;
}

bool PolicyRegistry::Has(const std::string& name) const {
  for (const Entry& e : entries_)
    if (e.info.name == name) return true;
  return false;
}

std::vector<std::string> PolicyRegistry::Names() const {
  std::vector<std::string> names;
  for (const Entry& e : entries_) names.push_back(e.info.name);
  return names;
}

std::string PolicyRegistry::NameList() const {
  return field_text::Join(Names());
}

std::vector<PolicyInfo> PolicyRegistry::Describe() const {
  std::vector<PolicyInfo> out;
  for (const Entry& e : entries_) out.push_back(e.info);
  return out;
}

std::shared_ptr<const PolicySpec> PolicyRegistry::Resolve(
    const Scenario& scenario) const {
  const std::string& name = scenario.policy.name;
  for (const Entry& e : entries_)
    if (e.info.name == name) return e.resolve(scenario);
  throw scenario.ErrorAt("policy.name", UnknownPolicy(name));
}

std::string PolicyRegistry::UnknownPolicy(const std::string& name) const {
  std::string what = "unknown policy '" + name + "'";
  const std::string closest = field_text::ClosestName(name, Names());
  if (!closest.empty()) what += " (did you mean `" + closest + "`?)";
  return what + " (valid: " + NameList() + ")";
}

PolicyRegistry BuiltinPolicies() {
  PolicyRegistry r;
  r.Add<RandomPolicy, NoParams>(
      "a uniformly random valid move per robot (Random-Walker)",
      [](const NoParams&) { return std::make_unique<RandomPolicy>(); });
  r.Add<GreedyPolicy, NoParams>(
      "one-step largest drop of the robot's own log det, else a shortest path "
      "to the nearest unlocalized target",
      [](const NoParams&) { return std::make_unique<GreedyPolicy>(); });
  r.Add<ExpertPolicy, ExpertParams>(
      "C-SB: centralized sampling-based tree over the team and the "
      "centralized filter",
      [](const ExpertParams& p) { return std::make_unique<ExpertPolicy>(p); });
  r.Add<DecSbPolicy, DecSbParams>(
      "Dec-SB: one receding-horizon sampling tree per robot on its own DKF "
      "belief",
      [](const DecSbParams& p) { return std::make_unique<DecSbPolicy>(p); });
  return r;
}

}  // namespace aia
