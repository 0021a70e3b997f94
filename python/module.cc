// aia._aia: the C++ core of the Python package (python/aia/__init__.py
// wraps it; docs/python.md). A Mission is one episode of the same loop as
// `aia run` (runtime/episode.h) whose moves come from Python; a builtin
// policy is a registered policy deciding on a mission's state with the
// same truth fence as in the loop.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "aia/commands/episode_picture.h"
#include "aia/commands/eval.h"
#include "aia/core/error.h"
#include "aia/core/field_io.h"
#include "aia/core/field_values.h"
#include "aia/core/interrupt.h"
#include "aia/core/rng.h"
#include "aia/core/thread_pool.h"
#include "aia/estimation/heatmap.h"
#include "aia/learning/channels.h"
#include "aia/learning/dataset.h"
#include "aia/planning/policy.h"
#include "aia/planning/registry.h"
#include "aia/runtime/episode.h"
#include "aia/runtime/generated.h"
#include "aia/runtime/instance.h"
#include "aia/runtime/mission.h"
#include "aia/runtime/observers.h"
#include "aia/runtime/policies.h"
#include "aia/scenario/loader.h"
#include "aia/scenario/yaml.h"

namespace py = pybind11;

namespace aia {
namespace python {
namespace {

// (key path, YAML text) pairs, as Python's wrapper passes `overrides`.
using KeyValues = std::vector<std::pair<std::string, std::string>>;

std::vector<Override> AsOverrides(const KeyValues& pairs,
                                  const std::string& flag_prefix) {
  std::vector<Override> out;
  for (const auto& [key, value] : pairs)
    out.push_back({flag_prefix + key, key, value});
  return out;
}

// The moves of the next step, set from Python.
class ExternalPolicy : public NamedPolicy<ExternalPolicy> {
 public:
  static constexpr std::string_view kName = "python";
  void Reset(const Map&, int, int, std::uint64_t) override {}
  PolicyStatus Decide(const DecisionContext&,
                      std::vector<Move>* moves) override {
    *moves = next;
    return PolicyStatus::kOk;
  }
  std::vector<Move> next;
};

// A move from Python: 0 (left), 1 (right), 2 (up), 3 (down) or 4 (stay);
// `where` names it in the error ("3" for moves[3]).
Move ToMove(long long m, const std::string& where) {
  if (m < 0 || m > 4)
    throw py::value_error("moves[" + where +
                          "]: must be 0 (left), 1 (right), 2 (up), 3 (down) "
                          "or 4 (stay), got " +
                          std::to_string(m));
  return static_cast<Move>(m);
}

// Moves from Python: one per robot.
std::vector<Move> MovesFrom(const py::array_t<long long>& moves, int n) {
  const py::buffer_info b = moves.request();
  if (b.ndim != 1 || b.shape[0] != n)
    throw py::value_error(
        "moves: must be one move per robot (" + std::to_string(n) +
        "), got shape " +
        py::str(py::tuple(py::cast(b.shape))).cast<std::string>());
  std::vector<Move> out(n);
  const auto view = moves.unchecked<1>();
  for (int i = 0; i < n; ++i) out[i] = ToMove(view(i), std::to_string(i));
  return out;
}

template <typename T>
py::array_t<T> Array(std::vector<py::ssize_t> shape) {
  return py::array_t<T>(shape);
}

// Channel settings from Python (key, YAML text) pairs, read as a model's
// metadata is: `channels: window: must be an integer in [4, 512], got 2`.
ChannelParams ChannelSettings(const KeyValues& params) {
  ChannelParams settings;
  ConfigNode node = ConfigNode::Map();
  for (const auto& [key, value] : params)
    node.Set(key, ParseYamlValue(value, "channels: " + key));
  ReadFields(node, ReadOptions{"channels", "", ""}, "", &settings);
  return settings;
}

std::atomic<std::uint64_t> g_next_mission_id{1};

// One mission, owned (its own episode, stepped from Python) or a view of a
// decision inside aia's own loop (evaluate), valid during that call only.
class Mission {
 public:
  Mission(const std::string& scenario, std::optional<std::uint64_t> seed,
          const KeyValues& overrides)
      : id_(g_next_mission_id++) {
    std::vector<Override> all;
    if (seed) all.push_back({"seed", "seed", std::to_string(*seed)});
    for (const Override& o : AsOverrides(overrides, "overrides: "))
      all.push_back(o);
    instance_ = BuildInstance(LoadScenario(scenario, all));
    auto policy = std::make_unique<ExternalPolicy>();
    external_ = policy.get();
    episode_ = std::make_unique<Episode>(instance_, std::move(policy));
    episode_->AddObserver(&moves_);
    episode_->AddObserver(&estimate_);
    moves_.OnStart(*episode_);
    estimate_.OnStart(*episode_);
    seed_ = episode_->scenario().seed;
    max_steps_ = episode_->mission().max_steps;
  }
  Mission(const DecisionContext* view, std::uint64_t seed, std::uint64_t id,
          int max_steps)
      : id_(id), view_(view), seed_(seed), max_steps_(max_steps) {}

