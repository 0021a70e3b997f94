#include "aia/commands/plan_command.h"

#include <sys/resource.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/io.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/outputs.h"
#include "aia/scenario/loader.h"

namespace aia {

double PeakRssMiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux reports KiB
}

SamplingPlan PlanFromStart(std::shared_ptr<const Instance> instance,
                           const ExpertParams& params,
                           std::optional<long> budget) {
  // The plan is made on the state at step 0, which no policy has touched.
  const std::uint64_t seed = instance->scenario.seed;
  const Episode episode(std::move(instance));
  SamplingParams sampling = params;
  if (budget) sampling.anytime = *budget;
  SamplingTree tree;
  Rng rng(seed, "policy.expert");
  return tree.Solve(ExpertProblem(episode.Context()), sampling, rng);
}

namespace {

// The scenario written next to the plan: DIR/NAME.effective.yaml for
// DIR/NAME.json ("" without --out). Neither it nor the plan may replace an
// input; checked before the solve.
std::string CheckPlanOutputs(const PlanOptions& o,
                             const PreparedMission& mission) {
  if (o.out.empty()) return "";
  const std::filesystem::path out(o.out);
  const std::string side =
      (out.parent_path() / (out.stem().string() + ".effective.yaml")).string();
  const std::vector<InputFile> inputs =
      MissionInputs(mission.scenario, mission.policy.get());
  CheckNotAnInput(o.out, "--out", inputs);
  CheckNotAnInput(side, "--out", inputs, "written next to the plan");
  CheckOutputFiles({side}, "--out", "written next to the plan");
  MakeOutputDir(out.parent_path().string(), "--out");
  return side;
}

// What the solve found, on stdout.
void PrintPlan(const Scenario& scenario, const World& world,
               const SamplingPlan& plan) {
  std::printf("%s: seed %llu, %d robots, %d targets\n", scenario.name.c_str(),
              static_cast<unsigned long long>(scenario.seed), world.NumRobots(),
              world.NumTargets());
  if (plan.found) {
    std::printf(
        "F* = %d steps (lower bound %d, F*/bound %.3f), cost J = %.6g\n",
        plan.depth, plan.bound,
        static_cast<double>(plan.depth) / std::max(plan.bound, 1), plan.cost);
  } else {
    std::printf("no plan meets eps within the budget (best effort: %d steps)\n",
                plan.depth);
  }
  std::printf(
      "solve %.3f s, %ld nodes, %ld iterations (first goal at %ld), arena %.1f "
      "MiB, peak RSS %.1f MiB\n",
      plan.seconds, plan.nodes, plan.iterations, plan.first_goal_iteration,
      plan.arena_bytes / 1048576.0, PeakRssMiB());
  if (!plan.rollouts.empty()) {
    std::string seeds;
    for (const RolloutResult& r : plan.rollouts)
      seeds += " " + r.name + " " +
               (r.found ? std::to_string(r.depth) : std::string("-"));
    std::printf("seeded rollouts (steps):%s\n", seeds.c_str());
  }
}

// The plan file's JSON: the outcome, the seeded rollouts, the solve's
// counters and the robots' points at every step.
nlohmann::ordered_json PlanJson(const Scenario& scenario, const World& world,
                                const SamplingPlan& plan) {
  nlohmann::ordered_json j;
  j["scenario"] = scenario.name;
  j["seed"] = scenario.seed;
  j["found"] = plan.found;
  j["flowtime"] = plan.depth;
  j["bound"] = plan.bound;
  j["cost"] = plan.cost;
  j["best_cost"] = plan.best_cost;
  nlohmann::ordered_json rollouts = nlohmann::ordered_json::object();
  for (const RolloutResult& r : plan.rollouts)
    rollouts[r.name] = {
        {"found", r.found}, {"steps", r.depth}, {"cost", r.cost}};
  j["rollouts"] = rollouts;
  j["useful_until"] = plan.useful_until;
  nlohmann::ordered_json aims = nlohmann::ordered_json::array();
  for (const Vec2& a : plan.aims) aims.push_back({a.x(), a.y()});
  j["aims"] = aims;
  j["nodes"] = plan.nodes;
  j["iterations"] = plan.iterations;
  j["first_goal_iteration"] = plan.first_goal_iteration;
  j["solve_s"] = plan.seconds;
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  for (size_t d = 0; d < plan.configs.size(); ++d) {
    nlohmann::ordered_json robots = nlohmann::ordered_json::array();
    for (int idx : plan.configs[d]) {
      const Vec2 p = world.map.lattice().Point(idx);
      robots.push_back({p.x(), p.y()});
    }
    steps.push_back({{"step", d}, {"robots", robots}, {"det", plan.det[d]}});
  }
  j["plan"] = steps;
  return j;
}

// --out: the plan, and its effective scenario next to it (--budget as the
// expert's anytime).
void WritePlan(const PlanOptions& o, const std::string& side,
               const PreparedMission& mission, const SamplingPlan& plan) {
  const nlohmann::ordered_json j =
      PlanJson(mission.scenario, mission.instance->world, plan);
  WriteFileAtomic(
      o.out,
      j.dump(1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  Scenario effective = EffectiveScenario(mission);
  if (o.budget) {
    effective.policy.params.Set("anytime",
                                ConfigNode::Scalar(std::to_string(*o.budget)));
  }
  WriteFileAtomic(side, EffectiveYaml(effective,
                                      "# The effective scenario of this plan "
                                      "(aia plan; the expert's parameters\n"
                                      "# below, --budget included).\n"));
  std::printf("plan written to %s (scenario: %s)\n", o.out.c_str(),
              side.c_str());
}

}  // namespace

int RunPlanCommand(const PlanOptions& o) {
  {
    PlanOptions flags = o;
    CheckFlags(&flags);  // their declarations: `--flag: what`
  }
  if (!o.out.empty()) CheckOutputFile(o.out, "--out");
  // aia plan runs the expert, and --budget is its anytime: a --set of
  // either would be overruled (said as --policy's, a flag plan lacks).
  for (const std::string& text : o.overrides.sets) {
    const Override set = ParseSetFlag(text);
    if (set.path == "policy.name" || ReplacesSectionOf(set.path, "policy.name"))
      throw InputError::Flag(
          "--set " + set.path,
          "aia plan runs the expert (C-SB) and sets policy.name "
          "itself; set the expert's keys one by one (--set "
          "policy.KEY=VALUE)");
    if (o.budget) RefuseSetOfFlagKey(set, "policy.anytime", "--budget");
  }
  const PolicyRegistry registry = AllPolicies();
  CommandOverrides overrides = o.overrides;
  overrides.policy = "expert";
  const PreparedMission mission = PrepareMission(
      LoadScenario(o.scenario_path, overrides.ToOverrides(registry)), registry);
  const std::string side = CheckPlanOutputs(o, mission);
  // The expert's parameters as resolved (and range-checked) by the registry.
  const ExpertParams* params = ParamsOf<ExpertParams>(*mission.policy);
  AIA_CHECK(params != nullptr);
  const SamplingPlan plan = PlanFromStart(mission.instance, *params, o.budget);
  PrintPlan(mission.scenario, mission.instance->world, plan);
  if (!o.out.empty()) WritePlan(o, side, mission, plan);
  return 0;
}

}  // namespace aia
