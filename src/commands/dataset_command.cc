#include "aia/commands/dataset_command.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <stdexcept>
#include <thread>

#include "aia/core/clock.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/io.h"
#include "aia/core/rng.h"
#include "aia/estimation/heatmap.h"
#include "aia/learning/dataset.h"
#include "aia/planning/expert.h"
#include "aia/planning/search.h"
#include "aia/runtime/generated.h"
#include "aia/runtime/mission.h"

namespace aia {
namespace {

using Clock = std::chrono::steady_clock;

// A shadow expert plans from scratch at every step it labels (the acting
// policy is never where its plan says), so it labels only the steps that
// are kept: step 0, and `count` distinct steps of [1, T) with T = 3 F0
// (F0: the depth of its plan from step 0; the success horizon), at least
// count + 1 and at most max_steps, drawn from the episode's own stream (an
// episode that ends sooner keeps fewer).
std::vector<int> StepsToLabel(int count, int max_steps, int depth,
                              std::uint64_t seed) {
  Rng rng(seed, "dataset/label");
  const int horizon = std::min(max_steps, std::max(3 * depth, count + 1));
  std::vector<int> order(std::max(horizon - 1, 0));
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = static_cast<int>(i) + 1;
  const int keep = std::clamp(count, 0, static_cast<int>(order.size()));
  for (int i = 0; i < keep; ++i)
    std::swap(order[i], order[i + rng.UniformInt(order.size() - i)]);
  order.resize(keep);
  std::sort(order.begin(), order.end());
  return order;
}

// Records every decision step's samples; labels them with the expert.
class DatasetObserver : public StepObserver {
 public:
  // With a shadow: it labels `keep` steps, step 0 and keep - 1 drawn
  // (named stream of `seed`) once its first plan says how long the mission
  // should take; the others it only watches.
  DatasetObserver(ExpertPolicy* shadow, std::int64_t episode, int stop_after,
                  double max_seconds, int keep = 0, int max_steps = 0,
                  std::uint64_t seed = 0)
      : shadow_(shadow),
        keep_(keep),
        max_steps_(max_steps),
        seed_(seed),
        episode_(episode),
        stop_after_(stop_after),
        max_seconds_(max_seconds),
        start_(Clock::now()) {}

  void OnStart(const Episode& e) override {
    if (shadow_) {
      shadow_->Reset(e.world().map, e.world().NumRobots(),
                     e.world().NumTargets(), e.scenario().seed);
      expert_ = shadow_;
    } else {
      expert_ = dynamic_cast<const ExpertPolicy*>(&e.policy());
    }
  }