  bool owned() const { return episode_ != nullptr; }
  void Invalidate() { view_ = nullptr; }
  std::uint64_t id() const { return id_; }
  std::uint64_t seed() const { return seed_; }
  int max_steps() const { return max_steps_; }
  // What a policy is given now (the team's belief included).
  DecisionContext Context() const {
    if (owned()) return episode_->Context();
    if (view_ == nullptr)
      throw py::value_error(
          "this mission is a view of one decision of aia.evaluate: it is "
          "valid only inside the policy's call");
    return *view_;
  }
  const Episode& episode() const {
    if (!owned())
      throw py::value_error(
          "a mission seen by a policy inside aia.evaluate can only be read "
          "(state(), num_robots, ...); aia steps it");
    return *episode_;
  }
  int num_robots() const {
    return static_cast<int>(Context().robot_lattice->size());
  }
  int num_targets() const { return Context().beliefs->layout().num_targets(); }
  int step() const { return Context().step; }
  bool done() const { return owned() && episode_->done(); }
  bool success() const { return owned() && episode_->success(); }
  int flowtime() const { return owned() ? episode_->flowtime() : -1; }

  // What the robots know (the context's arrays), and for an owned mission
  // the ground truth apart.
  py::dict State() const {
    const DecisionContext ctx = Context();
    const int n = num_robots(), m = num_targets();
    const Lattice& lattice = ctx.map->lattice();
    auto positions = Array<double>({n, 2});
    auto headings = Array<double>({n});
    auto lattice_index = Array<long long>({n});
    auto cells = Array<long long>({n, 2});
    auto active = Array<bool>({n});
    auto neighbors = Array<bool>({n, n});
    auto mean = Array<double>({n, m, 2});
    auto cov = Array<double>({n, m, 2, 2});
    auto det = Array<double>({n, m});
    auto log_det_prior = Array<double>({m});
    auto p = positions.mutable_unchecked<2>();
    auto h = headings.mutable_unchecked<1>();
    auto li = lattice_index.mutable_unchecked<1>();
    auto c = cells.mutable_unchecked<2>();
    auto a = active.mutable_unchecked<1>();
    auto g = neighbors.mutable_unchecked<2>();
    auto mu = mean.mutable_unchecked<3>();
    auto sigma = cov.mutable_unchecked<4>();
    auto d = det.mutable_unchecked<2>();
    auto prior = log_det_prior.mutable_unchecked<1>();
    const BeliefSet& beliefs = *ctx.beliefs;
    for (int i = 0; i < n; ++i) {
      const int q = (*ctx.robot_lattice)[i];
      const Vec2 x =
          ctx.robot_positions ? (*ctx.robot_positions)[i] : lattice.Point(q);
      p(i, 0) = x.x();
      p(i, 1) = x.y();
      h(i) = ctx.robot_headings ? (*ctx.robot_headings)[i] : 0.0;
      li(i) = q;
      c(i, 0) = lattice.Ix(q);
      c(i, 1) = lattice.Iy(q);
      a(i) = ctx.comm->Active(i);
      for (int j = 0; j < n; ++j) g(i, j) = false;
      for (int j : ctx.comm->Neighbors(i)) g(i, j) = true;
      for (int k = 0; k < m; ++k) {
        const Vec2 xk = beliefs.PositionMean(i, k);
        const Mat2 s = beliefs.PositionCovariance(i, k);
        mu(i, k, 0) = xk.x();
        mu(i, k, 1) = xk.y();
        for (int r = 0; r < 2; ++r)
          for (int col = 0; col < 2; ++col) sigma(i, k, r, col) = s(r, col);
        d(i, k) = beliefs.DetCovariance(i, k);
      }
    }
    for (int k = 0; k < m; ++k)
      prior(k) = ctx.log_det_prior ? (*ctx.log_det_prior)[k] : 0.0;
    py::dict state;
    state["step"] = ctx.step;
    state["positions"] = positions;
    state["headings"] = headings;
    state["lattice"] = lattice_index;
    state["cells"] = cells;
    state["active"] = active;
    state["neighbors"] = neighbors;
    state["mean"] = mean;
    state["cov"] = cov;
    state["det"] = det;
    state["log_det_prior"] = log_det_prior;
    state["eps"] = ctx.eps;
    state["workspace"] =
        py::make_tuple(ctx.map->size().x(), ctx.map->size().y());
    if (owned()) {
      auto truth_positions = Array<double>({m, 2});
      auto t = truth_positions.mutable_unchecked<2>();
      for (int k = 0; k < m; ++k) {
        t(k, 0) = episode_->target_positions()[k].x();
        t(k, 1) = episode_->target_positions()[k].y();
      }
      py::dict truth;
      truth["target_positions"] = truth_positions;
      state["truth"] = truth;
    }
    return state;
  }

