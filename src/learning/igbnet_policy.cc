#include "aia/learning/igbnet_policy.h"

#include <filesystem>
#include <limits>
#include <map>
#include <mutex>

#include "aia/core/check.h"
#include "aia/core/error.h"
#include "aia/core/plugin.h"
#include "aia/planning/information.h"

#ifndef AIA_SOURCE_DIR
#define AIA_SOURCE_DIR "."
#endif

namespace aia {

std::string DefaultModelPath() {
  std::error_code ec;
  const std::filesystem::path here = "models/igbnet.pt";
  if (std::filesystem::is_regular_file(here, ec)) return here.string();
  const std::filesystem::path source =
      std::filesystem::path(AIA_SOURCE_DIR) / here;
  if (std::filesystem::is_regular_file(source, ec)) return source.string();
  // An installed aia (cmake --install): PREFIX/share/aia/models/.
  const std::string dir = ExecutableDir();
  const std::filesystem::path installed =
      std::filesystem::path(dir) / "../share/aia" / here;
  if (!dir.empty() && std::filesystem::is_regular_file(installed, ec))
    return installed.lexically_normal().string();
  return source.string();
}

std::shared_ptr<const IgbNet> LoadModelOnce(const std::string& path,
                                            const std::string& error_file,
                                            int error_line,
                                            const std::string& key) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const IgbNet>> cache;
  std::error_code ec;
  std::string id = std::filesystem::weakly_canonical(path, ec).string();
  if (ec) id = path;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = cache.find(id);
  if (it != cache.end()) return it->second;
  std::shared_ptr<const IgbNet> net =
      IgbNet::Load(path, error_file, error_line, key);
  cache.emplace(id, net);
  return net;
}

IgbNetPolicy::IgbNetPolicy(std::shared_ptr<const IgbNet> net,
                           IgbNetParams params)
    : net_(std::move(net)), params_(params) {
  AIA_CHECK(net_ != nullptr);
}

void IgbNetPolicy::Reset(const Map& map, int num_robots, int num_targets,
                         std::uint64_t /*seed*/) {
  renderer_.emplace(map.occupancy(), map.size(), net_->config().channels,
                    &map.lattice());
  logits_.assign(static_cast<std::size_t>(num_robots) * kNumMoves, 0.0f);
  last_point_.assign(num_robots, -1);
  last_move_.assign(num_robots, Move::kStay);
  reversals_.assign(num_robots, 0);
  walked_.assign(num_robots, 0);
  goal_.assign(num_robots, -1);
  decisions_ = 0;
  rule_moves_ = 0;
  rule_stays_ = 0;
  idle_moves_ = 0;
  search_.Reset(num_robots, num_targets);
  claims_.Reset();
}

