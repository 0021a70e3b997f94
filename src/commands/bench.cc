#include "aia/commands/bench.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <set>
#include <string>

#include "aia/commands/eval.h"
#include "aia/commands/plan_command.h"
#include "aia/core/error.h"
#include "aia/core/io.h"
#include "aia/learning/network.h"
#include "aia/learning/trainer.h"
#include "aia/runtime/mission.h"
#include "aia/scenario/config.h"

namespace aia {

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// mujoco-testspeed on a model file: its "Steps per second" and "Contacts per
// step", -1 where it did not run.
struct TestSpeedResult {
  double steps_per_s = -1.0, contacts = -1.0;
};

TestSpeedResult TestSpeed(const std::string& xml_path, int nstep) {
  TestSpeedResult r;
  const std::string cmd = "mujoco-testspeed '" + xml_path + "' " +
                          std::to_string(nstep) + " 1 0.01 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  if (!pipe) return r;
  char buf[512];
  while (std::fgets(buf, sizeof(buf), pipe.get())) {
    // " Steps per second     : 1234"
    std::string line(buf);
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, colon);
    double* into =
        key.find("Steps per second") != std::string::npos    ? &r.steps_per_s
        : key.find("Contacts per step") != std::string::npos ? &r.contacts
                                                             : nullptr;
    if (into == nullptr) continue;
    char* end = nullptr;
    const double v = std::strtod(line.c_str() + colon + 1, &end);
    if (end != line.c_str() + colon + 1) *into = v;
  }
  return r;
}

}  // namespace

namespace {

// One instance per size at the first seed: what the setup checks.
std::vector<EvalInstance> Instances(const BenchOptions& o) {
  return EnumerateInstances(o.sizes, 1, o.seed);
}

int RunExpertBench(const BenchOptions& o) {
  std::printf(
      "aia bench --expert: C-SB solve from the initial state, %d generated "
      "worlds per size "
      "(seeds %llu..%llu)\n",
      o.seeds, static_cast<unsigned long long>(o.seed),
      static_cast<unsigned long long>(o.seed + o.seeds - 1));
  std::printf("%-8s %10s %10s %8s %8s %10s %12s %12s %10s\n", "size",
              "median_s", "worst_s", "F*_med", "found", "nodes_med",
              "arena_MiB", "arena_worst", "RSS_MiB");
  const EvalSetup setup =
      MakeEvalSetup({}, o.sets, AllPolicies(), Instances(o));
  const ExpertParams& expert = *ParamsOf<ExpertParams>(*setup.expert);
  for (const TeamSize& size : o.sizes) {
    const std::string size_text = size.ToText();
    std::vector<double> secs, fstar, nodes, arena;
    int found = 0;
    for (int k = 0; k < o.seeds; ++k) {
      const EvalInstance instance{size_text, size.robots, size.targets,
                                  o.seed + k};
      const std::shared_ptr<const Instance> built = BuildGenerated(
          InstanceScenario(instance, setup), InstanceSpec(instance, setup));
      const SamplingPlan plan = PlanFromStart(built, expert);
      secs.push_back(plan.seconds);
      // F* is a found plan's depth: a search that found none has no F*.
      if (plan.found) fstar.push_back(plan.depth);
      nodes.push_back(static_cast<double>(plan.nodes));
      arena.push_back(plan.arena_bytes / 1048576.0);
      found += plan.found ? 1 : 0;
    }
    char fstar_text[32] = "-";
    if (!fstar.empty())
      std::snprintf(fstar_text, sizeof fstar_text, "%.1f", Median(fstar));
    std::printf("%-8s %10.4f %10.4f %8s %5d/%-2d %10.0f %12.2f %12.2f %10.1f\n",
                size_text.c_str(), Median(secs),
                *std::max_element(secs.begin(), secs.end()), fstar_text, found,
                o.seeds, Median(nodes), Median(arena),
                *std::max_element(arena.begin(), arena.end()), PeakRssMiB());
    std::fflush(stdout);
  }
  std::printf(
      "(arena: the tree's node storage; RSS: the whole process's peak so far, "
      "MuJoCo models of the worlds included)\n");
  return 0;
}

}  // namespace