  // I-GBNet's input of every robot, (N, C, H, W) float32, from the C++
  // renderer (learning/channels.h) with these channel settings; the heat of
  // each robot's own fused belief, its neighbours from this step's graph.
  py::array_t<float> Channels(const KeyValues& params) const {
    const ChannelParams settings = ChannelSettings(params);
    const DecisionContext ctx = Context();
    const Map& map = *ctx.map;
    const Lattice& lattice = map.lattice();
    ChannelRenderer renderer(map.occupancy(), map.size(), settings, &lattice);
    const int n = num_robots();
    py::array_t<float> out({static_cast<py::ssize_t>(n),
                            static_cast<py::ssize_t>(renderer.channels()),
                            static_cast<py::ssize_t>(renderer.height()),
                            static_cast<py::ssize_t>(renderer.width())});
    float* data = out.mutable_data();
    std::vector<Vec2> neighbours;
    std::vector<HeatSource> targets;
    const std::vector<double> no_prior(num_targets(), 0.0);
    const std::vector<double>& prior =
        ctx.log_det_prior ? *ctx.log_det_prior : no_prior;
    py::gil_scoped_release release;
    for (int i = 0; i < n; ++i) {
      neighbours.clear();
      for (int j : ctx.comm->Neighbors(i))
        if (j != i)
          neighbours.push_back(lattice.Point((*ctx.robot_lattice)[j]));
      HeatSources(*ctx.beliefs, i, &targets);
      renderer.Render(lattice.Point((*ctx.robot_lattice)[i]), neighbours,
                      targets, prior, ctx.eps, data + i * renderer.ImageSize());
    }
    return out;
  }

  // An RGB frame (H, W, 3) of the physics now with aia render's overlays.
  // The renderer is made at the first call (and again for another size);
  // the trails start there.
  py::array_t<std::uint8_t> Render(int width, int height) {
    const Episode& e = episode();  // owned only
    if (width < 16 || height < 16 || width > 8192 || height > 8192)
      throw py::value_error(
          "render: width and height must be in [16, 8192], "
          "got " +
          std::to_string(width) + " x " + std::to_string(height));
    if (!picture_ || width != picture_width_ || height != picture_height_) {
      picture_.reset();
      FrameSettings settings;
      settings.scene.width = width;
      settings.scene.height = height;
      renderer_ =
          std::make_unique<FrameRenderer>(e.sim(), e.world().map, settings);
      picture_ = std::make_unique<PictureObserver>(e, renderer_.get());
      if (!picture_added_) {
        episode_->AddObserver(&picture_forward_);
        picture_added_ = true;
      }
      picture_width_ = width;
      picture_height_ = height;
    }
    const cv::Mat& bgr = picture_->picture.Render(e);
    py::array_t<std::uint8_t> out({static_cast<py::ssize_t>(bgr.rows),
                                   static_cast<py::ssize_t>(bgr.cols),
                                   static_cast<py::ssize_t>(3)});
    auto v = out.mutable_unchecked<3>();
    for (int y = 0; y < bgr.rows; ++y) {
      const std::uint8_t* row = bgr.ptr<std::uint8_t>(y);
      for (int x = 0; x < bgr.cols; ++x)
        for (int c = 0; c < 3; ++c) v(y, x, c) = row[3 * x + 2 - c];
    }
    return out;
  }

