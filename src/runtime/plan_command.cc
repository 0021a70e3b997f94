#include "aia/runtime/plan_command.h"

#include <sys/resource.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/planning/expert.h"
#include "aia/planning/random_policy.h"
#include "aia/scenario/loader.h"

namespace aia {

double PeakRssMiB() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux reports KiB
}

SamplingPlan PlanFromStart(const Scenario& scenario,
                           std::optional<long> budget) {
  Scenario s = scenario;
  // The plan is made on the initial state; the episode's own policy is not
  // used, so build it with the cheapest one and keep the expert's keys.
  const auto params_source = s;
  s.policy.name = "random";
  s.policy.params.clear();
  Episode episode(s, std::make_unique<RandomPolicy>(s));
  Scenario expert = params_source;
  if (expert.policy.name != "expert") expert.policy.params.clear();
  SamplingParams params = ExpertParams(expert);
  if (budget) params.anytime = *budget;
  SamplingTree tree;
  Rng rng(scenario.seed, "policy.expert");
  return tree.Solve(ExpertProblem(episode.Context()), params, rng);
}

int RunPlanCommand(const PlanOptions& o) {
  Scenario scenario = LoadScenario(o.scenario_path);
  ApplyOverrides(o.overrides, AllPolicies(), &scenario);
  if (o.budget && *o.budget < 0)
    throw InputError("command line", 0, "--budget", "must be >= 0");
  const SamplingPlan plan = PlanFromStart(scenario, o.budget);
  const World world = World::Build(scenario);
  std::printf("%s: seed %llu, %d robots, %d targets\n", scenario.name.c_str(),
              static_cast<unsigned long long>(scenario.seed), world.NumRobots(),
              world.NumTargets());
  if (plan.found) {
    std::printf("F* = %d steps, cost J = %.6g\n", plan.depth, plan.cost);
  } else {
    std::printf("no plan meets eps within the budget (best effort: %d steps)\n",
                plan.depth);
  }
  std::printf(
      "solve %.3f s, %ld nodes, %ld iterations (first goal at %ld), arena %.1f "
      "MiB, "
      "peak RSS %.1f MiB\n",
      plan.seconds, plan.nodes, plan.iterations, plan.first_goal_iteration,
      plan.arena_bytes / 1048576.0, PeakRssMiB());
  if (!o.out.empty()) {
    nlohmann::ordered_json j;
    j["scenario"] = scenario.name;
    j["seed"] = scenario.seed;
    j["found"] = plan.found;
    j["flowtime"] = plan.depth;
    j["cost"] = plan.cost;
    j["nodes"] = plan.nodes;
    j["iterations"] = plan.iterations;
    j["first_goal_iteration"] = plan.first_goal_iteration;
    j["solve_s"] = plan.seconds;
    nlohmann::ordered_json steps = nlohmann::ordered_json::array();
    for (size_t d = 0; d < plan.configs.size(); ++d) {
      nlohmann::ordered_json robots = nlohmann::ordered_json::array();
      for (int idx : plan.configs[d]) {
        const Vec2 p = world.lattice.Point(idx);
        robots.push_back({p.x(), p.y()});
      }
      steps.push_back({{"step", d}, {"robots", robots}, {"det", plan.det[d]}});
    }
    j["plan"] = steps;
    WriteFileAtomic(o.out, j.dump(1) + "\n");
    std::printf("plan written to %s\n", o.out.c_str());
  }
  return 0;
}

}  // namespace aia
