// build/aia: one binary, one subcommand per job. Parses flags, calls the
// runtime, turns bad input into `error: FILE:LINE: key: what` and exit code 2.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "aia/core/error.h"
#include "aia/runtime/bench.h"
#include "aia/runtime/eval.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/plan_command.h"
#include "aia/runtime/render_mission.h"

namespace {

void AddOverrides(CLI::App* cmd, aia::ScenarioOverrides* o, std::string* policy,
                  std::uint64_t* seed, int* max_steps) {
  cmd->add_option("--policy", *policy,
                  "policy name (overrides the scenario's policy.name)");
  cmd->add_option("--seed", *seed,
                  "random seed (overrides the scenario's seed)");
  cmd->add_option("--max-steps", *max_steps,
                  "decision steps at most (overrides mission.max_steps)");
  (void)o;
}

void ResolveOverrides(CLI::App* cmd, const std::string& policy,
                      std::uint64_t seed, int max_steps,
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
  CLI::App* run_cmd = app.add_subcommand(
      "run", "run one mission; write summary.json and trace.csv");
  run_cmd->add_option("scenario", run.scenario_path, "scenario YAML file")
      ->required();
  AddOverrides(run_cmd, &run.overrides, &policy, &seed, &max_steps);
  run_cmd->add_option("--out", run.out_dir,
                      "output directory (default: renders/<scenario name>)");
  run_cmd->add_flag("--quiet", quiet, "no progress line");

  aia::RenderOptions render;
  int width = 0, height = 0, fps = 0, heatmap = -1;
  CLI::App* render_cmd = app.add_subcommand(
      "render",
      "render one mission as an H.264 MP4 (headless), with belief overlays");
  render_cmd->add_option("scenario", render.scenario_path, "scenario YAML file")
      ->required();
  render_cmd
      ->add_option("--out", render.out_file,
                   "the video, FILE.mp4 (FILE.summary.json and "
                   "FILE.trace.csv are written next to it)")
      ->required();
  AddOverrides(render_cmd, &render.overrides, &policy, &seed, &max_steps);
  render_cmd->add_option("--width", width,
                         "image width in pixels, even (default render.width)");
  render_cmd->add_option(
      "--height", height,
      "image height in pixels, even (default render.height)");
  render_cmd->add_option("--fps", fps,
                         "frames per second of simulated time and of the video "
                         "(default render.fps)");
  render_cmd->add_option(
      "--heatmap", heatmap,
      "robot whose uncertainty heatmap is drawn, -1 for none "
      "(default render.follow_robot)");
  render_cmd->add_option("--frames", render.frames_dir,
                         "also write frames as PNG into this folder");
  render_cmd
      ->add_option("--frames-every", render.frames_every,
                   "with --frames: write every k-th frame")
      ->capture_default_str();
  render_cmd
      ->add_option("--hold", render.hold_seconds,
                   "seconds the final frame is held")
      ->capture_default_str();
  render_cmd->add_flag("--quiet", quiet, "no progress line");

  aia::BenchOptions bench;
  CLI::App* bench_cmd = app.add_subcommand(
      "bench", "decision steps per second and where a step's time goes");
  bench_cmd
      ->add_option("--sizes", bench.sizes, "robots x targets, e.g. 10x10,80x80")
      ->delimiter(',')
      ->capture_default_str();
  bench_cmd->add_option("--steps", bench.steps, "decision steps per run")
      ->capture_default_str();
  bench_cmd
      ->add_option("--repeats", bench.repeats,
                   "runs per size (median reported)")
      ->capture_default_str();
  bench_cmd->add_option("--seed", bench.seed, "seed of the generated worlds")
      ->capture_default_str();
  bench_cmd->add_option("--policy", bench.policy, "policy to time")
      ->capture_default_str();
  bench_cmd->add_flag("--no-testspeed", bench.skip_testspeed,
                      "do not run mujoco-testspeed for comparison");
  bench_cmd->add_flag("--expert", bench.expert,
                      "time the expert's solve (C-SB) instead of episodes");
  bench_cmd
      ->add_option("--seeds", bench.seeds, "with --expert: worlds per size")
      ->capture_default_str();

  aia::PlanOptions plan;
  long budget = 0;
  CLI::App* plan_cmd = app.add_subcommand(
      "plan", "the expert (C-SB) alone: its plan, F*, solve time, nodes");
  plan_cmd->add_option("scenario", plan.scenario_path, "scenario YAML file")
      ->required();
  plan_cmd->add_option("--seed", seed,
                       "random seed (overrides the scenario's seed)");
  plan_cmd->add_option(
      "--budget", budget,
      "anytime budget: sampling iterations after the first goal (default: "
      "the scenario's policy.anytime, else 20000)");
  plan_cmd->add_option("--out", plan.out,
                       "write the plan as JSON to this file");

  aia::EvalOptions eval;
  CLI::App* eval_cmd =
      app.add_subcommand("eval",
                         "success rate and flowtime increase against the "
                         "expert on generated worlds");
  eval_cmd
      ->add_option("--sizes", eval.sizes, "robots x targets, e.g. 10x10,20x20")
      ->delimiter(',')
      ->capture_default_str();
  eval_cmd->add_option("--seeds", eval.seeds, "worlds per size")
      ->capture_default_str();
  eval_cmd
      ->add_option("--seed-base", eval.seed_base,
                   "first seed (seeds B .. B+n-1)")
      ->capture_default_str();
  eval_cmd
      ->add_option(
          "--policies", eval.policies,
          "policies to score (default: every registered one but the expert)")
      ->delimiter(',');
  eval_cmd
      ->add_option("--out", eval.out_dir,
                   "output folder (runs.csv, summary.csv)")
      ->required();
  eval_cmd
      ->add_option("--threads", eval.threads, "worker threads (0: all cores)")
      ->capture_default_str();
  eval_cmd->add_flag("--quiet", quiet, "no progress line");

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
    } else if (*plan_cmd) {
      if (plan_cmd->count("--seed")) plan.overrides.seed = seed;
      if (plan_cmd->count("--budget")) plan.budget = budget;
      return aia::RunPlanCommand(plan);
    } else if (*render_cmd) {
      ResolveOverrides(render_cmd, policy, seed, max_steps, &render.overrides);
      if (render_cmd->count("--width")) render.width = width;
      if (render_cmd->count("--height")) render.height = height;
      if (render_cmd->count("--fps")) render.fps = fps;
      if (render_cmd->count("--heatmap")) render.heatmap_robot = heatmap;
      render.progress = !quiet;
      aia::RenderMission(render);
    } else if (*eval_cmd) {
      eval.progress = !quiet;
      return aia::RunEval(eval);
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