  // (N, 4): which of each robot's moves stay on the lattice.
  py::array_t<bool> ValidMoves() const {
    const DecisionContext ctx = Context();
    const Lattice& lattice = ctx.map->lattice();
    const int n = num_robots();
    auto out = Array<bool>({n, kNumMoves});
    auto v = out.mutable_unchecked<2>();
    for (int i = 0; i < n; ++i)
      for (int a = 0; a < kNumMoves; ++a)
        v(i, a) = lattice.Valid((*ctx.robot_lattice)[i], static_cast<Move>(a));
    return out;
  }

  py::dict Step(const py::array_t<long long>& moves) {
    std::vector<Move> next = MovesFrom(moves, num_robots());
    const long invalid_before = episode().invalid_moves();
    {
      py::gil_scoped_release release;
      StepWith(std::move(next));
    }
    const Episode& e = *episode_;
    py::dict changed;
    changed["step"] = e.step();
    changed["invalid_moves"] = e.invalid_moves() - invalid_before;
    changed["localized"] = e.NumLocalized();
    changed["done"] = e.done();
    changed["success"] = e.success();
    return changed;
  }
  // One step with these moves (owned missions; no Python object touched).
  void StepWith(std::vector<Move> moves) {
    if (episode_->done())
      throw py::value_error("step: the mission is done (done is True)");
    external_->next = std::move(moves);
    episode_->Step();
    if (episode_->done()) {
      moves_.OnEnd(*episode_);
      estimate_.OnEnd(*episode_);
    }
  }

  std::string SummaryText() const {
    return SummaryJson(Summarize(episode(), 0.0), episode());
  }
  std::string DiagnosticsText() const {
    return DiagnosticsJson(episode(), moves_, estimate_, 0.0);
  }

 private:
  std::uint64_t id_;
  const DecisionContext* view_ = nullptr;
  std::uint64_t seed_ = 0;
  int max_steps_ = 0;
  std::shared_ptr<const Instance> instance_;
  ExternalPolicy* external_ = nullptr;  // owned by the episode
  std::unique_ptr<Episode> episode_;
  MoveObserver moves_;
  EstimateObserver estimate_;
  // render(): the picture kept in step with the episode once made.
  struct PictureObserver {
    PictureObserver(const Episode& e, FrameRenderer* renderer)
        : picture(e, renderer) {
      picture.AfterStep(e);
    }
    EpisodePicture picture;
  };
  struct PictureForward : StepObserver {
    explicit PictureForward(Mission* m) : mission(m) {}
    ObserverStatus OnStep(const Episode& e) override {
      if (mission->picture_) mission->picture_->picture.AfterStep(e);
      return ObserverStatus::kContinue;
    }
    Mission* mission;
  };
  std::unique_ptr<FrameRenderer> renderer_;
  std::unique_ptr<PictureObserver> picture_;
  PictureForward picture_forward_{this};
  bool picture_added_ = false;
  int picture_width_ = 0, picture_height_ = 0;
};

// A registered policy deciding on a mission's current state.
class BuiltinPolicy {
 public:
  BuiltinPolicy(const std::string& name, const KeyValues& params) {
    std::vector<Override> o = {{"name", "policy.name", name}};
    for (const Override& p : AsOverrides(params, ""))
      o.push_back({p.flag, "policy." + p.path, p.value});
    const PolicyRegistry registry = AllPolicies();
    if (!registry.Has(name))
      throw InputError("builtin_policy", 0, "name",
                       registry.UnknownPolicy(name));
    // On any valid scenario: only its policy section is read.
    spec_ = registry.Resolve(WithOverrides(GeneratedScenario(1, 1, 0), o));
  }

  const std::string& name() const { return spec_->name(); }
  bool centralized() const { return spec_->centralized(); }