void IgbNetPolicy::RenderAndForward(const DecisionContext& ctx) {
  const Lattice& lattice = ctx.map->lattice();
  const std::size_t size = renderer_->ImageSize();
  images_.resize(rows_.size() * size);
  const std::vector<double>* prior = ctx.log_det_prior;
  if (!prior) {  // a hand-made context: every prior counts as det 1
    no_prior_.assign(ctx.beliefs->layout().num_targets(), 0.0);
    prior = &no_prior_;
  }
  const int workers = std::max(1, PolicyThreads());
  heat_.Prepare(
      *ctx.beliefs, rows_, *prior, renderer_->Heatmap(ctx.eps),
      renderer_->occupancy(),
      [](int n, const HeatTask& f) { ParallelFor(n, 16, f); }, workers);
  if (static_cast<int>(worker_heat_.size()) < workers) {
    worker_heat_.resize(workers, renderer_->occupancy());
    worker_neighbours_.resize(workers);
    worker_targets_.resize(workers);
  }
  const bool geodesic = renderer_->params().geodesic;
  const bool searching = searching_ && geodesic;
  // Chunks of kForwardBatch robots: each rendered and run through the
  // network by one thread (libtorch runs single-threaded inside), so that a
  // robot's logits depend on its chunk, never on the number of threads.
  const int count = static_cast<int>(rows_.size());
  const int chunks = (count + kForwardBatch - 1) / kForwardBatch;
  batch_logits_.resize(rows_.size() * kNumMoves);
  const bool passing = net_->config().message_hops > 0;
  const int hidden = net_->config().hidden;
  if (passing) features_.resize(rows_.size() * hidden);
  ParallelFor(chunks, 1, [&](int c0, int c1, int worker) {
    Grid<float>& heat = worker_heat_[worker];
    std::vector<Vec2>& neighbours = worker_neighbours_[worker];
    for (int c = c0; c < c1; ++c) {
      const int begin = c * kForwardBatch;
      const int end = std::min(count, begin + kForwardBatch);
      for (int b = begin; b < end; ++b) {
        const int i = rows_[b];
        neighbours.clear();
        for (int j : ctx.comm->Neighbors(i))
          if (j != i)
            neighbours.push_back(lattice.Point((*ctx.robot_lattice)[j]));
        std::vector<HeatSource>* targets = nullptr;
        if (geodesic) {
          targets = &worker_targets_[worker];
          HeatSources(*ctx.beliefs, i, targets);
          if (searching)
            for (std::size_t k = 0; k < targets->size(); ++k)
              (*targets)[k].mean = search_.Aim(i, static_cast<int>(k));
          if (!keep_[b].empty())
            for (std::size_t k = 0; k < targets->size(); ++k)
              if (!keep_[b][k])
                (*targets)[k].log_det =
                    -std::numeric_limits<double>::infinity();
        }
        renderer_->RenderWithHeat(
            lattice.Point((*ctx.robot_lattice)[i]), neighbours,
            keep_[b].empty() ? heat_.Robot(b, &heat)
                             : heat_.Robot(b, keep_[b], &heat),
            targets, prior, ctx.eps, images_.data() + b * size);
      }
      if (passing)
        net_->Embed(images_.data() + begin * size, end - begin,
                    renderer_->height(), renderer_->width(),
                    features_.data() + begin * hidden);
      else
        net_->Forward(images_.data() + begin * size, end - begin,
                      renderer_->height(), renderer_->width(),
                      batch_logits_.data() + begin * kNumMoves);
    }
  });
  if (!passing) return;
  // The team's features over this step's graph among the active robots.
  graph_.offsets.assign(1, 0);
  graph_.neighbours.clear();
  for (int b = 0; b < count; ++b) {
    for (int j : ctx.comm->Neighbors(rows_[b]))
      if (j != rows_[b] && row_of_[j] >= 0)
        graph_.neighbours.push_back(row_of_[j]);
    graph_.offsets.push_back(static_cast<int>(graph_.neighbours.size()));
  }
  net_->Head(features_.data(), graph_, batch_logits_.data());
}