  ObserverStatus OnDecision(const Episode& e, const DecisionContext& ctx,
                            const Decision& d) override {
    if (stop_after_ >= 0 && ctx.step >= stop_after_) {
      killed_ = true;
      return ObserverStatus::kStop;
    }
    if (max_seconds_ > 0.0 && SecondsSince(start_) > max_seconds_) {
      over_time_ = true;
      return ObserverStatus::kStop;
    }
    const int n = e.world().NumRobots();
    const Lattice& lattice = ctx.map->lattice();
    // Every robot's search points, as a network that learns to search keeps
    // them (learning/channels.h, ChannelParams::search).
    if (search_.num_robots() != n ||
        search_.num_targets() != e.world().NumTargets())
      search_.Reset(n, e.world().NumTargets());
    active_.clear();
    for (int i = 0; i < n; ++i)
      if (ctx.comm->Active(i)) active_.push_back(i);
    // Read as the shipped models' data were recorded: a belief that shrank
    // ends a search (no measurements in the context), so that their recipes
    // reproduce them; the policies read the robots' own measurements.
    DecisionContext recorded = ctx;
    recorded.measurements = nullptr;
    for (int i : active_) search_.Update(recorded, i);
    search_.Share(recorded, active_);
    const std::vector<Move>* labels = &d.wanted;
    if (shadow_) {
      if (ctx.step > 0 && !std::binary_search(label_steps_.begin(),
                                              label_steps_.end(), ctx.step)) {
        shadow_->Observe(ctx);  // a full plan only where a label is kept
        return ObserverStatus::kContinue;
      }
      labels_.assign(n, Move::kStay);
      shadow_->Decide(ctx, &labels_);
      labels = &labels_;
      if (ctx.step == 0) {
        const int depth =
            std::max(0, static_cast<int>(shadow_->plan().configs.size()) - 1);
        label_steps_ = StepsToLabel(keep_ - 1, max_steps_, depth, seed_);
      }
    }
    std::vector<DatasetSample> step;
    for (int i = 0; i < n; ++i) {
      if (!ctx.comm->Active(i) || (*labels)[i] == Move::kStay) continue;
      DatasetSample s;
      s.episode = episode_;
      s.step = ctx.step;
      s.robot = i;
      s.position = lattice.Point((*ctx.robot_lattice)[i]);
      for (int j : ctx.comm->Neighbors(i))
        if (j != i)
          s.neighbours.push_back(lattice.Point((*ctx.robot_lattice)[j]));
      HeatSources(*ctx.beliefs, i, &s.targets);
      for (int k = 0; k < search_.num_targets(); ++k) {
        if (search_.Points(i, k).empty()) continue;
        if (s.search.empty()) s.search.resize(search_.num_targets());
        s.search[k] = search_.Points(i, k);
      }
      s.label = (*labels)[i];
      s.came = ctx.history ? ctx.history->last(i) : Move::kStay;
      s.useful = expert_ && expert_->LastMoveUseful(i);
      s.acted = d.wanted[i];
      step.push_back(std::move(s));
    }
    steps_.push_back(std::move(step));
    return ObserverStatus::kContinue;
  }

  std::vector<std::vector<DatasetSample>>& steps() { return steps_; }
  // Stopped past --max-seconds: the world is recorded, its samples dropped.
  bool over_time() const { return over_time_; }
  // Stopped by the test hook (DatasetOptions::stop_after_episodes): the run
  // ends here, as if killed.
  bool killed() const { return killed_; }

