// aia's command line (commands/cli.h): one subcommand per job. Each
// Add*Command declares its flags and returns what runs it; CliMain parses,
// runs the chosen one, and turns bad input into `error: FILE:LINE: key: what`
// and exit code 2.
#include "aia/commands/cli.h"

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <functional>
#include <memory>
#include <new>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "aia/commands/bench.h"
#include "aia/commands/catalog.h"
#include "aia/commands/dataset_command.h"
#include "aia/commands/eval.h"
#include "aia/commands/plan_command.h"
#include "aia/commands/ranks.h"
#include "aia/commands/render_mission.h"
#include "aia/commands/run_command.h"
#include "aia/commands/world_command.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/interrupt.h"
#include "aia/learning/trainer.h"
#include "aia/runtime/mission.h"

namespace {

using Action = std::function<int()>;

// --set's help, naming the command's own flags that set a key.
std::string SetHelp(const std::string& own_flags) {
  return "override a scenario key, e.g. --set mission.eps=0.05 or --set "
         "policy.p_v=0.8 (repeatable; see aia schema and aia policies" +
         (own_flags.empty() ? std::string(")")
                            : "; not a key that " + own_flags + " gives too)");
}

// Paths given to a flag: an empty one is a mistake (an unset variable in a
// script), not the flag's default.
const CLI::Validator kPath(
    [](std::string& v) -> std::string {
      return v.empty() ? "an empty path; give a file or folder" : "";
    },
    "", "PATH");

// Flags declared by a struct's fields (core/fields.h): each field's flag is
// aia::FlagName of its key, its help the field's documentation, its default
// the member's value. A given flag's text is read after parsing (Apply) by
// the scenario keys' reader, with their error form (`command line: --flag:
// must be an integer >= 1, got x`); relations between fields are checked
// where the struct is used (aia::CheckFlags).
class DeclaredFlags {
 public:
  explicit DeclaredFlags(CLI::App* cmd) : cmd_(cmd) {}

  // Every field of *value but those in `skip`; *value must outlive the
  // command.
  template <typename T>
  void Add(T* value, std::set<std::string> skip = {}) {
    skip_ = std::move(skip);
    value->Serialize(this);
  }
  // Reads the enumerations given by name.
  void Apply() const {
    for (const auto& apply : after_) apply();
  }
  // The flags of these declarations given on the command line.
  std::vector<std::string> Given() const {
    std::vector<std::string> given;
    for (const std::string& flag : flags_)
      if (cmd_->count(flag) > 0) given.push_back(flag);
    return given;
  }

  template <typename T>
  void Visit(const aia::Field<T>& f) {
    if (skip_.count(std::string(f.name))) return;
    const std::string flag = aia::FlagName(f.name);
    const std::string help(f.doc);
    flags_.push_back(flag);
    if constexpr (std::is_same_v<T, bool>) {
      cmd_->add_flag(flag, *f.value, help);
    } else if constexpr (aia::internal::IsVector<T>::value) {
      // A comma-separated list, each item read as the field's items are.
      // Split here rather than by CLI11, which drops empty items: `--sizes
      // 2x2,,3x3` is a mistake (a variable left empty), not two sizes.
      auto items = std::make_shared<std::vector<std::string>>();
      const std::optional<aia::ConfigNode> list =
          aia::FieldWriter::Write(*f.value, f);  // kept: its items are read
      std::string shown;
      for (const aia::ConfigNode& item : list->items)
        shown += (shown.empty() ? "" : ",") + item.scalar;
      cmd_->add_option(flag, *items, help)->default_str(shown);
      ReadAfter(f, flag, [items, flag] {
        aia::ConfigNode list = aia::ConfigNode::List();
        for (const std::string& text : *items) {
          std::size_t start = 0;
          while (true) {
            const std::size_t comma = text.find(',', start);
            const std::string item = text.substr(
                start,
                comma == std::string::npos ? std::string::npos : comma - start);
            if (item.empty())
              throw aia::InputError::Flag(
                  flag, "'" + text +
                            "' has an empty item; separate the items by one "
                            "comma");
            list.items.push_back(aia::ConfigNode::Scalar(item));
            if (comma == std::string::npos) break;
            start = comma + 1;
          }
        }
        return list;
      });
    } else {
      // A number, a name or a one-token value.
      const std::optional<aia::ConfigNode> shown =
          aia::FieldWriter::Write(*f.value, f);
      auto text = std::make_shared<std::string>(shown ? shown->scalar : "");
      cmd_->add_option(flag, *text, help)
          ->capture_default_str()
          ->type_name(TypeName<T>());
      ReadAfter(f, flag, [text] { return aia::ConfigNode::Scalar(*text); });
    }
  }