PolicyStatus IgbNetPolicy::Decide(const DecisionContext& ctx,
                                  std::vector<Move>* moves) {
  AIA_CHECK_MSG(renderer_.has_value(), "Reset() before Decide()");
  const Lattice& lattice = ctx.map->lattice();
  const int n = static_cast<int>(moves->size());
  rows_.clear();
  for (int i = 0; i < n; ++i)
    if (ctx.comm->Active(i)) rows_.push_back(i);
  row_of_.assign(n, -1);
  for (std::size_t b = 0; b < rows_.size(); ++b)
    row_of_[rows_[b]] = static_cast<int>(b);
  // What each robot missed so far (a hand-made context may lack the sensor
  // or differ from Reset's team: then no memory).
  searching_ = params_.search && ctx.sensor && search_.num_robots() == n &&
               search_.num_targets() == ctx.beliefs->layout().num_targets();
  if (searching_) {
    for (int i : rows_) search_.Update(ctx, i);
    if (params_.share_search) search_.Share(ctx, rows_);
  }
  ClaimTargets(ctx);
  RenderAndForward(ctx);
  logits_.assign(static_cast<std::size_t>(n) * kNumMoves, 0.0f);
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < n; ++i) (*moves)[i] = Move::kStay;
  if (static_cast<int>(last_point_.size()) < n) {  // a hand-made context
    last_point_.resize(n, -1);
    last_move_.resize(n, Move::kStay);
    reversals_.resize(n, 0);
    walked_.resize(n, 0);
    goal_.resize(n, -1);
  }
  for (std::size_t b = 0; b < rows_.size(); ++b) {
    const int i = rows_[b];
    const int here = (*ctx.robot_lattice)[i];
    const float* l = batch_logits_.data() + b * kNumMoves;
    std::copy(l, l + kNumMoves, logits_.data() + i * kNumMoves);
    // The move that brought the robot here (from where it stood at its last
    // decision), and whether it undid the one before.
    if (last_point_[i] >= 0 && last_point_[i] != here) {
      Move came = Move::kStay;
      for (Move m : kMoves)
        if (lattice.Next(last_point_[i], m) == here) came = m;
      if (came != Move::kStay && last_move_[i] != Move::kStay &&
          came == Opposite(last_move_[i])) {
        ++reversals_[i];
      } else {
        reversals_[i] = 0;
      }
      last_move_[i] = came;
    }
    last_point_[i] = here;
    // Deadlocked: walk toward the nearest point that sees an open target
    // until the robot stands on one (or has walked max_walk moves).
    ++decisions_;
    if (params_.max_reversals > 0 && reversals_[i] >= params_.max_reversals &&
        walked_[i] == 0) {
      walked_[i] = 1;
      goal_[i] = -1;
    }
    if (walked_[i] > 0) {
      const Move out = (params_.max_walk == 0 || walked_[i] <= params_.max_walk)
                           ? Escape(ctx, i)
                           : Move::kStay;
      if (out != Move::kStay) {
        ++walked_[i];
        ++rule_moves_;
        (*moves)[i] = out;
        continue;
      }
      walked_[i] = 0;
    }
    // The most probable valid move (ties to the lower move index).
    int best = -1;
    float best_logit = -std::numeric_limits<float>::infinity();
    for (int a = 0; a < kNumMoves; ++a) {
      if (!lattice.Valid(here, static_cast<Move>(a))) continue;
      if (best < 0 || l[a] > best_logit) {
        best = a;
        best_logit = l[a];
      }
    }
    if (best < 0) {
      status = PolicyStatus::kNoValidMove;
      continue;
    }
    if (params_.no_undo && last_move_[i] != Move::kStay &&
        static_cast<Move>(best) == Opposite(last_move_[i])) {
      goal_[i] = -1;
      const Move out = Escape(ctx, i);
      if (out == Move::kStay && ctx.sensor &&
          std::find(open_.begin(), open_.end(), 1) == open_.end()) {
        // Nothing open in the robot's own belief (a tracking mission after
        // success): a stay would be replaced by a random move by the world
        // rule, so the network's best move that does not undo the last.
        int next = -1;
        for (int a = 0; a < kNumMoves; ++a) {
          if (a == best || !lattice.Valid(here, static_cast<Move>(a))) continue;
          if (next < 0 || l[a] > l[next]) next = a;
        }
        if (next >= 0) {
          ++idle_moves_;
          (*moves)[i] = static_cast<Move>(next);
          continue;
        }
      }
      if (out == Move::kStay) {
        ++rule_stays_;
        continue;
      }
      walked_[i] = 2;  // the walk's first move, as above
      ++rule_moves_;
      (*moves)[i] = out;
      continue;
    }
    (*moves)[i] = static_cast<Move>(best);
  }
  return status;
}

void IgbNetPolicy::OpenAims(const DecisionContext& ctx, int i) {
  const int m = ctx.beliefs->layout().num_targets();
  const double log_eps = std::log(ctx.eps);
  aims_.resize(m);
  open_.assign(m, 0);
  for (int k = 0; k < m; ++k) {
    if (ctx.beliefs->LogDetCovariance(i, k) <= log_eps) continue;
    aims_[k] = searching_ ? search_.Aim(i, k) : ctx.beliefs->PositionMean(i, k);
    open_[k] = 1;
  }
}

void IgbNetPolicy::ClaimTargets(const DecisionContext& ctx) {
  if (keep_.size() < rows_.size()) keep_.resize(rows_.size());
  for (auto& k : keep_) k.clear();
  for (auto& k : owned_) k.clear();
  if (params_.claims == TargetClaimsMode::kNone || !ctx.sensor) return;
  claims_.Begin(*ctx.map, *ctx.sensor);
  if (owned_.size() < rows_.size()) owned_.resize(rows_.size());
  for (std::size_t b = 0; b < rows_.size(); ++b) {
    const int i = rows_[b];
    others_.clear();
    for (int j : ctx.comm->Neighbors(i))
      if (j != i && ctx.comm->Active(j))
        others_.push_back((*ctx.robot_lattice)[j]);
    OpenAims(ctx, i);
    if (params_.claims == TargetClaimsMode::kRoute)
      claims_.Route((*ctx.robot_lattice)[i], others_, aims_, open_, &claimed_);
    else
      claims_.Claim((*ctx.robot_lattice)[i], others_, aims_, open_, &claimed_);
    if (std::find(claimed_.begin(), claimed_.end(), 1) != claimed_.end())
      keep_[b] = claimed_;
    // What the deadlock rule's walk heads for: the targets the robot owns.
    if (params_.claims == TargetClaimsMode::kRoute)
      claims_.Claim((*ctx.robot_lattice)[i], others_, aims_, open_, &owned_[b]);
    else
      owned_[b] = claimed_;
  }
}

