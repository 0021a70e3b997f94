#include "aia/runtime/policies.h"

#include <mutex>
#include <vector>

#include "aia/learning/igbnet_policy.h"

namespace aia {
namespace {

std::mutex g_mutex;
std::vector<PolicyAdder>& Adders() {
  static std::vector<PolicyAdder> adders;
  return adders;
}

}  // namespace

void RegisterPolicies(PolicyAdder add) {
  std::lock_guard<std::mutex> lock(g_mutex);
  Adders().push_back(add);
}

PolicyRegistry AllPolicies() {
  PolicyRegistry registry = BuiltinPolicies();
  AddLearnedPolicies(&registry);
  std::lock_guard<std::mutex> lock(g_mutex);
  for (PolicyAdder add : Adders()) add(&registry);
  return registry;
}

}  // namespace aia