  // One move per robot from what the robots know at this step (the team's
  // belief only for a centralized policy). The policy starts afresh (Reset
  // with the mission's seed) on a new mission or a step that is not the
  // next one, so that deciding at every step repeats `aia run`.
  // One move per robot from what the robots know at this step (the team's
  // belief only for a centralized policy). Each mission has its own policy
  // state, started afresh (Reset with the mission's seed) at its first
  // decision or at a step that is not the next one, so that deciding at
  // every step repeats `aia run`, also with missions on several threads
  // (evaluate). Called with the GIL held; the decision runs without it.
  py::array_t<long long> Decide(const Mission& mission) {
    DecisionContext ctx = mission.Context();
    std::shared_ptr<State>& slot = states_[mission.id()];
    if (!slot || ctx.step != slot->next_step) {
      slot = std::make_shared<State>();
      slot->policy = spec_->Create();
      slot->policy->Reset(*ctx.map, mission.num_robots(), mission.num_targets(),
                          mission.seed());
    }
    const std::shared_ptr<State> state = slot;  // kept while deciding
    state->last_use = ++uses_;
    Forget();
    if (!state->policy->centralized()) {
      ctx.central = nullptr;
    } else if (ctx.central == nullptr) {
      throw py::value_error(
          name() +
          " decides from the team's belief, which this policy is "
          "not given: aia.evaluate(..., centralized=True)");
    }
    std::vector<Move> moves(mission.num_robots(), Move::kStay);
    PolicyStatus status;
    {
      py::gil_scoped_release release;
      status = state->policy->Decide(ctx, &moves);
    }
    status_ = status;
    state->next_step = ctx.step + 1;
    py::array_t<long long> out(static_cast<py::ssize_t>(moves.size()));
    auto v = out.mutable_unchecked<1>();
    for (std::size_t i = 0; i < moves.size(); ++i)
      v(static_cast<py::ssize_t>(i)) = static_cast<long long>(moves[i]);
    return out;
  }
  std::string LastStatus() const {
    return std::string(PolicyStatusName(status_));
  }

 private:
  struct State {
    std::unique_ptr<Policy> policy;
    int next_step = 0;
    std::uint64_t last_use = 0;
  };
  // The states of the kMissions missions decided for most recently.
  static constexpr std::size_t kMissions = 256;
  void Forget() {
    while (states_.size() > kMissions) {
      auto oldest = states_.begin();
      for (auto it = states_.begin(); it != states_.end(); ++it)
        if (it->second->last_use < oldest->second->last_use) oldest = it;
      states_.erase(oldest);
    }
  }

  std::shared_ptr<const PolicySpec> spec_;
  std::map<std::uint64_t, std::shared_ptr<State>> states_;  // by mission id
  std::uint64_t uses_ = 0;
  PolicyStatus status_ = PolicyStatus::kOk;
};

// n missions of one scenario (seeds given), stepped together on C++
// threads without the GIL.
class VectorMissions {
 public:
  VectorMissions(const std::string& scenario,
                 const std::vector<std::uint64_t>& seeds,
                 const KeyValues& overrides, int threads)
      : pool_((threads > 0 ? threads
                           : static_cast<int>(std::max(
                                 1u, std::thread::hardware_concurrency()))) -
              1) {
    if (seeds.empty()) throw py::value_error("n: must be at least 1");
    for (std::uint64_t seed : seeds)
      missions_.push_back(std::make_unique<Mission>(scenario, seed, overrides));
  }
  int size() const { return static_cast<int>(missions_.size()); }
  int num_robots() const { return missions_[0]->num_robots(); }
  Mission& at(int i) { return *missions_.at(i); }

  // moves: (n, robots); missions already done ignore theirs.
  py::dict Step(const py::array_t<long long>& moves) {
    const int n = size(), robots = num_robots();
    const py::buffer_info b = moves.request();
    if (b.ndim != 2 || b.shape[0] != n || b.shape[1] != robots)
      throw py::value_error("moves: must be (missions, robots) = (" +
                            std::to_string(n) + ", " + std::to_string(robots) +
                            ")");
    std::vector<std::vector<Move>> next(n, std::vector<Move>(robots));
    const auto view = moves.unchecked<2>();
    for (int i = 0; i < n; ++i)
      for (int r = 0; r < robots; ++r)
        next[i][r] =
            ToMove(view(i, r), std::to_string(i) + "][" + std::to_string(r));
    std::vector<long> before(n);
    for (int i = 0; i < n; ++i)
      before[i] = missions_[i]->episode().invalid_moves();
    {
      py::gil_scoped_release release;
      // A failed mission must not keep the others from stepping.
      pool_.Run(
          n,
          [&](int i, int) {
            if (!missions_[i]->episode().done())
              missions_[i]->StepWith(std::move(next[i]));
          },
          OnFailure::kFinish);
    }
    auto step = Array<long long>({n});
    auto done = Array<bool>({n});
    auto success = Array<bool>({n});
    auto invalid = Array<long long>({n});
    auto st = step.mutable_unchecked<1>();
    auto dn = done.mutable_unchecked<1>();
    auto sc = success.mutable_unchecked<1>();
    auto iv = invalid.mutable_unchecked<1>();
    for (int i = 0; i < n; ++i) {
      const Episode& e = missions_[i]->episode();
      st(i) = e.step();
      dn(i) = e.done();
      sc(i) = e.success();
      iv(i) = e.invalid_moves() - before[i];
    }
    py::dict changed;
    changed["step"] = step;
    changed["done"] = done;
    changed["success"] = success;
    changed["invalid_moves"] = invalid;
    return changed;
  }

