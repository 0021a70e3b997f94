// The explicit policy registry: name -> declared parameters and factory, as
// OMPL's planners declare theirs (`declareParam`). No static
// self-registration (linkers drop unreferenced objects from static
// libraries); higher layers (learning) add their policies with Add().
//
// Each policy's parameters are a struct that declares its fields once
// (core/fields.h): typed, range-checked, with defaults and docs. Resolve()
// reads the scenario's `policy:` keys into it, with the usual
// `FILE:LINE: key: what` errors, and returns a PolicySpec: the checked
// parameters and any shared resource (a learned model), ready to make one
// policy per episode without loading anything again.
#ifndef AIA_PLANNING_REGISTRY_H_
#define AIA_PLANNING_REGISTRY_H_

#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "aia/core/field_io.h"
#include "aia/core/hash.h"
#include "aia/planning/policy.h"
#include "aia/scenario/config.h"

namespace aia {

// A policy as `aia policies` lists it.
struct PolicyInfo {
  std::string name;
  std::string description;
  bool centralized = false;
  std::vector<FieldDoc> params;  // keys "policy.<param>"
};

// A policy with checked parameters (and its loaded resource), shared
// read-only by the episodes that use it.
class PolicySpec {
 public:
  PolicySpec(std::string name, bool centralized)
      : name_(std::move(name)), centralized_(centralized) {}
  virtual ~PolicySpec() = default;

  const std::string& name() const { return name_; }
  bool centralized() const { return centralized_; }
  // A fresh policy for one episode.
  virtual std::unique_ptr<Policy> Create() const = 0;
  // Every parameter with its value, defaults included (for effective.yaml).
  virtual ConfigNode Params() const = 0;
  // The file a learned policy's model was loaded from (its absolute path and
  // SHA-256), recorded in effective.yaml; nullptr for other policies.
  const FileIdentity* model_file() const {
    return model_file_.path.empty() ? nullptr : &model_file_;
  }
  void set_model_file(FileIdentity file) { model_file_ = std::move(file); }

 private:
  std::string name_;
  bool centralized_;
  FileIdentity model_file_;
};

// A policy without parameters declares this.
struct NoParams {
  template <typename Archive>
  void Serialize(Archive*) {}
};

class PolicyRegistry {
 public:
  template <typename Params>
  using Factory = std::function<std::unique_ptr<Policy>(const Params&)>;
  template <typename Params, typename Resource>
  using Loader = std::function<std::shared_ptr<const Resource>(
      const Params&, const Scenario&)>;
  template <typename Params, typename Resource>
  using ResourceFactory = std::function<std::unique_ptr<Policy>(
      const Params&, std::shared_ptr<const Resource>)>;

  // The policy class P (a NamedPolicy: its name and whether it is
  // centralized come from P) with parameters the struct `Params`.
  template <typename P, typename Params>
  void Add(const std::string& description, Factory<Params> make);

  // A policy that also needs a shared, read-only resource (a learned model):
  // `load` runs once per Resolve() (once per process for a command), and
  // every policy Create()d from the spec shares what it returned. Its model
  // file is the scenario's policy.model (and policy.model_sha256), listed
  // first among its parameters with `default_model` as the default.
  template <typename P, typename Params, typename Resource>
  void Add(const std::string& description, const std::string& default_model,
           Loader<Params, Resource> load,
           ResourceFactory<Params, Resource> make);

  bool Has(const std::string& name) const;
  std::vector<std::string> Names() const;
  // "random, greedy, ..." for messages.
  std::string NameList() const;
  // "unknown policy 'grdy' (did you mean `greedy`?) (valid: ...)".
  std::string UnknownPolicy(const std::string& name) const;
  std::vector<PolicyInfo> Describe() const;

  // The scenario's policy with its parameters read and checked: an unknown
  // policy name (at policy.name, listing the valid ones), an unknown
  // parameter or a value out of range is an InputError at its key's line.
  std::shared_ptr<const PolicySpec> Resolve(const Scenario& scenario) const;

