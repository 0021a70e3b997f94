// build/aia: one binary, one subcommand per job. Each Add*Command declares its
// flags and returns what runs it; main() parses, runs the chosen one, and
// turns bad input into `error: FILE:LINE: key: what` and exit code 2.
#include <CLI/CLI.hpp>
#include <array>
#include <cstdio>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aia/core/error.h"
#include "aia/runtime/bench.h"
#include "aia/runtime/catalog.h"
#include "aia/runtime/eval.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/plan_command.h"
#include "aia/runtime/render_mission.h"

namespace {

using Action = std::function<int()>;

constexpr char kSetHelp[] =
    "override a scenario key, e.g. --set mission.eps=0.05 or --set "
    "policy.p_v=0.8 (repeatable; see aia schema and aia policies)";

// The scenario flags of the mission commands; their values are read after
// parsing (only the flags given override the scenario).
struct MissionFlags {
  CLI::App* cmd = nullptr;
  std::string policy;
  std::uint64_t seed = 0;
  int max_steps = 0;
  std::vector<std::string> sets;

  void Add(CLI::App* c, bool with_policy = true, bool with_max_steps = true) {
    cmd = c;
    if (with_policy)
      c->add_option("--policy", policy,
                    "policy name (overrides the scenario's policy.name)");
    c->add_option("--seed", seed,
                  "random seed (overrides the scenario's seed)");
    if (with_max_steps)
      c->add_option("--max-steps", max_steps,
                    "decision steps at most (overrides mission.max_steps)");
    c->add_option("--set", sets, kSetHelp)->take_all()->expected(1);
  }
  aia::CommandOverrides Get() const {
    aia::CommandOverrides o;
    const auto given = [this](const char* flag) {
      const CLI::Option* opt = cmd->get_option_no_throw(flag);
      return opt != nullptr && opt->count() > 0;
    };
    if (given("--policy")) o.policy = policy;
    if (given("--seed")) o.seed = seed;
    if (given("--max-steps")) o.max_steps = max_steps;
    o.sets = sets;
    return o;
  }
};

Action AddRunCommand(CLI::App& app) {
  auto run = std::make_shared<aia::RunOptions>();
  auto flags = std::make_shared<MissionFlags>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "run",
      "run one mission; write summary.json, trace.csv, estimate.csv, "
      "effective.yaml and diagnostics.json");
  cmd->add_option("scenario", run->scenario_path, "scenario YAML file")
      ->required();
  flags->Add(cmd);
  cmd->add_option("--out", run->out_dir,
                  "output directory (default: renders/<scenario name>)");
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    run->overrides = flags->Get();
    run->progress = !*quiet;
    aia::RunMission(*run);
    return 0;
  };
}

Action AddRenderCommand(CLI::App& app) {
  auto render = std::make_shared<aia::RenderOptions>();
  auto flags = std::make_shared<MissionFlags>();
  auto ints = std::make_shared<std::array<int, 4>>();  // width height fps heat
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "render",
      "render one mission as an H.264 MP4 (headless), with belief overlays");
  cmd->add_option("scenario", render->scenario_path, "scenario YAML file")
      ->required();
  cmd->add_option("--out", render->out_file,
                  "the video, FILE.mp4 (FILE.summary.json, FILE.trace.csv, "
                  "... are written next to it)")
      ->required();
  flags->Add(cmd);
  cmd->add_option("--width", (*ints)[0],
                  "image width in pixels, even (default render.width)");
  cmd->add_option("--height", (*ints)[1],
                  "image height in pixels, even (default render.height)");
  cmd->add_option("--fps", (*ints)[2],
                  "frames per second of simulated time and of the video "
                  "(default render.fps)");
  cmd->add_option("--heatmap", (*ints)[3],
                  "robot whose uncertainty heatmap is drawn, -1 for none "
                  "(default render.follow_robot)");
  cmd->add_option("--frames", render->frames_dir,
                  "also write frames as PNG into this folder");
  cmd->add_option("--frames-every", render->frames_every,
                  "with --frames: write every k-th frame")
      ->capture_default_str();
  cmd->add_option("--hold", render->hold_seconds,
                  "seconds the final frame is held")
      ->capture_default_str();
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    render->overrides = flags->Get();
    const char* names[] = {"--width", "--height", "--fps", "--heatmap"};
    std::optional<int>* targets[] = {&render->width, &render->height,
                                     &render->fps, &render->heatmap_robot};
    for (int i = 0; i < 4; ++i)
      if (cmd->count(names[i])) *targets[i] = (*ints)[i];
    render->progress = !*quiet;
    aia::RenderMission(*render);
    return 0;
  };
}