 private:
  ThreadPool pool_;  // the caller is the first of `threads`
  std::vector<std::unique_ptr<Mission>> missions_;
};

// The samples of `aia dataset` shards, rendered as the trainer renders them
// (learning/dataset.h, the trainer's batches).
class PyDataset {
 public:
  PyDataset(const std::vector<std::string>& paths, const KeyValues& params) {
    channels_ = ChannelSettings(params);
    data_ = ReadDataset(paths, "paths");
    if (data_.samples.empty())
      throw InputError("Dataset", 0, "paths", "holds no samples");
    for (const DatasetWorld& w : data_.worlds) {
      const Map map(w.size, w.obstacles, w.map_cell, w.lattice_step,
                    w.robot_radius);
      renderers_.emplace_back(map.occupancy(), w.size, channels_,
                              &map.lattice());
    }
  }

  int size() const { return static_cast<int>(data_.samples.size()); }
  int num_worlds() const { return static_cast<int>(data_.worlds.size()); }

  // Per sample: label, useful, acted, world index, episode, step, robot.
  py::dict Samples() const {
    const py::ssize_t n = size();
    py::array_t<long long> label(n), acted(n), world(n), episode(n), step(n),
        robot(n);
    py::array_t<bool> useful(n);
    for (py::ssize_t i = 0; i < n; ++i) {
      const DatasetSample& s = data_.samples[i];
      label.mutable_at(i) = static_cast<long long>(s.label);
      acted.mutable_at(i) = static_cast<long long>(s.acted);
      world.mutable_at(i) = s.world;
      episode.mutable_at(i) = s.episode;
      step.mutable_at(i) = s.step;
      robot.mutable_at(i) = s.robot;
      useful.mutable_at(i) = s.useful;
    }
    py::dict d;
    d["label"] = label;
    d["useful"] = useful;
    d["acted"] = acted;
    d["world"] = world;
    d["episode"] = episode;
    d["step"] = step;
    d["robot"] = robot;
    return d;
  }

  // Whether each world is held out for validation, as `aia train` splits
  // (--val-share, --seed).
  py::array_t<bool> ValidationWorlds(double share, std::uint64_t seed) const {
    py::array_t<bool> out(num_worlds());
    for (int w = 0; w < num_worlds(); ++w) {
      Rng rng(seed, "train/split",
              static_cast<std::uint64_t>(data_.worlds[w].seed));
      out.mutable_at(w) = rng.Uniform() < share;
    }
    return out;
  }

  // (B, C, H, W) float32 images of these samples and their labels.
  py::tuple Batch(const std::vector<long long>& indices) {
    if (indices.empty()) throw py::value_error("batch: no sample indices");
    for (long long i : indices)
      if (i < 0 || i >= size())
        throw py::index_error("batch: sample " + std::to_string(i) + " of " +
                              std::to_string(size()));
    const ChannelRenderer& first = renderers_[data_.samples[indices[0]].world];
    for (long long i : indices) {
      const ChannelRenderer& r = renderers_[data_.samples[i].world];
      if (r.height() != first.height() || r.width() != first.width())
        throw py::value_error(
            "batch: worlds of different sizes in the global frame; use the "
            "centred frame or one workspace size");
    }
    const py::ssize_t b = static_cast<py::ssize_t>(indices.size());
    py::array_t<float> images({b, static_cast<py::ssize_t>(first.channels()),
                               static_cast<py::ssize_t>(first.height()),
                               static_cast<py::ssize_t>(first.width())});
    py::array_t<long long> labels(b);
    float* data = images.mutable_data();
    const std::size_t size = first.ImageSize();
    for (py::ssize_t k = 0; k < b; ++k)
      labels.mutable_at(k) =
          static_cast<long long>(data_.samples[indices[k]].label);
    {
      py::gil_scoped_release release;
      for (py::ssize_t k = 0; k < b; ++k) {
        const DatasetSample& s = data_.samples[indices[k]];
        const DatasetWorld& w = data_.worlds[s.world];
        renderers_[s.world].Render(s.position, s.neighbours, s.targets,
                                   w.log_det_prior, w.eps, data + k * size,
                                   SampleMemory(s, w));
      }
    }
    return py::make_tuple(images, labels);
  }

