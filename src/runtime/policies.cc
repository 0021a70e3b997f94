#include "aia/runtime/policies.h"

#include "aia/learning/igbnet_policy.h"

namespace aia {

PolicyRegistry AllPolicies() {
  PolicyRegistry registry = BuiltinPolicies();
  AddLearnedPolicies(&registry);
  return registry;
}

}  // namespace aia