 private:
  // One field read alone, with its declaration's options.
  template <typename T>
  struct OneField {
    aia::Field<T> field;
    T value{};
    template <typename A>
    void Serialize(A* a) {
      a->Visit(field.For(&value));
    }
  };

  // "INT", "UINT", "FLOAT" or "TEXT" in --help.
  template <typename T>
  static const char* TypeName() {
    if constexpr (aia::internal::IsOptional<T>::value)
      return TypeName<typename T::value_type>();
    if constexpr (std::is_same_v<T, std::uint64_t>) return "UINT";
    if constexpr (aia::internal::kIsInteger<T>) return "INT";
    if constexpr (std::is_floating_point_v<T>) return "FLOAT";
    return "TEXT";
  }

  // After parsing, a given flag's text (made by `node`) is read into the
  // field by the scenario keys' reader: `command line: --flag: what`.
  template <typename T, typename MakeNode>
  void ReadAfter(const aia::Field<T>& f, const std::string& flag,
                 MakeNode node) {
    after_.push_back([this, f, flag, node] {
      if (cmd_->count(flag) == 0) return;
      OneField<T> one{f};
      aia::ConfigNode map = aia::ConfigNode::Map();
      map.Set(std::string(f.name), node()).SetOrigin(flag);
      aia::ReadFields(map, aia::ReadOptions{"command line", "", ""}, "", &one);
      *f.value = std::move(one.value);
    });
  }

  CLI::App* cmd_;
  std::vector<std::string> flags_;
  std::set<std::string> skip_;
  std::vector<std::function<void()>> after_;
};

// The scenario flags of the mission commands; only the flags given
// override the scenario, read as its keys (`command line: --seed: what`).
struct MissionFlags {
  CLI::App* cmd = nullptr;
  std::string policy, seed, max_steps;
  std::vector<std::string> sets;

  void Add(CLI::App* c, bool with_policy = true, bool with_max_steps = true) {
    cmd = c;
    if (with_policy)
      c->add_option("--policy", policy,
                    "policy name (overrides the scenario's policy.name)");
    c->add_option("--seed", seed, "random seed (overrides the scenario's seed)")
        ->type_name("UINT");
    if (with_max_steps)
      c->add_option("--max-steps", max_steps,
                    "decision steps at most (overrides mission.max_steps)")
          ->type_name("INT");
    c->add_option("--set", sets,
                  SetHelp(with_policy && with_max_steps
                              ? "--policy, --seed or --max-steps"
                          : with_policy    ? "--policy or --seed"
                          : with_max_steps ? "--seed or --max-steps"
                                           : "--seed"))
        ->take_all()
        ->expected(1);
  }
  aia::CommandOverrides Get() const {
    aia::CommandOverrides o;
    const auto given = [this](const char* flag) {
      const CLI::Option* opt = cmd->get_option_no_throw(flag);
      return opt != nullptr && opt->count() > 0;
    };
    if (given("--policy")) o.policy = policy;
    if (given("--seed")) o.flags.push_back({"--seed", "seed", seed});
    if (given("--max-steps"))
      o.flags.push_back({"--max-steps", "mission.max_steps", max_steps});
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
                  "output directory (default: renders/NAME for a scenario file "
                  "NAME.yaml)")
      ->check(kPath);
  // --trace, as RunOptions declares it.
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(run.get());
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    run->overrides = flags->Get();
    run->progress = !*quiet;
    aia::InstallInterruptHandler();  // Ctrl-C: write what is done, exit 130
    aia::RunMission(*run);
    if (aia::Interrupted()) {
      std::fprintf(stderr, "aia run: interrupted; wrote the steps done\n");
      return aia::kInterruptedExitCode;
    }
    return 0;
  };
}

