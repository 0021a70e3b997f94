// build/aia: one binary, one subcommand per job. Parses flags, calls the
// runtime, turns bad input into `error: FILE:LINE: key: what` and exit code 2.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "aia/core/error.h"
#include "aia/runtime/bench.h"
#include "aia/runtime/mission.h"

namespace {

void AddOverrides(CLI::App* cmd, aia::ScenarioOverrides* o, std::string* policy,
                  std::uint64_t* seed, int* max_steps) {
  cmd->add_option("--policy", *policy, "policy name (overrides the scenario's policy.name)");
  cmd->add_option("--seed", *seed, "random seed (overrides the scenario's seed)");
  cmd->add_option("--max-steps", *max_steps, "decision steps at most (overrides mission.max_steps)");
  (void)o;
}

void ResolveOverrides(CLI::App* cmd, const std::string& policy, std::uint64_t seed, int max_steps,
                      aia::ScenarioOverrides* o) {
  if (cmd->count("--policy")) o->policy = policy;
  if (cmd->count("--seed")) o->seed = seed;
  if (cmd->count("--max-steps")) o->max_steps = max_steps;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"aia: multi-robot Active Information Acquisition testbed"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "aia 0.1.0");

  std::string policy;
  std::uint64_t seed = 0;
  int max_steps = 0;

  aia::RunOptions run;
  bool quiet = false;
  CLI::App* run_cmd = app.add_subcommand("run", "run one mission; write summary.json and trace.csv");
  run_cmd->add_option("scenario", run.scenario_path, "scenario YAML file")->required();
  AddOverrides(run_cmd, &run.overrides, &policy, &seed, &max_steps);
  run_cmd->add_option("--out", run.out_dir, "output directory (default: renders/<scenario name>)");
  run_cmd->add_flag("--quiet", quiet, "no progress line");

  aia::BenchOptions bench;
  CLI::App* bench_cmd =
      app.add_subcommand("bench", "decision steps per second and where a step's time goes");
  bench_cmd->add_option("--sizes", bench.sizes, "robots x targets, e.g. 10x10,80x80")
      ->delimiter(',')
      ->capture_default_str();
  bench_cmd->add_option("--steps", bench.steps, "decision steps per run")->capture_default_str();
  bench_cmd->add_option("--repeats", bench.repeats, "runs per size (median reported)")
      ->capture_default_str();
  bench_cmd->add_option("--seed", bench.seed, "seed of the generated worlds")->capture_default_str();
  bench_cmd->add_option("--policy", bench.policy, "policy to time")->capture_default_str();
  bench_cmd->add_flag("--no-testspeed", bench.skip_testspeed,
                      "do not run mujoco-testspeed for comparison");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (*run_cmd) {
      ResolveOverrides(run_cmd, policy, seed, max_steps, &run.overrides);
      run.progress = !quiet;
      aia::RunMission(run);
    } else if (*bench_cmd) {
      return aia::RunBench(bench);
    }
  } catch (const aia::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.Format().c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