 private:
  ChannelParams channels_;
  Dataset data_;
  std::vector<ChannelRenderer> renderers_;
};

// A Python callable as a policy of aia's own loop (evaluate): each decision
// takes the GIL, hands the callable a view of the decision and reads its
// moves. A Python exception ends the evaluation and reaches the caller.
class CallbackPolicy : public Policy {
 public:
  CallbackPolicy(std::string name, bool centralized, py::object decide)
      : name_(std::move(name)),
        centralized_(centralized),
        decide_(std::move(decide)) {}
  ~CallbackPolicy() override {
    py::gil_scoped_acquire gil;
    decide_ = py::object();
  }
  std::string_view name() const override { return name_; }
  bool centralized() const override { return centralized_; }
  void Reset(const Map&, int, int, std::uint64_t seed) override {
    seed_ = seed;
    id_ = g_next_mission_id++;
  }
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override {
    py::gil_scoped_acquire gil;
    const int n = static_cast<int>(moves->size());
    py::object view = py::cast(new Mission(&ctx, seed_, id_, 0),
                               py::return_value_policy::take_ownership);
    struct Invalidate {
      py::object& view;
      ~Invalidate() { view.cast<Mission&>().Invalidate(); }
    } invalidate{view};
    const py::object result = decide_(view);
    *moves = MovesFrom(
        py::array_t<long long, py::array::c_style | py::array::forcecast>(
            result),
        n);
    return PolicyStatus::kOk;
  }

 private:
  std::string name_;
  bool centralized_;
  py::object decide_;
  std::uint64_t seed_ = 0, id_ = 0;
};

class CallbackSpec : public PolicySpec {
 public:
  CallbackSpec(const std::string& name, bool centralized, py::object decide)
      : PolicySpec(name, centralized), decide_(std::move(decide)) {}
  ~CallbackSpec() override {
    py::gil_scoped_acquire gil;
    decide_ = py::object();
  }
  std::unique_ptr<Policy> Create() const override {
    py::gil_scoped_acquire gil;
    return std::make_unique<CallbackPolicy>(name(), centralized(), decide_);
  }
  // effective.yaml's line: rows under this name are resumed whatever the
  // code does, so a changed policy needs another name.
  ConfigNode Params() const override {
    ConfigNode node = ConfigNode::Map();
    node.Set("kind", ConfigNode::Scalar("python"));
    node.Set("centralized",
             ConfigNode::Scalar(centralized() ? "true" : "false"));
    return node;
  }

 private:
  py::object decide_;
};

// aia.evaluate's core: `aia eval` with one more policy, the callable.
int Evaluate(py::object decide, const std::string& name, bool centralized,
             const std::vector<std::string>& sizes, int seeds,
             std::uint64_t seed_base, const std::string& out, int threads,
             const std::vector<std::string>& sets, bool progress) {
  EvalOptions o;
  o.sizes.clear();
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    std::string why;
    const std::optional<TeamSize> size = TeamSize::FromText(sizes[i], &why);
    if (!size)
      throw InputError(
          "evaluate", 0, "sizes[" + std::to_string(i) + "]",
          (why.empty() ? "must be " + std::string(TeamSize::kExpect) : why) +
              ", got '" + sizes[i] + "'");
    o.sizes.push_back(*size);
  }
  o.seeds = seeds;
  o.seed_base = seed_base;
  o.out_dir = out;
  o.threads = threads;
  o.sets = sets;
  o.progress = progress;
  o.exit_on_interrupt = false;
  o.extra_policies = {
      std::make_shared<CallbackSpec>(name, centralized, std::move(decide))};
  py::gil_scoped_release release;
  InterruptScope scope;  // Ctrl-C: the rows done are written; back to Python
  return RunEval(o);
}

}  // namespace
}  // namespace python
}  // namespace aia