Action AddRenderCommand(CLI::App& app) {
  auto render = std::make_shared<aia::RenderOptions>();
  auto flags = std::make_shared<MissionFlags>();
  // --width, --height, --fps and --heatmap: keys of the render section.
  struct SectionFlag {
    const char* flag;
    const char* key;
    const char* help;
  };
  static constexpr SectionFlag kSection[] = {
      {"--width", "render.width", "image width in pixels, even"},
      {"--height", "render.height", "image height in pixels, even"},
      {"--fps", "render.fps",
       "frames per second of simulated time and of the video"},
      {"--heatmap", "render.follow_robot",
       "robot whose uncertainty heatmap is drawn, -1 for none"}};
  auto texts = std::make_shared<std::array<std::string, 4>>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "render",
      "render one mission as an H.264 MP4 (headless), with belief overlays");
  cmd->add_option("scenario", render->scenario_path, "scenario YAML file")
      ->required();
  cmd->add_option("--out", render->out_file,
                  "the video, FILE.mp4 (FILE.summary.json, FILE.trace.csv, "
                  "... are written next to it)")
      ->required()
      ->check(kPath);
  flags->Add(cmd);
  for (int i = 0; i < 4; ++i)
    cmd->add_option(
           kSection[i].flag, (*texts)[i],
           std::string(kSection[i].help) + " (default " + kSection[i].key + ")")
        ->type_name("INT");
  cmd->add_option("--frames", render->frames_dir,
                  "also write frames as PNG into this folder")
      ->check(kPath);
  // --frames-every, --hold and --edges, as RenderOptions declares them.
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(render.get());
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    render->overrides = flags->Get();
    // Read as the scenario's keys (`command line: --width: what`).
    for (int i = 0; i < 4; ++i)
      if (cmd->count(kSection[i].flag))
        render->overrides.flags.push_back(
            {kSection[i].flag, kSection[i].key, (*texts)[i]});
    render->progress = !*quiet;
    // Ctrl-C: the mission ends after the current step; the video so far and
    // the result files are written; exit 130.
    aia::InstallInterruptHandler();
    aia::RenderMission(*render);
    if (aia::Interrupted()) {
      std::fprintf(stderr,
                   "aia render: interrupted; wrote the video and files of the "
                   "steps done\n");
      return aia::kInterruptedExitCode;
    }
    return 0;
  };
}

Action AddPlanCommand(CLI::App& app) {
  auto plan = std::make_shared<aia::PlanOptions>();
  auto flags = std::make_shared<MissionFlags>();
  CLI::App* cmd = app.add_subcommand(
      "plan", "the expert (C-SB) alone: its plan, F*, solve time, nodes");
  cmd->add_option("scenario", plan->scenario_path, "scenario YAML file")
      ->required();
  flags->Add(cmd, /*with_policy=*/false, /*with_max_steps=*/false);
  cmd->get_option("--set")->description(
      "override a scenario key, e.g. --set mission.eps=0.05 or --set "
      "policy.max_iterations=5000 (repeatable; see aia schema and aia "
      "policies; not a key that --seed gives too, nor policy.name: plan runs "
      "the expert; nor policy.anytime beside --budget)");
  // --budget, as PlanOptions declares it.
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(plan.get());
  cmd->add_option("--out", plan->out,
                  "write the plan as JSON to this file (and the scenario "
                  "next to it as FILE.effective.yaml)")
      ->check(kPath);
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    plan->overrides = flags->Get();
    return aia::RunPlanCommand(*plan);
  };
}

Action AddWorldCommand(CLI::App& app) {
  auto world = std::make_shared<aia::WorldOptions>();
  auto flags = std::make_shared<MissionFlags>();
  CLI::App* cmd = app.add_subcommand(
      "world",
      "write a scenario's generated world as MJCF (robots at their starts, "
      "targets at their positions) for mujoco-simulate or Python's mujoco");
  cmd->add_option("scenario", world->scenario_path, "scenario YAML file")
      ->required();
  flags->Add(cmd, /*with_policy=*/false, /*with_max_steps=*/false);
  cmd->add_option("--out", world->out, "the MJCF file to write, e.g. world.xml")
      ->required()
      ->check(kPath);
  return [=]() {
    if (!cmd->parsed()) return -1;
    world->overrides = flags->Get();
    return aia::RunWorldCommand(*world);
  };
}