Action AddPlanCommand(CLI::App& app) {
  auto plan = std::make_shared<aia::PlanOptions>();
  auto flags = std::make_shared<MissionFlags>();
  auto budget = std::make_shared<long>(0);
  CLI::App* cmd = app.add_subcommand(
      "plan", "the expert (C-SB) alone: its plan, F*, solve time, nodes");
  cmd->add_option("scenario", plan->scenario_path, "scenario YAML file")
      ->required();
  flags->Add(cmd, /*with_policy=*/false, /*with_max_steps=*/false);
  cmd->add_option("--budget", *budget,
                  "anytime budget: sampling iterations after the first goal "
                  "(default: the expert's policy.anytime)");
  cmd->add_option("--out", plan->out,
                  "write the plan as JSON to this file (and the scenario "
                  "next to it as FILE.effective.yaml)");
  return [=]() {
    if (!cmd->parsed()) return -1;
    plan->overrides = flags->Get();
    if (cmd->count("--budget")) plan->budget = *budget;
    return aia::RunPlanCommand(*plan);
  };
}

Action AddEvalCommand(CLI::App& app) {
  auto eval = std::make_shared<aia::EvalOptions>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "success rate and flowtime increase against the expert on generated "
      "worlds");
  cmd->add_option("--sizes", eval->sizes, "robots x targets, e.g. 10x10,20x20")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--seeds", eval->seeds, "worlds per size")
      ->capture_default_str();
  cmd->add_option("--seed-base", eval->seed_base,
                  "first seed (seeds B .. B+n-1)")
      ->capture_default_str();
  cmd->add_option(
         "--policies", eval->policies,
         "policies to score (default: every registered one but the expert)")
      ->delimiter(',');
  cmd->add_option("--set", eval->sets,
                  "override a key of every instance's scenario, e.g. --set "
                  "sensor.range=3; policy.<param> goes to each policy that "
                  "has it (repeatable)")
      ->take_all()
      ->expected(1);
  cmd->add_option("--out", eval->out_dir,
                  "output folder (runs.csv, summary.csv, effective.yaml)")
      ->required();
  cmd->add_option("--threads", eval->threads, "worker threads (0: all cores)")
      ->capture_default_str();
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    eval->progress = !*quiet;
    return aia::RunEval(*eval);
  };
}

Action AddBenchCommand(CLI::App& app) {
  auto bench = std::make_shared<aia::BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "decision steps per second and where a step's time goes");
  cmd->add_option("--sizes", bench->sizes, "robots x targets, e.g. 10x10,80x80")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--steps", bench->steps, "decision steps per run")
      ->capture_default_str();
  cmd->add_option("--repeats", bench->repeats,
                  "runs per size (median reported)")
      ->capture_default_str();
  cmd->add_option("--seed", bench->seed, "seed of the generated worlds")
      ->capture_default_str();
  cmd->add_option("--policy", bench->policy, "policy to time")
      ->capture_default_str();
  cmd->add_flag("--no-testspeed", bench->skip_testspeed,
                "do not run mujoco-testspeed for comparison");
  cmd->add_flag("--expert", bench->expert,
                "time the expert's solve (C-SB) instead of episodes");
  cmd->add_option("--seeds", bench->seeds, "with --expert: worlds per size")
      ->capture_default_str();
  cmd->add_option("--set", bench->sets,
                  "override a key of the generated scenarios, e.g. --set "
                  "sensor.range=3 (repeatable)")
      ->take_all()
      ->expected(1);
  return [=]() { return cmd->parsed() ? aia::RunBench(*bench) : -1; };
}

Action AddPoliciesCommand(CLI::App& app) {
  auto markdown = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "policies", "every policy with its parameters (type, default, meaning)");
  cmd->add_flag("--markdown", *markdown,
                "as the Markdown of docs/scenarios.md");
  return [=]() {
    if (!cmd->parsed()) return -1;
    std::fputs(aia::PolicyCatalog(aia::AllPolicies(), *markdown).c_str(),
               stdout);
    return 0;
  };
}

Action AddSchemaCommand(CLI::App& app) {
  auto markdown = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "schema", "every scenario key with its type, default and meaning");
  cmd->add_flag("--markdown", *markdown,
                "as the Markdown of docs/scenarios.md");
  return [=]() {
    if (!cmd->parsed()) return -1;
    std::fputs(aia::ScenarioSchema(*markdown).c_str(), stdout);
    return 0;
  };
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"aia: multi-robot Active Information Acquisition testbed"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "aia 0.1.0");
  const std::vector<Action> commands = {
      AddRunCommand(app),   AddRenderCommand(app), AddPlanCommand(app),
      AddEvalCommand(app),  AddBenchCommand(app),  AddPoliciesCommand(app),
      AddSchemaCommand(app)};
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    for (const Action& run : commands) {
      const int code = run();
      if (code >= 0) return code;
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