int RunNetworkBench(const BenchOptions& o) {
  std::printf(
      "aia bench --network: I-GBNet's network alone, samples (robot images) "
      "per second, medians of %d runs, %d threads\n",
      o.repeats, InferenceThreads());
  // bfloat16 where the CPU has it (policy.precision), "-" where not.
  const bool bf16 = NativeBFloat16();
  std::printf("%-8s %-7s %6s %12s %12s %14s %12s\n", "input", "stride", "width",
              "infer b=10", "infer b=80", "bfloat16 b=80", "train b=16");
  for (int stride : {1, 2}) {
    NetworkConfig c;
    c.stem_stride = stride;
    const int side = c.channels.window;
    const double i10 =
        MeasureNetworkSpeed(c, side, side, 10, false, 20, o.repeats);
    const double i80 =
        MeasureNetworkSpeed(c, side, side, 80, false, 4, o.repeats);
    const std::string b80 =
        bf16 ? std::to_string(std::lround(MeasureNetworkSpeed(
                   c, side, side, 80, false, 4, o.repeats, true)))
             : "-";
    const double t16 =
        MeasureNetworkSpeed(c, side, side, 16, true, 8, o.repeats);
    std::printf("%-8s %-7d %6d %12.0f %12.0f %14s %12.0f\n",
                (std::to_string(side) + "x" + std::to_string(side)).c_str(),
                stride, c.width, i10, i80, b80.c_str(), t16);
  }
  return 0;
}

void BenchOptions::Validate(const FieldChecker& c) const {
  if (sizes.empty()) c.Fail(sizes, "give at least one size");
  const std::string why =
      expert ? SeedRangeProblem(seed, seeds, "--seeds", "--seed") : "";
  if (!why.empty()) c.Fail(seed, why);
}

// A flag the mode does not read, given a value of its own: refused, not
// ignored (the network and the expert modes time other things).
void CheckModeFlags(const BenchOptions& o) {
  const BenchOptions d;
  const char* mode = o.network  ? "--network (the network alone)"
                     : o.expert ? "--expert (the expert's plan from the start)"
                                : nullptr;
  const auto refuse = [&](bool given, const char* flag, const char* reads) {
    if (given)
      throw InputError::Flag(flag,
                             std::string("is not read by aia bench ") + reads);
  };
  if (o.network && o.expert)
    throw InputError::Flag("--expert",
                           "and --network time different things: give one");
  if (mode != nullptr) {
    const std::string with = std::string("with ") + mode;
    refuse(o.policy != d.policy, "--policy", with.c_str());
    refuse(o.steps != d.steps, "--steps", with.c_str());
    refuse(o.skip_testspeed, "--no-testspeed", with.c_str());
    refuse(o.policy_threads != d.policy_threads, "--policy-threads",
           with.c_str());
  }
  if (o.network) {
    refuse(!o.sets.empty(), "--set", "with --network (no world is made)");
    refuse(o.seeds != d.seeds, "--seeds", "with --network");
    refuse(o.seed != d.seed, "--seed", "with --network");
    refuse(o.sizes != d.sizes, "--sizes",
           "with --network (it times its own batches of 10 and 80)");
  }
  if (o.expert) refuse(o.repeats != d.repeats, "--repeats", "with --expert");
  if (!o.expert) refuse(o.seeds != d.seeds, "--seeds", "without --expert");
  std::set<std::string> sizes;
  for (const TeamSize& s : o.sizes)
    if (!sizes.insert(s.ToText()).second)
      throw InputError::Flag("--sizes", s.ToText() + " is given twice");
}