Action AddEvalCommand(CLI::App& app) {
  auto eval = std::make_shared<aia::EvalOptions>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "success rate and flowtime increase against the expert on generated "
      "worlds");
  // --sizes, --seeds, --seed-base, --policies and --threads, as EvalOptions
  // declares them.
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(eval.get());
  cmd->add_option("--set", eval->sets,
                  "override a key of every instance's scenario, e.g. --set "
                  "sensor.range=3; policy.<param> goes to each policy that "
                  "has it (repeatable)")
      ->take_all()
      ->expected(1);
  cmd->add_option("--out", eval->out_dir,
                  "output folder (runs.csv, summary.csv, effective.yaml)")
      ->required()
      ->check(kPath);
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    eval->progress = !*quiet;
    return aia::RunEval(*eval);
  };
}

Action AddBenchCommand(CLI::App& app) {
  auto bench = std::make_shared<aia::BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "decision steps per second and where a step's time goes");
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(bench.get());
  cmd->add_option("--policy", bench->policy, "policy to time")
      ->capture_default_str();
  cmd->add_flag("--no-testspeed", bench->skip_testspeed,
                "do not run mujoco-testspeed for comparison");
  cmd->add_flag("--expert", bench->expert,
                "time the expert's solve (C-SB) instead of episodes");
  cmd->add_flag("--network", bench->network,
                "time I-GBNet's network alone (inference and training)");
  cmd->add_option("--set", bench->sets,
                  "override a key of the generated scenarios, e.g. --set "
                  "sensor.range=3 (repeatable)")
      ->take_all()
      ->expected(1);
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    return aia::RunBench(*bench);
  };
}

Action AddDatasetCommand(CLI::App& app) {
  auto o = std::make_shared<aia::DatasetOptions>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "dataset",
      "imitation data for I-GBNet: the expert's episodes on generated worlds, "
      "states and expert labels in SQLite (resumable; docs/learning.md)");
  cmd->add_option("--out", o->out, "dataset folder (one SQLite file per shard)")
      ->required()
      ->check(kPath);
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(o.get());
  cmd->add_option("--policy", o->policy,
                  "acting policy (igbnet for DAgger; labels always come "
                  "from the expert)")
      ->capture_default_str();
  cmd->add_option("--model", o->model, "model of a learned acting policy")
      ->check(kPath);
  cmd->add_option("--set", o->sets,
                  "override a key of the generated worlds' scenarios, e.g. "
                  "--set sensor.range=3 (repeatable; see aia schema)")
      ->take_all()
      ->expected(1);
  cmd->add_flag("--quiet", *quiet, "no progress line");
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    const aia::Ranks& ranks = aia::Ranks::Get();
    if (ranks.distributed()) {  // under mpirun: one shard per rank
      if (cmd->count("--shard"))
        throw aia::InputError::Flag("--shard",
                                    "is given by the MPI ranks under mpirun");
      o->shard = {ranks.rank(), ranks.size()};
    }
    o->progress = !*quiet && ranks.rank() == 0;
    aia::RunDataset(*o);
    return 0;
  };
}

