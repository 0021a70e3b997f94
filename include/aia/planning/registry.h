// The explicit policy registry: name -> factory. No static self-registration
// (linkers drop unreferenced objects from static libraries); higher layers
// (learning) add their policies with Add().
#ifndef AIA_PLANNING_REGISTRY_H_
#define AIA_PLANNING_REGISTRY_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "aia/planning/policy.h"
#include "aia/scenario/config.h"

namespace aia {

// Builds a policy for a scenario; may throw InputError for bad policy
// parameters (citing the scenario's file and line).
using PolicyFactory = std::function<std::unique_ptr<Policy>(const Scenario&)>;

class PolicyRegistry {
 public:
  void Add(const std::string& name, const std::string& description,
           PolicyFactory factory);
  bool Has(const std::string& name) const;
  // Throws InputError naming the valid policies when `name` is unknown
  // (file and line of `policy.name` in the scenario when it came from there).
  std::unique_ptr<Policy> Create(const std::string& name,
                                 const Scenario& scenario) const;
  std::vector<std::string> Names() const;
  std::string Description(const std::string& name) const;
  // "random, greedy, ..." for messages.
  std::string NameList() const;

 private:
  struct Entry {
    std::string name;
    std::string description;
    PolicyFactory factory;
  };
  std::vector<Entry> entries_;
};

// random, greedy (and later expert, decsb).
PolicyRegistry BuiltinPolicies();

}  // namespace aia

#endif  // AIA_PLANNING_REGISTRY_H_