 private:
  struct Entry {
    PolicyInfo info;
    std::function<std::shared_ptr<const PolicySpec>(const Scenario&)> resolve;
  };
  void Put(Entry entry);

  // policy.model and policy.model_sha256 as PolicyConfig declares them.
  static std::vector<FieldDoc> ModelFieldDocs(const std::string& default_model);
  template <typename Params>
  static Params ReadParams(const std::string& name, const Scenario& scenario);

  std::vector<Entry> entries_;
};

// random, greedy, expert, decsb.
PolicyRegistry BuiltinPolicies();

// --- Implementation ---------------------------------------------------------

namespace internal {

// Whether a resource says which file it was loaded from (`file()`).
template <typename R, typename = void>
struct HasFileIdentity : std::false_type {};
template <typename R>
struct HasFileIdentity<
    R, std::enable_if_t<std::is_same_v<
           decltype(std::declval<const R&>().file()), const FileIdentity&>>>
    : std::true_type {};

template <typename P>
class TypedPolicySpec : public PolicySpec {
 public:
  using Make = std::function<std::unique_ptr<Policy>(const P&)>;
  TypedPolicySpec(std::string name, bool centralized, P params, Make make)
      : PolicySpec(std::move(name), centralized),
        params_(std::move(params)),
        make_(std::move(make)) {}
  std::unique_ptr<Policy> Create() const override { return make_(params_); }
  ConfigNode Params() const override {
    return FieldWriter::WriteStruct(params_);
  }
  const P& params() const { return params_; }

 private:
  const P params_;
  Make make_;
};

}  // namespace internal

// A spec's checked parameters, when they are a P (else nullptr).
template <typename P>
const P* ParamsOf(const PolicySpec& spec) {
  const auto* typed = dynamic_cast<const internal::TypedPolicySpec<P>*>(&spec);
  return typed ? &typed->params() : nullptr;
}

template <typename Params>
Params PolicyRegistry::ReadParams(const std::string& name,
                                  const Scenario& scenario) {
  Params params;
  ReadOptions options;
  options.file = scenario.ErrorFile();
  options.unknown_key_lead = "unknown parameter for policy '" + name + "'";
  ReadFields(scenario.policy.params, options, "policy", &params);
  return params;
}

template <typename P, typename Params>
void PolicyRegistry::Add(const std::string& description, Factory<Params> make) {
  const std::string name(P::kName);
  const bool centralized = IsCentralizedPolicy<P>::value;
  Entry e;
  e.info = {name, description, centralized, FieldDocs::Of(Params{}, "policy")};
  e.resolve = [name, centralized,
               make](const Scenario& s) -> std::shared_ptr<const PolicySpec> {
    return std::make_shared<internal::TypedPolicySpec<Params>>(
        name, centralized, ReadParams<Params>(name, s), make);
  };
  Put(std::move(e));
}

template <typename P, typename Params, typename Resource>
void PolicyRegistry::Add(const std::string& description,
                         const std::string& default_model,
                         Loader<Params, Resource> load,
                         ResourceFactory<Params, Resource> make) {
  const std::string name(P::kName);
  const bool centralized = IsCentralizedPolicy<P>::value;
  Entry e;
  e.info = {name, description, centralized, ModelFieldDocs(default_model)};
  for (FieldDoc& d : FieldDocs::Of(Params{}, "policy"))
    e.info.params.push_back(std::move(d));
  e.resolve = [name, centralized, load,
               make](const Scenario& s) -> std::shared_ptr<const PolicySpec> {
    const Params params = ReadParams<Params>(name, s);
    std::shared_ptr<const Resource> resource = load(params, s);
    auto spec = std::make_shared<internal::TypedPolicySpec<Params>>(
        name, centralized, params,
        [make, resource](const Params& p) { return make(p, resource); });
    if constexpr (internal::HasFileIdentity<Resource>::value)
      spec->set_model_file(resource->file());
    return spec;
  };
  Put(std::move(e));
}

}  // namespace aia

#endif  // AIA_PLANNING_REGISTRY_H_