PYBIND11_MODULE(_aia, m) {
  using aia::python::BuiltinPolicy;
  using aia::python::Mission;
  m.doc() = "aia's C++ core (use the aia package)";
  // numpy's C API is set up once, here: done first on a worker thread it
  // would import numpy under a static's guard while another thread holds
  // the GIL and waits on that guard.
  py::module_::import("numpy");
  (void)py::array_t<long long>(1);
  static py::exception<aia::InputError> input_error(m, "InputError",
                                                    PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const aia::InputError& e) {
      // A scenario's bytes need not be UTF-8: shown escaped, not lost.
      const std::string text = e.Format();
      PyObject* message = PyUnicode_DecodeUTF8(
          text.data(), static_cast<Py_ssize_t>(text.size()),
          "backslashreplace");
      PyErr_SetObject(input_error.ptr(), message);
      Py_XDECREF(message);
    }
  });

  py::class_<Mission>(m, "Mission")
      .def(py::init<const std::string&, std::optional<std::uint64_t>,
                    const aia::python::KeyValues&>(),
           py::arg("scenario"), py::arg("seed") = py::none(),
           py::arg("overrides") = aia::python::KeyValues{})
      .def("state", &Mission::State)
      .def("step", &Mission::Step, py::arg("moves"))
      .def("valid_moves", &Mission::ValidMoves)
      .def("render", &Mission::Render, py::arg("width") = 640,
           py::arg("height") = 480)
      .def("channels", &Mission::Channels,
           py::arg("params") = aia::python::KeyValues{})
      .def("summary_json", &Mission::SummaryText)
      .def("diagnostics_json", &Mission::DiagnosticsText)
      .def_property_readonly("num_robots", &Mission::num_robots)
      .def_property_readonly("num_targets", &Mission::num_targets)
      .def_property_readonly("step_count", &Mission::step)
      .def_property_readonly("done", &Mission::done)
      .def_property_readonly("success", &Mission::success)
      .def_property_readonly("flowtime", &Mission::flowtime)
      .def_property_readonly("max_steps", &Mission::max_steps)
      .def_property_readonly("seed", &Mission::seed)
      .def_property_readonly("owned", &Mission::owned);

  py::class_<aia::python::VectorMissions>(m, "VectorMissions")
      .def(py::init<const std::string&, const std::vector<std::uint64_t>&,
                    const aia::python::KeyValues&, int>(),
           py::arg("scenario"), py::arg("seeds"),
           py::arg("overrides") = aia::python::KeyValues{},
           py::arg("threads") = 0)
      .def("__len__", &aia::python::VectorMissions::size)
      .def("mission", &aia::python::VectorMissions::at,
           py::return_value_policy::reference_internal)
      .def("step", &aia::python::VectorMissions::Step, py::arg("moves"))
      .def_property_readonly("num_robots",
                             &aia::python::VectorMissions::num_robots);

  py::class_<aia::python::PyDataset>(m, "Dataset")
      .def(py::init<const std::vector<std::string>&,
                    const aia::python::KeyValues&>(),
           py::arg("paths"), py::arg("params") = aia::python::KeyValues{})
      .def("__len__", &aia::python::PyDataset::size)
      .def_property_readonly("num_worlds", &aia::python::PyDataset::num_worlds)
      .def("samples", &aia::python::PyDataset::Samples)
      .def("validation_worlds", &aia::python::PyDataset::ValidationWorlds,
           py::arg("share"), py::arg("seed"))
      .def("batch", &aia::python::PyDataset::Batch, py::arg("indices"));

  py::class_<BuiltinPolicy>(m, "BuiltinPolicy")
      .def(py::init<const std::string&, const aia::python::KeyValues&>(),
           py::arg("name"), py::arg("params") = aia::python::KeyValues{})
      .def("decide", &BuiltinPolicy::Decide, py::arg("mission"))
      .def_property_readonly("name", &BuiltinPolicy::name)
      .def_property_readonly("centralized", &BuiltinPolicy::centralized)
      .def_property_readonly("last_status", &BuiltinPolicy::LastStatus);

  m.def("policy_names", [] { return aia::AllPolicies().Names(); });
  m.def("evaluate", &aia::python::Evaluate, py::arg("decide"), py::arg("name"),
        py::arg("centralized"), py::arg("sizes"), py::arg("seeds"),
        py::arg("seed_base"), py::arg("out"), py::arg("threads"),
        py::arg("sets"), py::arg("progress"));
}