Action AddTrainCommand(CLI::App& app) {
  auto o = std::make_shared<aia::TrainOptions>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "train",
      "train I-GBNet by imitation of the expert (checkpoint every epoch, "
      "--resume; docs/learning.md)");
  cmd->add_option("--data", o->data, "dataset folders or files (repeatable)")
      ->required()
      ->take_all()
      ->check(kPath);
  cmd->add_option("--out", o->out,
                  "model file to write (required to train; the shipped one "
                  "is models/igbnet.pt); OUT.ckpt and OUT(.pt->.train.csv) "
                  "beside it")
      ->check(kPath);
  cmd->add_option("--init", o->init, "start from this model (DAgger rounds)")
      ->check(kPath);
  // The hyperparameters and the network, as their structs declare them.
  auto declared = std::make_shared<DeclaredFlags>(cmd);
  declared->Add(o.get());
  auto network = std::make_shared<DeclaredFlags>(cmd);
  // set by --message-hops, --reach-world, --search, --trail, --centre,
  // --geodesic-length, --reach-detour, --reach-broad, --reach-second and
  // --neighbour-cap, which may change an --init model
  network->Add(&o->network, {"message_hops", "reach_world", "search", "trail",
                             "centre", "geodesic_length", "reach_detour",
                             "reach_broad", "reach_second", "neighbour_cap"});
  cmd->add_flag("--resume", o->resume,
                "continue from OUT.ckpt (same options) if it is there");
  auto validate = std::make_shared<std::string>();
  cmd->add_option("--validate", *validate,
                  "train nothing: the loss and accuracy of this model on the "
                  "held-out worlds of --data (same --val-share and --seed)")
      ->check(kPath);
  cmd->add_flag("--quiet", *quiet, "no progress lines");
  return [=]() {
    if (!cmd->parsed()) return -1;
    declared->Apply();
    network->Apply();
    o->progress = !*quiet;
    // A model read (--init, --validate) brings its own network: a network
    // flag beside it would be ignored, so it is refused.
    for (const std::string& flag : network->Given()) {
      if (!o->init.empty() || !validate->empty())
        throw aia::InputError::Flag(
            flag,
            "the network is the one of the " +
                std::string(!validate->empty() ? "--validate" : "--init") +
                " model; drop the flag (or --init, for a new network)");
    }
    if (!validate->empty()) {
      // It trains nothing: a flag of training or of a network to extend
      // would be ignored, so it is refused.
      static const std::set<std::string> kRead = {
          "--data",        "--validate", "--val-share", "--seed",
          "--valid-moves", "--threads",  "--quiet"};
      for (const CLI::Option* opt : cmd->get_options()) {
        const std::string name = opt->get_name();
        if (opt->count() > 0 && !kRead.count(name))
          throw aia::InputError::Flag(
              name,
              "--validate trains nothing and scores the model as it is "
              "(it reads --data, --val-share, --seed, --valid-moves and "
              "--threads); drop the flag");
      }
      // --threads as training takes it (0: libtorch's default).
      aia::SetInferenceThreads(o->threads);
      const aia::ValidationResult v = aia::Validate(
          *validate, o->data, o->val_share, o->seed, o->valid_moves != 0);
      char useful[64] = "none of them with useful work";
      if (!std::isnan(v.acc_useful))
        std::snprintf(useful, sizeof useful,
                      "accuracy on samples with useful work %.4f",
                      v.acc_useful);
      std::printf("%s: %ld held-out samples: loss %.4f, accuracy %.4f, %s\n",
                  validate->c_str(), v.samples, v.loss, v.acc, useful);
      return 0;
    }
    const std::vector<aia::EpochLog> logs = aia::Train(*o);
    if (o->epochs == 0)
      std::printf("[aia train] %s: the weights of %s, no training\n",
                  o->out.c_str(), o->init.c_str());
    if (!logs.empty()) {
      const aia::EpochLog& e = logs.back();
      double seconds = 0.0;
      for (const aia::EpochLog& l : logs) seconds += l.seconds;
      std::printf("[aia train] %s: %d epochs, %s, %.0f s training; log %s\n",
                  o->out.c_str(), e.epoch, aia::ValidationText(e).c_str(),
                  seconds, aia::TrainLogPath(o->out).c_str());
    }
    return 0;
  };
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

// Output that did not reach standard output (a full disk, /dev/full, a
// closed descriptor) fails the command: `code` when it failed already,
// else 1, after one `error:` line.
int CheckStandardOutput(int code) {
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  if (flushed && !std::ferror(stdout)) return code;
  int err = flushed ? 0 : errno;
  if (err == 0) {
    // An earlier write failed and stdio kept no errno: ask again with an
    // empty write.
    errno = 0;
    if (::write(STDOUT_FILENO, "", 0) < 0) err = errno;
  }
  std::fprintf(stderr, "error: cannot write to standard output: %s\n",
               err != 0 ? std::strerror(err) : "a write failed");
  return code == 0 ? 1 : code;
}