int RunBench(const BenchOptions& o) {
  {
    BenchOptions flags = o;
    CheckFlags(&flags);  // their declarations: `--flag: what`
  }
  CheckModeFlags(o);
  SetPolicyThreads(o.policy_threads);
  if (o.network) return RunNetworkBench(o);
  if (o.expert) return RunExpertBench(o);
  const PolicyRegistry registry = AllPolicies();
  if (!registry.Has(o.policy))
    throw InputError::Flag("--policy", registry.UnknownPolicy(o.policy));
  const EvalSetup setup =
      MakeEvalSetup({o.policy}, o.sets, registry, Instances(o));
  std::printf(
      "aia bench: policy %s, %d decision steps x %d runs per size (the median "
      "run by ms/step), "
      "%d policy thread%s\n",
      o.policy.c_str(), o.steps, o.repeats, o.policy_threads,
      o.policy_threads == 1 ? "" : "s");
  std::printf("%-8s %10s %9s %9s %9s %9s %9s %9s %8s %10s %11s %9s %11s\n",
              "size", "steps/s", "ms/step", "physics", "sensing", "fusion",
              "policy", "rest", "mj_step%", "mj_step/s", "testspeed/s",
              "contacts", "ts_contacts");
  for (const EvalInstance& generated : Instances(o)) {
    const std::string& size_text = generated.size;
    Scenario s = InstanceScenario(generated, setup);
    s.mission.max_steps = o.steps;
    s.mission.stop_at_success = false;
    const std::shared_ptr<const PolicySpec>& policy = setup.policies[0];
    const std::shared_ptr<const Instance> instance =
        BuildGenerated(s, InstanceSpec(generated, setup));
    std::vector<double> rate, ms, phys, sens, fus, pol, rest, share, mjrate,
        contacts;
    std::string mjcf;
    for (int r = 0; r < o.repeats; ++r) {
      auto episode = std::make_unique<Episode>(instance, policy->Create());
      episode->Run();
      const PhaseTimes& t = episode->times();
      const int steps = episode->step();
      if (steps == 0)
        throw InputError::Flag(
            "--sizes " + size_text,
            "the mission ended before its first decision step "
            "(no robot active: every robot fails at step 0?), "
            "so there is nothing to time");
      rate.push_back(steps / t.total);
      ms.push_back(1e3 * t.total / steps);
      phys.push_back(1e3 * t.physics / steps);
      sens.push_back(1e3 * t.sensing / steps);
      fus.push_back(1e3 * t.fusion / steps);
      pol.push_back(1e3 * t.policy / steps);
      rest.push_back(1e3 *
                     (t.total - t.physics - t.sensing - t.fusion - t.policy) /
                     steps);
      const Simulation& sim = episode->sim();
      share.push_back(100.0 * t.physics / t.total);
      mjrate.push_back(sim.mj_steps() / sim.physics_seconds());
      contacts.push_back(static_cast<double>(sim.contacts_summed()) /
                         std::max(1L, sim.mj_steps()));
      mjcf = episode->sim().mjcf();
    }
    TestSpeedResult testspeed;
    if (!o.skip_testspeed) {
      const auto path = std::filesystem::temp_directory_path() /
                        ("aia_bench_" + size_text + "_" +
                         std::to_string(::getpid()) + ".xml");
      WriteFileAtomic(path.string(), mjcf);  // never blocks on a FIFO
      testspeed = TestSpeed(path.string(), 4000);
      std::filesystem::remove(path);
    }
    // One run's row, the median run's by ms/step (the lower of the middle
    // two for an even count), so that the phases add up to its ms/step and
    // steps/s is 1000 / ms/step: medians of each column apart do not.
    std::vector<std::size_t> order(ms.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(
        order.begin(), order.end(),
        [&](std::size_t a, std::size_t b) { return ms[a] < ms[b]; });
    const std::size_t m = order[(order.size() - 1) / 2];
    std::printf(
        "%-8s %10.1f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %7.1f%% %10.0f "
        "%11.0f %9.2f %11.2f\n",
        size_text.c_str(), rate[m], ms[m], phys[m], sens[m], fus[m], pol[m],
        rest[m], share[m], mjrate[m], testspeed.steps_per_s, contacts[m],
        testspeed.contacts);
    std::fflush(stdout);
  }
  std::printf(
      "(per-step phase times in ms; physics is the time inside mj_step, "
      "mj_step%% its share of the step, and the waypoint spring, the stall "
      "rule and the targets' motion between physics steps are in rest; "
      "mj_step/s and contacts (per mj_step) are inside episodes; testspeed/s "
      "and ts_contacts are mujoco-testspeed's on the "
      "same generated model: 1 thread, ctrlnoise 0.01, passive dynamics "
      "from the start, the robots at rest)\n");
  return 0;
}

}  // namespace aia