Move IgbNetPolicy::Escape(const DecisionContext& ctx, int i) {
  if (!ctx.sensor) return Move::kStay;
  const Lattice& lattice = ctx.map->lattice();
  const int here = (*ctx.robot_lattice)[i];
  const int m = ctx.beliefs->layout().num_targets();
  OpenAims(ctx, i);
  for (int k = 0; k < m; ++k)
    if (open_[k] && PredictedPrecision(*ctx.map, *ctx.sensor,
                                       lattice.Point(here), aims_[k]) > 0.0)
      return Move::kStay;  // it is where it can measure
  // The walk's target while it is open and reachable.
  int& goal = goal_[i];
  if (goal >= 0 && goal < m && open_[goal]) {
    claimed_.assign(m, 0);
    claimed_[goal] = 1;
    const Move move =
        toward_.FirstMove(*ctx.map, *ctx.sensor, here, aims_, claimed_);
    if (move != Move::kStay) return move;
  }
  goal = -1;
  // With claims: the nearest of the open targets the robot owns (in
  // lattice moves among it and its neighbours), where it owns one.
  const int row = i < static_cast<int>(row_of_.size()) ? row_of_[i] : -1;
  if (params_.claims != TargetClaimsMode::kNone && row >= 0 &&
      static_cast<int>(owned_[row].size()) == m) {
    claimed_.assign(m, 0);
    bool any = false;
    for (int k = 0; k < m; ++k) {
      claimed_[k] = owned_[row][k] && open_[k];
      any = any || claimed_[k];
    }
    if (any) {
      const Move move = toward_.FirstMove(*ctx.map, *ctx.sensor, here, aims_,
                                          claimed_, &goal);
      if (move != Move::kStay) return move;
    }
  }
  // Leave to a neighbour the open targets it is nearer to (straight line;
  // ties to the lower index); all of them when each is nearer to one.
  const Vec2 p = lattice.Point(here);
  claimed_.assign(open_.begin(), open_.end());
  bool any = false;
  for (int k = 0; k < m; ++k) {
    if (!open_[k]) continue;
    const double mine = (aims_[k] - p).squaredNorm();
    for (int j : ctx.comm->Neighbors(i)) {
      if (j == i) continue;
      const double theirs =
          (aims_[k] - lattice.Point((*ctx.robot_lattice)[j])).squaredNorm();
      if (theirs < mine || (theirs == mine && j < i)) {
        claimed_[k] = 0;
        break;
      }
    }
    any = any || claimed_[k];
  }
  return toward_.FirstMove(*ctx.map, *ctx.sensor, here, aims_,
                           any ? claimed_ : open_, &goal);
}

std::vector<std::pair<std::string, long>> IgbNetPolicy::Counters() const {
  return {{"decisions", decisions_},
          {"rule_moves", rule_moves_},
          {"rule_stays", rule_stays_},
          {"idle_moves", idle_moves_},
          {"misses", search_.misses()}};
}

void AddLearnedPolicies(PolicyRegistry* registry) {
  registry->Add<IgbNetPolicy, IgbNetParams, IgbNet>(
      "I-GBNet, the paper's graph network trained by imitation of the expert "
      "(docs/learning.md); each robot decides from its own belief, its "
      "neighbours' positions and the map",
      "models/igbnet.pt",
      [](const IgbNetParams&, const Scenario& s) {
        const bool given = !s.policy.model.empty();
        const std::string path = given ? s.policy.model : DefaultModelPath();
        std::shared_ptr<const IgbNet> net;
        try {
          net =
              LoadModelOnce(path, s.ErrorFile(), 0,
                            given ? "policy.model" : "policy.model (default)");
        } catch (const InputError& e) {
          // At the key's line, or naming the flag that set it.
          if (given) throw s.ErrorAt("policy.model", e.message());
          throw;
        }
        // A result's effective.yaml records the model's hash: repeating it
        // with a retrained or replaced model would not repeat it.
        if (s.policy.model_sha256 &&
            *s.policy.model_sha256 != net->file().sha256)
          throw s.ErrorAt(
              "policy.model_sha256",
              "the model file '" + net->file().path + "' has SHA-256 " +
                  net->file().sha256.substr(0, 16) + "..., not the recorded " +
                  s.policy.model_sha256->substr(0, 16) +
                  "...: it was retrained or replaced since; restore that "
                  "model, or delete the policy.model_sha256 line to run with "
                  "this one");
        return net;
      },
      [](const IgbNetParams& params, std::shared_ptr<const IgbNet> net) {
        return std::make_unique<IgbNetPolicy>(std::move(net), params);
      });
}

}  // namespace aia
