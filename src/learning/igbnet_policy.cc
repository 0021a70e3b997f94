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

std::string DefaultModelPath(Coordination coordination) {
  std::error_code ec;
  const std::filesystem::path here = coordination == Coordination::kNone
                                         ? "models/igbnet_learned.pt"
                                         : "models/igbnet.pt";
  // An installed aia's own model, whatever the working folder holds; a
  // build's, its source tree's: a models/ folder where a program happens to
  // run does not change its results (it did: a Python script run from a
  // folder holding models/igbnet.pt decided with that file, and nothing
  // said so). The working folder's only where the source tree has none (a
  // build tree moved away from it).
  if (const std::string data = InstalledDataDir(); !data.empty()) {
    const std::filesystem::path installed = std::filesystem::path(data) / here;
    if (std::filesystem::is_regular_file(installed, ec))
      return installed.lexically_normal().string();
  }
  const std::filesystem::path source =
      std::filesystem::path(AIA_SOURCE_DIR) / here;
  if (!std::filesystem::is_regular_file(source, ec) &&
      std::filesystem::is_regular_file(here, ec))
    return here.string();
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
    : IgbNetPolicy(
          std::make_unique<NetworkScorer>(std::move(net), params.precision),
          params) {}

IgbNetPolicy::IgbNetPolicy(std::unique_ptr<MoveScorer> scorer,
                           IgbNetParams params)
    : scorer_(std::move(scorer)), params_(params) {
  AIA_CHECK(scorer_ != nullptr);
  if (params_.coordination == Coordination::kRules)
    rules_ = std::make_unique<RulesLayer>(params_);
}

void IgbNetPolicy::Reset(const Map& map, int num_robots, int num_targets,
                         std::uint64_t /*seed*/) {
  scorer_->Reset(map, num_robots, num_targets);
  if (rules_) rules_->Reset(num_robots, num_targets);
  logits_.assign(static_cast<std::size_t>(num_robots) * kNumMoves, 0.0f);
  known_.Clear();
  decisions_ = shaped_moves_ = handwritten_moves_ = bfloat16_decisions_ = 0;
}

const SearchMemory& IgbNetPolicy::search() const {
  static const SearchMemory kNone;
  return rules_ ? rules_->memory() : kNone;
}

PolicyStatus IgbNetPolicy::Decide(const DecisionContext& given,
                                  std::vector<Move>* moves) {
  // Every part reads the beliefs' log dets and means from one digest,
  // worked out once per step over the policy's threads (and kept, with
  // what each neighbourhood holds, while the team's knowledge is the same:
  // async rounds between two sensing ticks).
  const bool known = known_.Holds(given);
  if (!known) digest_.Compute(*given.beliefs, PolicyRunner());
  DecisionContext ctx = given;
  ctx.digest = &digest_;
  const Lattice& lattice = ctx.map->lattice();
  const int n = static_cast<int>(moves->size());
  team_.rows.clear();
  for (int i = 0; i < n; ++i)
    if (ctx.comm->Active(i)) team_.rows.push_back(i);
  team_.row_of.assign(n, -1);
  for (int b = 0; b < team_.size(); ++b) team_.row_of[team_.rows[b]] = b;
  // The rules' open targets by what each neighbourhood holds.
  if (rules_ && params_.open == OpenRule::kNeighbours) {
    if (!known)
      holds_.Compute(ctx, team_.rows, params_.refresh, PolicyRunner());
    ctx.holds = &holds_;
  }
  known_.Set(given);
  ScorerView view;
  PolicyStatus status = PolicyStatus::kOk;
  for (int i = 0; i < n; ++i) (*moves)[i] = Move::kStay;
  walking_.assign(team_.rows.size(), 0);
  if (rules_) {
    rules_->Shape(ctx, team_.rows);
    view.shown = rules_->shown();
    view.aims = rules_->aims();
    // A robot on a deadlock walk moves without the network, so its image is
    // not made (a walk reads and changes only its own robot's state, so
    // walking first gives the moves the loop below would).
    for (int b = 0; b < team_.size(); ++b) {
      const int i = team_.rows[b];
      Move walk = Move::kStay;
      if (!Deciding(ctx, i) || !rules_->Walk(ctx, b, i, &walk)) continue;
      walking_[b] = 1;
      (*moves)[i] = walk;
    }
    view.unread = &walking_;
  }
  batch_logits_.resize(team_.rows.size() * kNumMoves);
  scorer_->Score(ctx, team_, view, batch_logits_.data());
  logits_.assign(static_cast<std::size_t>(n) * kNumMoves, 0.0f);
  for (int b = 0; b < team_.size(); ++b) {
    const int i = team_.rows[b];
    if (!Deciding(ctx, i)) continue;  // on its way (async decisions)
    ++decisions_;
    if (walking_[b]) {
      ++handwritten_moves_;
      continue;
    }
    if (scorer_->BFloat16()) ++bfloat16_decisions_;
    const int here = (*ctx.robot_lattice)[i];
    const float* l = batch_logits_.data() + b * kNumMoves;
    std::copy(l, l + kNumMoves, logits_.data() + i * kNumMoves);
    const int best = BestValidMove(lattice, here, l);
    if (best < 0) {
      status = PolicyStatus::kNoValidMove;
      continue;
    }
    Move move = static_cast<Move>(best);
    if (rules_) {
      bool replaced = false;
      move = rules_->Arbitrate(ctx, b, i, move, l, &replaced);
      if (replaced) {
        ++handwritten_moves_;
      } else if (rules_->Shaped(ctx, b, i, scorer_->ShowsAims())) {
        ++shaped_moves_;
        ++handwritten_moves_;
      }
    }
    (*moves)[i] = move;
  }
  return status;
}

std::vector<std::pair<std::string, long>> IgbNetPolicy::Counters() const {
  std::vector<std::pair<std::string, long>> c = {{"decisions", decisions_}};
  if (rules_) {
    for (auto& p : rules_->Counters()) c.push_back(p);
  } else {  // the same keys, at zero
    static const RulesLayer kUnused{IgbNetParams{}};
    for (auto& p : kUnused.Counters()) c.push_back(p);
  }
  c.push_back({"shaped_moves", shaped_moves_});
  c.push_back({"handwritten_moves", handwritten_moves_});
  c.push_back({"bfloat16_decisions", bfloat16_decisions_});
  return c;
}

void AddLearnedPolicies(PolicyRegistry* registry) {
  registry->Add<IgbNetPolicy, IgbNetParams, IgbNet>(
      "I-GBNet, the paper's graph network trained by imitation of the expert "
      "(docs/learning.md); each robot decides from its own belief, its "
      "neighbours' positions and the map",
      "models/igbnet.pt with coordination rules, models/igbnet_learned.pt "
      "with none",
      [](const IgbNetParams& params, const Scenario& s) {
        if (params.coordination == Coordination::kNone) {
          const std::string key = FirstRuleKeySet(params);
          if (!key.empty())
            throw s.ErrorAt(key,
                            "a rule of the hand-written coordination layer, "
                            "which policy.coordination none does not use; "
                            "remove it, or set policy.coordination: rules");
        }
        if (const std::string why = PrecisionProblem(params.precision);
            !why.empty())
          throw s.ErrorAt("policy.precision", why);
        const bool given = !s.policy.model.empty();
        const std::string path =
            given ? s.policy.model : DefaultModelPath(params.coordination);
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
        // Its renderers' grids cover the workspace: refused before a 10 km
        // world asks for gigabytes.
        if (const std::string why = ChannelGridProblem(
                s.workspace.size,
                AtLatticeStep(net->config().channels, s.robots.step));
            !why.empty())
          throw s.ErrorAt("workspace.size", "policy " + s.policy.name + " (" +
                                                net->file().path + "): " + why);
        return net;
      },
      [](const IgbNetParams& params, std::shared_ptr<const IgbNet> net) {
        return std::make_unique<IgbNetPolicy>(std::move(net), params);
      });
}

}  // namespace aia
