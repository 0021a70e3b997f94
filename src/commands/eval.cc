// The eval core (eval.h): the instances, the setup they share, one
// instance's runs and the summary of their rows.
#include "aia/commands/eval.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "aia/commands/plan_command.h"
#include "aia/core/clock.h"
#include "aia/core/error.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/observers.h"
#include "aia/sim/simulation.h"

namespace aia {
namespace {

// The policy keys of the registry's declarations: "policy.p_v" -> "p_v".
std::set<std::string> DeclaredParams(const PolicyRegistry& registry,
                                     const std::string& policy) {
  std::set<std::string> out;
  for (const PolicyInfo& info : registry.Describe())
    if (info.name == policy)
      for (const FieldDoc& d : info.params) out.insert(d.key.substr(7));
  return out;
}

}  // namespace

std::vector<EvalInstance> EnumerateInstances(const std::vector<TeamSize>& sizes,
                                             int seeds,
                                             std::uint64_t seed_base) {
  const std::string why =
      SeedRangeProblem(seed_base, seeds, "--seeds", "--seed-base");
  if (!why.empty()) throw InputError::Flag("--seed-base", why);
  const std::uint64_t worlds = static_cast<std::uint64_t>(sizes.size()) *
                               static_cast<std::uint64_t>(seeds);
  if (worlds > kMaxEvalWorlds)
    throw InputError::Flag(
        "--seeds",
        std::to_string(sizes.size()) + " sizes x " + std::to_string(seeds) +
            " seeds are " + std::to_string(worlds) +
            " worlds, more than one evaluation takes (" +
            std::to_string(kMaxEvalWorlds) +
            "): split the seeds over several evaluations with --seed-base "
            "(docs/sweeps.md)");
  std::vector<EvalInstance> out;
  out.reserve(worlds);
  for (const TeamSize& size : sizes)
    for (int s = 0; s < seeds; ++s)
      out.push_back({size.ToText(), size.robots, size.targets,
                     seed_base + static_cast<std::uint64_t>(s)});
  return out;
}

EvalSetup MakeEvalSetup(const std::vector<std::string>& policies,
                        const std::vector<std::string>& sets,
                        const PolicyRegistry& registry,
                        const std::vector<EvalInstance>& instances) {
  EvalSetup setup;
  std::vector<Override> policy_sets;
  for (const Override& o : ParseSetFlags(sets)) {
    const std::string key = "--set " + o.path;
    // A whole section holding a key the command sets would replace it.
    for (const char* held : {"robots.count", "targets.count", "policy.name",
                             "mission.max_steps"}) {
      if (ReplacesSectionOf(o.path, held))
        throw InputError::Flag(
            key, "replaces the whole section, which holds " +
                     std::string(held) +
                     ", set by the command; set the section's keys "
                     "one by one (--set " +
                     o.path + ".KEY=VALUE)");
    }
    if (o.path == "seed" || o.path == "robots.count" ||
        o.path == "targets.count") {
      throw InputError::Flag(key,
                             "is set by each instance (--sizes, --seeds, "
                             "--seed-base), not by --set");
    }
    if (o.path == "policy.name")
      throw InputError::Flag(key,
                             "the evaluated policies are given by --policies");
    if (o.path == "mission.max_steps")
      throw InputError::Flag(
          key,
          "is set by the command, not by --set: aia eval runs "
          "each mission to 3 F* of the expert's plan, aia bench "
          "for --steps decision steps");
    if (o.path.rfind("policy.", 0) == 0 && o.path != "policy.model" &&
        o.path != "policy.model_sha256") {
      policy_sets.push_back(o);
    } else {
      setup.overrides.push_back(o);
    }
  }
  // Checked now, once per size, rather than on every instance: the scenario
  // and the world of its first seed (the other seeds only draw another
  // world, which can still fail: RunInstance names the flag too).
  std::vector<EvalInstance> checked;
  for (const EvalInstance& inst : instances) {
    bool seen = false;
    for (const EvalInstance& c : checked) seen = seen || c.size == inst.size;
    if (!seen) checked.push_back(inst);
  }
  Scenario base;
  for (const EvalInstance& inst : checked) {
    const Scenario s = InstanceScenario(inst, setup);
    BuildGenerated(s, InstanceSpec(inst, setup));
    if (&inst == &checked.front()) base = s;
  }
  if (checked.empty()) base = InstanceScenario({"1x1", 1, 1, 0}, setup);
  std::set<std::string> used;
  const auto resolve = [&](const std::string& name) {
    const std::set<std::string> declared = DeclaredParams(registry, name);
    std::vector<Override> own;
    for (const Override& o : policy_sets) {
      if (declared.count(o.path.substr(7))) {
        own.push_back(o);
        used.insert(o.path);
      }
    }
    Scenario s = base;
    s.policy.name = name;
    return registry.Resolve(WithOverrides(s, own));
  };
  setup.expert = resolve("expert");
  for (const std::string& p : policies) {
    if (!registry.Has(p))
      throw InputError::Flag("--policies", registry.UnknownPolicy(p));
    setup.policies.push_back(resolve(p));
  }
  for (const Override& o : policy_sets) {
    if (!used.count(o.path)) {
      std::string names = "expert";
      for (const std::string& p : policies) names += ", " + p;
      throw InputError::Flag("--set " + o.path,
                             "no policy of this evaluation (" + names +
                                 ") has the parameter `" + o.path.substr(7) +
                                 "` (aia policies lists them)");
    }
  }
  // A model that no evaluated policy reads would change nothing (aia run
  // warns of it; here it went unsaid), as aia dataset says.
  bool reads_model = false;
  for (const auto& spec : setup.policies)
    reads_model = reads_model || spec->model_file() != nullptr;
  for (const Override& o : setup.overrides)
    if (!reads_model &&
        (o.path == "policy.model" || o.path == "policy.model_sha256"))
      throw InputError::Flag("--set " + o.path,
                             "no policy of this evaluation reads a model (a "
                             "learned policy does: igbnet)");
  return setup;
}

GeneratedSpec InstanceSpec(const EvalInstance& instance,
                           const EvalSetup& setup) {
  GeneratedSpec spec;
  spec.size = instance.size;
  spec.robots = instance.robots;
  spec.targets = instance.targets;
  spec.seed = instance.seed;
  spec.overrides = setup.overrides;
  return spec;
}

Scenario InstanceScenario(const EvalInstance& instance,
                          const EvalSetup& setup) {
  return ReadGenerated(InstanceSpec(instance, setup));
}

std::vector<EvalRow> RunInstance(const EvalInstance& inst,
                                 const EvalSetup& setup,
                                 const std::vector<std::string>& policies) {
  const std::shared_ptr<const Instance> instance =
      BuildGenerated(InstanceScenario(inst, setup), InstanceSpec(inst, setup));
  const SamplingPlan plan =
      PlanFromStart(instance, *ParamsOf<ExpertParams>(*setup.expert));
  const int fstar = plan.found ? plan.depth : -1;
  std::vector<EvalRow> rows;
  for (const auto& spec : setup.policies) {
    if (!policies.empty() && std::find(policies.begin(), policies.end(),
                                       spec->name()) == policies.end())
      continue;
    EvalRow row;
    row.size = inst.size;
    row.seed = inst.seed;
    row.policy = spec->name();
    row.fstar = fstar;
    row.bound = plan.bound;
    if (fstar >= 0) {
      const auto t0 = std::chrono::steady_clock::now();
      MissionConfig mission = instance->scenario.mission;
      mission.max_steps = EvalHorizon(fstar);
      Episode episode(instance, spec->Create(), mission);
      MoveObserver moves;
      episode.AddObserver(&moves);
      episode.Run();
      if (episode.interrupted()) throw RunInterrupted();
      row.success = episode.success();
      row.flowtime = episode.flowtime();
      row.reversal_share =
          moves.moves() > 0
              ? static_cast<double>(moves.reversals()) / moves.moves()
              : 0.0;
      row.longest_reversal_run = moves.longest_reversal_run();
      row.mission_seconds = episode.mission_seconds();
      for (const long c : episode.sim().robot_stalls()) row.stalls += c;
      for (const long c : episode.sim().robot_timeouts()) row.timeouts += c;
      // The row is kept (diagnostics are not written per run here), and
      // said: a line per run whose state MuJoCo reset, or whose robots
      // never arrived anywhere.
      const std::string what = "aia eval: " + inst.size + ", seed " +
                               std::to_string(inst.seed) + ", " + row.policy;
      std::fputs(EndOfMissionWarnings(episode, moves.moves(), what).c_str(),
                 stderr);
      row.wall_s = SecondsSince(t0);
    }
    rows.push_back(row);
  }
  return rows;
}

void EvalOptions::Validate(const FieldChecker& c) const {
  if (sizes.empty()) c.Fail(sizes, "give at least one size");
  for (std::size_t i = 0; i < sizes.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (sizes[i] == sizes[j])
        c.Fail(sizes, "'" + sizes[i].ToText() + "' is listed twice");
  for (std::size_t i = 0; i < policies.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (policies[i] == policies[j])
        c.Fail(policies, "'" + policies[i] + "' is listed twice");
  const std::string why =
      SeedRangeProblem(seed_base, seeds, "--seeds", "--seed-base");
  if (!why.empty()) c.Fail(seed_base, why);
}

std::string SummaryCsv(const std::vector<EvalRow>& rows,
                       const std::vector<std::string>& sizes,
                       const std::vector<std::string>& policies) {
  std::string out = CsvHeader<SummaryRow>() + "\n";
  for (const auto& size : sizes) {
    for (const auto& policy : policies) {
      int n = 0, ok = 0, no_plan = 0, longest = 0;
      double inc = 0.0, flow = 0.0, fstar = 0.0, gap = 0.0, reversals = 0.0;
      double seconds = 0.0, stalls = 0.0, timeouts = 0.0;
      for (const EvalRow& r : rows) {
        if (r.size != size || r.policy != policy) continue;
        if (r.fstar < 0) {
          ++no_plan;
          continue;
        }
        ++n;
        const int denom = std::max(r.fstar, 1);
        const int f = r.success ? r.flowtime : EvalHorizon(r.fstar);
        ok += r.success ? 1 : 0;
        inc += static_cast<double>(f - r.fstar) / denom;
        flow += f;
        fstar += r.fstar;
        // F* over its bound; a world solved at step 0 (F* = bound = 0) is
        // optimal, 1 (0 / max(0, 1) counted it as better than optimal).
        gap += r.bound == 0 ? (r.fstar == 0 ? 1.0 : r.fstar)
                            : static_cast<double>(r.fstar) / r.bound;
        reversals += r.reversal_share;
        longest = std::max(longest, r.longest_reversal_run);
        seconds += r.mission_seconds;
        stalls += static_cast<double>(r.stalls);
        timeouts += static_cast<double>(r.timeouts);
      }
      // A pair no row holds (another eval's size with this one's policy,
      // or not run yet) is no row of the table, not one of empty columns.
      if (n == 0 && no_plan == 0) continue;
      SummaryRow row;
      row.size = size;
      row.policy = policy;
      row.instances = n;
      row.no_expert_plan = no_plan;
      if (n > 0) {
        row.success_rate = static_cast<double>(ok) / n;
        row.flowtime_increase = inc / n;
        row.mean_flowtime = flow / n;
        row.mean_fstar = fstar / n;
        row.mean_fstar_over_bound = gap / n;
        row.reversal_share = reversals / n;
        row.longest_reversal_run = longest;
        row.mission_seconds = seconds / n;
        row.stalls = stalls / n;
        row.timeouts = timeouts / n;
      }
      out += CsvLine(row);
    }
  }
  return out;
}

}  // namespace aia
