// `aia plan`: the expert alone on a scenario's initial state: its plan, F*,
// solve time, nodes grown and peak memory.
#ifndef AIA_COMMANDS_PLAN_COMMAND_H_
#define AIA_COMMANDS_PLAN_COMMAND_H_

#include <optional>
#include <string>

#include "aia/core/fields.h"
#include "aia/planning/expert.h"
#include "aia/planning/sampling_tree.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"

namespace aia {

struct PlanOptions {
  std::string scenario_path;
  // --seed and --set; the policy is the expert (its parameters: the file's
  // when the file names the expert, else the defaults, then --set policy.*).
  CommandOverrides overrides;
  std::optional<long> budget;  // anytime iterations after the first goal
  std::string out;             // plan.json path; empty: none

  // --budget, declared once.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(AIA_FIELD(budget)
                 .In(Between(0, kMaxAnytime))
                 .Doc("anytime budget: sampling iterations after the first "
                      "goal (default: the expert's policy.anytime)"));
  }
};

// The expert's plan from the initial state of an instance (step 0: the prior
// fused with the first measurements), on the seed's "policy.expert" stream.
SamplingPlan PlanFromStart(std::shared_ptr<const Instance> instance,
                           const ExpertParams& params,
                           std::optional<long> budget = {});

// Peak resident memory of this process so far, in MiB.
double PeakRssMiB();

int RunPlanCommand(const PlanOptions& options);

}  // namespace aia

#endif  // AIA_COMMANDS_PLAN_COMMAND_H_