 private:
  ExpertPolicy* shadow_;
  int keep_, max_steps_;
  std::uint64_t seed_;
  std::vector<int> label_steps_;
  const ExpertPolicy* expert_ = nullptr;  // whose plan says what is useful
  std::int64_t episode_;
  int stop_after_;
  double max_seconds_;
  Clock::time_point start_;
  bool over_time_ = false;
  bool killed_ = false;
  std::vector<Move> labels_;
  std::vector<std::vector<DatasetSample>> steps_;
  SearchPoints search_;
  std::vector<int> active_;
};

// `keep` random decision steps of an episode (all when fewer), in step
// order, drawn from the episode's own stream.
std::vector<DatasetSample> KeptSamples(
    std::vector<std::vector<DatasetSample>>* steps, int keep_at_most,
    std::uint64_t seed) {
  std::vector<int> order(steps->size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  Rng rng(seed, "dataset/keep");
  const int keep = std::min<int>(keep_at_most, static_cast<int>(order.size()));
  for (int i = 0; i < keep; ++i)
    std::swap(order[i], order[i + rng.UniformInt(order.size() - i)]);
  order.resize(keep);
  std::sort(order.begin(), order.end());
  std::vector<DatasetSample> kept;
  for (int i : order)
    for (DatasetSample& d : (*steps)[i]) kept.push_back(std::move(d));
  return kept;
}

// The world record of episode `e` (flowtime -1 when it was stopped over
// time).
DatasetWorld EpisodeWorld(const Episode& episode, int e, bool over_time) {
  const World& w = episode.world();
  DatasetWorld world;
  world.episode = e;
  world.seed = static_cast<std::int64_t>(episode.scenario().seed);
  world.size = w.map.size();
  world.map_cell = w.map.occupancy().cell();
  world.lattice_step = w.map.lattice().step();
  world.robot_radius = w.map.robot_radius();
  world.eps = episode.mission().eps;
  world.robots = w.NumRobots();
  world.targets = w.NumTargets();
  world.steps = episode.step();
  world.flowtime = over_time ? -1 : episode.flowtime();
  world.obstacles = w.map.obstacles();
  world.log_det_prior = episode.log_det_prior();
  return world;
}

// The recipe of another shard of the folder ("" for an empty file: no
// recipe yet). A shard that another writer holds (an mpirun's other rank,
// started at the same moment) may not have its tables yet: read again
// until it has, while that writer holds it (kShardWait at most).
constexpr auto kShardWait = std::chrono::seconds(10);

std::string OtherShardRecipe(const std::string& path) {
  const auto until = std::chrono::steady_clock::now() + kShardWait;
  while (true) {
    std::error_code ec;
    if (std::filesystem::file_size(path, ec) == 0 && !ec) return "";
    try {
      return DatasetRecipe(path, "--out");
    } catch (const InputError&) {
      if (!LockedByAnotherProcess(path) ||
          std::chrono::steady_clock::now() > until)
        throw;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// One shard set per folder, of one recipe: `aia train --data` reads them
// all, sets of two counts hold the same episodes, and shards written with
// other options would be mixed (each shard checks its own on resume).
void CheckOneShardSet(const std::string& out, int shards,
                      const std::string& file, const std::string& recipe) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(out, ec)) {
    const std::string path = entry.path().string();
    const int n = ShardCount(path);
    if (n != 0 && n != shards)
      throw InputError::Flag(
          "--shard", out + " holds shards of a set of " + std::to_string(n) +
                         " ('" + path + "'), not of " + std::to_string(shards) +
                         ": use the same N, or another folder");
    if (n == 0 ||
        entry.path().filename() == std::filesystem::path(file).filename())
      continue;
    const std::string other = OtherShardRecipe(path);
    if (!other.empty() && other != recipe)
      throw InputError::Flag(
          "--out", out + " holds '" + path + "', written with other options (" +
                       other + "); this shard's would be " + recipe +
                       ": use the same options, or another folder");
  }
}

// The generated scenario of the episodes (seed: the first one) with the
// flags' overrides: --policy, --set (not of what the episodes set), --model,
// --max-steps.
GeneratedSpec DatasetSpec(const DatasetOptions& o) {
  GeneratedSpec spec;
  spec.size = o.size.ToText();
  spec.size_flag = "--size";
  spec.robots = o.size.robots;
  spec.targets = o.size.targets;
  spec.seed = o.first_seed;
  spec.overrides = {{"--policy", "policy.name", o.policy}};
  for (Override& ov : ParseSetFlags(o.sets)) {
    RefuseSetOfFlagKey(ov, "seed", "--first-seed");
    RefuseSetOfFlagKey(ov, "robots.count", "--size");
    RefuseSetOfFlagKey(ov, "targets.count", "--size");
    RefuseSetOfFlagKey(ov, "policy.name", "--policy");
    if (o.max_steps > 0)
      RefuseSetOfFlagKey(ov, "mission.max_steps", "--max-steps");
    if (!o.model.empty()) RefuseSetOfFlagKey(ov, "policy.model", "--model");
    if (ov.path == "mission.decisions" && ov.value != "lockstep")
      throw InputError::Flag("--set",
                             "mission.decisions " + ov.value +
                                 ": datasets record lockstep decisions (the "
                                 "expert labels the whole team's step)");
    spec.overrides.push_back(ov);
  }
  if (!o.model.empty())
    spec.overrides.push_back({"--model", "policy.model", o.model});
  if (o.max_steps > 0)
    spec.overrides.push_back(
        {"--max-steps", "mission.max_steps", std::to_string(o.max_steps)});
  return spec;
}

// The options an episode's data depend on, kept in the shard and compared on
// resume; `model`: the acting policy's model file (null for a policy
// without one), named by its content, so that a model retrained or resolved
// elsewhere (the default's path from another folder) is not mixed in.
std::string Recipe(const DatasetOptions& o, const FileIdentity* model) {
  std::string r =
      "size=" + o.size.ToText() +
      " first_seed=" + std::to_string(o.first_seed) +
      " keep=" + std::to_string(o.keep) + " policy=" + o.policy +
      // A model counts by its content (below), not by the path it was given.
      " model=" + (model ? std::string() : o.model) +
      " max_steps=" + std::to_string(o.max_steps) +
      (o.max_seconds > 0.0 ? " max_seconds=" + FormatNumber(o.max_seconds)
                           : std::string()) +
      " shards=" + std::to_string(o.shard.count);
  for (const std::string& s : o.sets) r += " set=" + s;
  if (model) r += " model_sha256=" + model->sha256;
  return r;
}

// What every episode of the shard shares.
struct DatasetSetup {
  PolicyRegistry registry;
  GeneratedSpec spec;  // the episodes' scenario (seed: the first episode's)
  Scenario base;       // spec read
  std::shared_ptr<const PolicySpec> acting;  // --policy
  std::shared_ptr<const PolicySpec> expert;  // the shadow that labels
};

// The flags checked, the policies resolved and the world of the first seed
// built now: a size the world cannot hold is bad input before any work (the
// episodes' other seeds are named as they come).
DatasetSetup PrepareDataset(const DatasetOptions& o) {
  if (o.out.empty()) throw InputError::Flag("--out", "is required");
  {
    DatasetOptions flags = o;
    CheckFlags(&flags);  // their declarations: `--flag: what`
  }
  DatasetSetup d;
  d.registry = AllPolicies();
  if (!d.registry.Has(o.policy))
    throw InputError::Flag("--policy", d.registry.UnknownPolicy(o.policy));
  d.spec = DatasetSpec(o);
  d.base = ReadGenerated(d.spec);
  d.acting = d.registry.Resolve(d.base);
  if (!o.model.empty() && d.acting->model_file() == nullptr)
    throw InputError::Flag(
        "--model", "policy " + o.policy +
                       " reads no model (a learned policy does: igbnet)");
  Scenario expert_scenario = d.base;
  expert_scenario.policy.name = "expert";
  expert_scenario.policy.params = ConfigNode();
  d.expert = d.registry.Resolve(expert_scenario);
  BuildGenerated(d.base, d.spec);
  return d;
}

// The shard's file, checked and locked: DIR/shard-I-of-N.sqlite.
std::string OpenShard(const DatasetOptions& o, const DatasetSetup& d,
                      const std::string& recipe) {
  const std::string file = o.out + "/shard-" + std::to_string(o.shard.index) +
                           "-of-" + std::to_string(o.shard.count) + ".sqlite";
  // The shard and SQLite's files beside it: a FIFO there would block SQLite.
  CheckOutputFiles({file, file + "-journal", file + "-wal", file + "-shm"},
                   "--out", "the shard written");
  MakeOutputDir(o.out, "--out");
  CheckNotAnInput(file, "--out", MissionInputs(d.base, d.acting.get()),
                  "the shard written");
  CheckOneShardSet(o.out, o.shard.count, file, recipe);
  // One writer per shard (the ranks of an mpirun share the folder): an
  // flock on the shard file itself, which SQLite's own (fcntl) locks leave
  // alone; an empty new file is an empty database to SQLite.
  LockOutput(file, "--out");
  return file;
}

// One episode of the dataset: its world record and the samples kept (none
// when it went over --max-seconds), or killed (a test's stop).
struct DatasetEpisode {
  bool killed = false;
  bool over_time = false;
  DatasetWorld world;
  std::vector<DatasetSample> kept;
};

// Runs episode e (seed first_seed + e) with the acting policy, the expert's
// shadow labelling each decision; `stop` makes the observer stop it (the
// tests' --stop-after-episodes).
DatasetEpisode RunDatasetEpisode(const DatasetOptions& o, const DatasetSetup& d,
                                 int e, bool stop) {
  Scenario s = d.base;
  s.seed = o.first_seed + static_cast<std::uint64_t>(e);
  std::unique_ptr<Policy> shadow_owner;
  ExpertPolicy* shadow = nullptr;
  if (o.policy != "expert") {
    shadow_owner = d.expert->Create();
    shadow = dynamic_cast<ExpertPolicy*>(shadow_owner.get());
  }
  GeneratedSpec spec = d.spec;
  spec.seed = s.seed;
  const std::shared_ptr<const Instance> instance = BuildGenerated(s, spec);
  Episode episode(instance, d.acting->Create());
  DatasetObserver observer(shadow, e, stop ? 3 : -1, o.max_seconds, o.keep,
                           instance->scenario.mission.max_steps, s.seed);
  episode.AddObserver(&observer);
  episode.Run();
  DatasetEpisode out;
  if (observer.killed()) {
    out.killed = true;
    return out;
  }
  out.over_time = observer.over_time();
  if (!out.over_time) out.kept = KeptSamples(&observer.steps(), o.keep, s.seed);
  out.world = EpisodeWorld(episode, e, out.over_time);
  return out;
}

}  // namespace

void DatasetOptions::Validate(const FieldChecker& c) const {
  const std::string why =
      SeedRangeProblem(first_seed, episodes, "--episodes", "--first-seed");
  if (!why.empty()) c.Fail(first_seed, why);
}

int RunDataset(const DatasetOptions& o) {
  const DatasetSetup d = PrepareDataset(o);
  const std::string recipe = Recipe(o, d.acting->model_file());
  const std::string file = OpenShard(o, d, recipe);
  DatasetWriter writer(file, recipe, "--out");

  std::vector<int> todo;
  for (int e = o.shard.index; e < o.episodes; e += o.shard.count)
    if (!writer.done().count(e)) todo.push_back(e);
  const int mine =
      (o.episodes - o.shard.index + o.shard.count - 1) / o.shard.count;
  ProgressLine line(o.progress);
  const auto t0 = Clock::now();
  int written = 0, skipped = 0;
  long samples = 0;
  for (int e : todo) {
    DatasetEpisode episode = RunDatasetEpisode(
        o, d, e,
        o.stop_after_episodes >= 0 && written >= o.stop_after_episodes);
    if (episode.killed) {
      line.Finish();
      return written;
    }
    skipped += episode.over_time ? 1 : 0;
    writer.WriteEpisode(episode.world, episode.kept);
    ++written;
    samples += static_cast<long>(episode.kept.size());
    const double secs = SecondsSince(t0);
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "[aia dataset] shard %d/%d  episode %zu/%d  %ld samples  "
                  "%.2f episodes/s",
                  o.shard.index, o.shard.count, writer.done().size(), mine,
                  samples, written / std::max(secs, 1e-9));
    line.Update(buf);
  }
  line.Finish();
  const double secs = SecondsSince(t0);
  std::string skip;
  if (o.max_seconds > 0.0)
    skip = ", " + std::to_string(skipped) + " skipped (over --max-seconds " +
           FormatNumber(o.max_seconds) + ")";
  // A folder made with a larger --episodes keeps them all (aia train reads
  // every one): say so rather than "30 of 20 done".
  if (writer.done().size() > static_cast<std::size_t>(mine))
    skip += "; the shard holds " + std::to_string(writer.done().size()) +
            " episodes, more than the " + std::to_string(mine) +
            " asked for, and aia train reads them all";
  std::printf(
      "[aia dataset] %s: %d episodes written now (%zu of %d done)%s, %ld "
      "samples, %.1f s, %.2f episodes/s\n",
      file.c_str(), written, writer.done().size(), mine, skip.c_str(), samples,
      secs, written / std::max(secs, 1e-9));
  return written;
}

}  // namespace aia