// "--sed: unknown option (did you mean `--seed`?)" for the first word of
// the command line that reads as a long flag (`--name` or `--name=value`)
// and is no flag of the command given (nor of aia itself); "" where there is
// none.
std::string UnknownFlag(const CLI::App& app, int argc, char** argv) {
  std::vector<std::string> flags;
  const auto add = [&](const CLI::App& a) {
    for (const CLI::Option* o : a.get_options())
      for (const std::string& name : o->get_lnames())
        flags.push_back("--" + name);
  };
  add(app);
  for (const CLI::App* sub : app.get_subcommands()) add(*sub);
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--") break;  // what follows is no flag
    if (word.size() < 3 || word.compare(0, 2, "--") != 0) continue;
    const std::string flag = word.substr(0, word.find('='));
    bool known = false;
    for (const std::string& f : flags) known = known || f == flag;
    if (known) continue;
    const std::string closest = aia::field_text::ClosestName(flag, flags);
    return aia::OneLine(flag) + ": unknown option" +
           (closest.empty() ? "" : " (did you mean `" + closest + "`?)");
  }
  return "";
}

}  // namespace

int aia::CliMain(int argc, char** argv) {
  CLI::App app{"aia: multi-robot Active Information Acquisition testbed"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "aia 0.1.0");
  const std::vector<Action> commands = {
      AddRunCommand(app),     AddRenderCommand(app), AddPlanCommand(app),
      AddWorldCommand(app),   AddEvalCommand(app),   AddBenchCommand(app),
      AddDatasetCommand(app), AddTrainCommand(app),  AddPoliciesCommand(app),
      AddSchemaCommand(app)};
  // A first word that names no command: CLI11 would say only that a
  // command is required.
  if (argc > 1 && argv[1][0] != '-') {
    std::vector<std::string> all;
    std::string names;
    for (const CLI::App* sub : app.get_subcommands({})) {
      all.push_back(sub->get_name());
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (std::find(all.begin(), all.end(), argv[1]) == all.end()) {
      const std::string closest = aia::field_text::ClosestName(argv[1], all);
      std::fprintf(
          stderr,
          "error: command line: '%s' is not a command%s; the "
          "commands are %s (aia --help lists them)\n",
          aia::OneLine(argv[1]).c_str(),
          closest.empty() ? "" : (" (did you mean `" + closest + "`?)").c_str(),
          names.c_str());
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help, --version
    if (e.get_exit_code() == 0) return CheckStandardOutput(app.exit(e));
    // One `error:` line like any bad input, with where to look.
    std::string what = e.what();  // CLI11 breaks some messages in lines
    for (char& c : what)
      if (c == '\n' || c == '\r') c = ' ';
    while (!what.empty() && what.back() == ' ') what.pop_back();
    what = aia::OneLine(what);
    std::string help = "aia --help";
    for (const CLI::App* sub : app.get_subcommands())
      help = "aia " + sub->get_name() + " --help";
    // An unknown flag is what is wrong, named with the command's flag it is
    // a typo of (CLI11 lists every word it did not expect, values
    // included, or says that a command is required after `aia --verison`).
    const std::string flag = UnknownFlag(app, argc, argv);
    if (!flag.empty()) what = flag;
    // A flag given twice, in aia's words (CLI11: "--seed: At Most 1
    // required but received 2").
    const std::string twice = ": At Most 1 required but received ";
    if (const std::size_t at = what.find(twice); at != std::string::npos)
      what = what.substr(0, at) + ": given " + what.substr(at + twice.size()) +
             " times; give it once";
    std::fprintf(stderr, "error: command line: %s (%s lists the options)\n",
                 what.c_str(), help.c_str());
    return 2;
  }
  try {
    for (const Action& run : commands) {
      const int code = run();
      if (code >= 0) return CheckStandardOutput(code);
    }
  } catch (const aia::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.Format().c_str());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "error: out of memory (a smaller scenario, fewer threads, "
                 "or a machine with more memory)\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", aia::OneLine(e.what()).c_str());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "error: an unknown failure ended aia\n");
    return 1;
  }
  return 0;
}
