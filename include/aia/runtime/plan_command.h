// `aia plan`: the expert alone on a scenario's initial state: its plan, F*,
// solve time, nodes grown and peak memory.
#ifndef AIA_RUNTIME_PLAN_COMMAND_H_
#define AIA_RUNTIME_PLAN_COMMAND_H_

#include <optional>
#include <string>

#include "aia/planning/sampling_tree.h"
#include "aia/runtime/mission.h"

namespace aia {

struct PlanOptions {
  std::string scenario_path;
  ScenarioOverrides overrides;  // --seed
  std::optional<long> budget;   // anytime iterations after the first goal
  std::string out;              // plan.json path; empty: none
};

// The expert's plan from the initial state of a scenario (step 0: the prior
// fused with the first measurements), with the scenario's expert parameters
// (the policy: keys, whatever policy the scenario names) and the seed's
// "policy.expert" stream.
SamplingPlan PlanFromStart(const Scenario& scenario,
                           std::optional<long> budget = {});

// Peak resident memory of this process so far, in MiB.
double PeakRssMiB();

int RunPlanCommand(const PlanOptions& options);

}  // namespace aia

#endif  // AIA_RUNTIME_PLAN_COMMAND_H_
