#include "aia/learning/coordination.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "aia/core/field_io.h"
#include "aia/learning/network.h"
#include "aia/planning/information.h"

namespace aia {

std::string FirstRuleKeySet(const IgbNetParams& params) {
  // Every field but the two that are not rules, in declaration order.
  for (const std::string& key : ChangedFields(params, IgbNetParams{}))
    if (key != "coordination" && key != "precision") return "policy." + key;
  return "";
}

int BestValidMove(const Lattice& lattice, int here, const float* logits,
                  int skip) {
  int best = -1;
  for (int a = 0; a < kNumMoves; ++a) {
    if (a == skip || !lattice.Valid(here, static_cast<Move>(a))) continue;
    if (best < 0 || logits[a] > logits[best]) best = a;
  }
  return best;
}

// --- OpenAims ----------------------------------------------------------------

void OpenAims::Of(const DecisionContext& ctx, int robot,
                  const SearchMemory* memory) {
  const int m = ctx.beliefs->layout().num_targets();
  const double log_eps = std::log(ctx.eps);
  aims_.resize(m);
  open_.assign(m, 0);
  const bool hood = ctx.holds && ctx.holds->Has(robot);
  for (int k = 0; k < m; ++k) {
    if (hood ? !ctx.holds->Open(robot, k) : LogDetOf(ctx, robot, k) <= log_eps)
      continue;
    aims_[k] = AimOf(ctx, robot, k, memory);
    open_[k] = 1;
  }
}

Vec2 OpenAims::AimOf(const DecisionContext& ctx, int robot, int k,
                     const SearchMemory* memory) {
  return memory ? memory->Aim(robot, k) : MeanOf(ctx, robot, k);
}

bool OpenAims::any() const {
  return std::find(open_.begin(), open_.end(), 1) != open_.end();
}

// --- MissMemory --------------------------------------------------------------

void MissMemory::Reset(int num_robots, int num_targets) {
  memory_.Reset(num_robots, num_targets);
  active_ = false;
}

void MissMemory::Update(const DecisionContext& ctx,
                        const std::vector<int>& rows) {
  const int n = static_cast<int>(ctx.robot_lattice->size());
  active_ = search_ && ctx.sensor && memory_.num_robots() == n &&
            memory_.num_targets() == ctx.beliefs->layout().num_targets();
  if (!active_) return;
  // The robots split over the policy's threads (each writes its own
  // memory only).
  const int workers = std::max(1, PolicyThreads());
  memory_.Update(ctx, rows, PolicyRunner(), workers);
  if (share_) memory_.Share(ctx, rows, PolicyRunner(), workers);
}

bool MissMemory::Moved(const DecisionContext& ctx, int robot) const {
  if (!active_) return false;
  const int m = ctx.beliefs->layout().num_targets();
  const double log_eps = std::log(ctx.eps);
  for (int k = 0; k < m; ++k)
    if (LogDetOf(ctx, robot, k) > log_eps &&
        memory_.Aim(robot, k) != MeanOf(ctx, robot, k))
      return true;
  return false;
}

// --- ClaimsShaper ------------------------------------------------------------

void ClaimsShaper::Shape(const DecisionContext& ctx,
                         const std::vector<int>& rows,
                         const SearchMemory* memory) {
  const std::size_t count = rows.size();
  if (shown_.size() < count) shown_.resize(count);
  if (owned_.size() < count) owned_.resize(count);
  for (auto& s : shown_) s.clear();
  for (auto& o : owned_) o.clear();
  narrowed_.assign(count, 0);
  unplanned_.assign(count, 0);
  if (mode_ == TargetClaimsMode::kNone || !ctx.sensor) return;
  claims_.Begin(*ctx.map, *ctx.sensor, ctx.beliefs->layout().num_targets());
  // The robots split over the policy's threads: each writes its own row.
  const int workers = std::max(1, PolicyThreads());
  if (static_cast<int>(scratch_.size()) < workers) scratch_.resize(workers);
  ParallelFor(static_cast<int>(count), 16, [&](int b0, int b1, int worker) {
    Scratch& w = scratch_[worker];
    for (int b = b0; b < b1; ++b) {
      const int i = rows[b];
      // Each robot claims from its own view: a robot on its way (async
      // decisions) needs none now.
      if (!Deciding(ctx, i)) continue;
      w.others.clear();
      for (int j : ctx.comm->Neighbors(i))
        if (j != i && ctx.comm->Active(j))
          w.others.push_back((*ctx.robot_lattice)[j]);
      w.open.Of(ctx, i, memory);
      const int here = (*ctx.robot_lattice)[i];
      const std::vector<Vec2>& aims = w.open.aims();
      const std::vector<std::uint8_t>& open = w.open.open();
      if (mode_ == TargetClaimsMode::kRoute)
        claims_.Route(here, w.others, aims, open, &w.claimed);
      else
        claims_.Claim(here, w.others, aims, open, &w.claimed);
      if (std::find(w.claimed.begin(), w.claimed.end(), 1) != w.claimed.end()) {
        shown_[b] = w.claimed;
        narrowed_[b] = w.claimed != open;
      }
      // What the walk heads for: the targets the robot owns.
      const bool planned =
          mode_ == TargetClaimsMode::kRoute &&
          TargetClaims::Plans(std::count(open.begin(), open.end(), 1),
                              static_cast<long>(w.others.size()));
      if (planned)
        claims_.Claim(here, w.others, aims, open, &owned_[b]);
      else
        owned_[b] = w.claimed;  // Claim's answer
      unplanned_[b] = !planned;
    }
  });
}

const std::vector<std::uint8_t>* ClaimsShaper::Owned(int b) const {
  if (mode_ == TargetClaimsMode::kNone || b < 0 ||
      b >= static_cast<int>(owned_.size()) || owned_[b].empty())
    return nullptr;
  return &owned_[b];
}

// --- DeadlockWalk ------------------------------------------------------------

void DeadlockWalk::Reset(int num_robots) {
  walked_.assign(num_robots, 0);
  goal_.assign(num_robots, -1);
  moves_ = 0;
}

void DeadlockWalk::Grow(int num_robots) {
  if (static_cast<int>(walked_.size()) >= num_robots) return;
  walked_.resize(num_robots, 0);  // a hand-made context's larger team
  goal_.resize(num_robots, -1);
}

bool DeadlockWalk::Walk(const DecisionContext& ctx, int robot, int reversals,
                        const std::vector<std::uint8_t>* owned,
                        const SearchMemory* memory, Move* move) {
  Grow(robot + 1);
  int& walked = walked_[robot];
  if (max_reversals_ > 0 && reversals >= max_reversals_ && walked == 0) {
    walked = 1;
    goal_[robot] = -1;
  }
  if (walked == 0) return false;
  const Move out = (max_walk_ == 0 || walked <= max_walk_)
                       ? Escape(ctx, robot, owned, memory)
                       : Move::kStay;
  if (out == Move::kStay) {
    walked = 0;  // it can measure, has nowhere to go, or walked enough
    return false;
  }
  ++walked;
  ++moves_;
  *move = out;
  return true;
}

Move DeadlockWalk::Start(const DecisionContext& ctx, int robot,
                         const std::vector<std::uint8_t>* owned,
                         const SearchMemory* memory) {
  Grow(robot + 1);
  goal_[robot] = -1;
  const Move out = Escape(ctx, robot, owned, memory);
  if (out != Move::kStay) {
    walked_[robot] = 2;  // its first move is this one
    ++moves_;
  }
  return out;
}

Move DeadlockWalk::Escape(const DecisionContext& ctx, int robot,
                          const std::vector<std::uint8_t>* owned,
                          const SearchMemory* memory) {
  if (!ctx.sensor) return Move::kStay;
  const Lattice& lattice = ctx.map->lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const int m = ctx.beliefs->layout().num_targets();
  open_.Of(ctx, robot, memory);
  const std::vector<std::uint8_t>& open = open_.open();
  const std::vector<Vec2>& aims = open_.aims();
  for (int k = 0; k < m; ++k)
    if (open[k] && PredictedPrecision(*ctx.map, *ctx.sensor,
                                      lattice.Point(here), aims[k]) > 0.0)
      return Move::kStay;  // it is where it can measure
  // The walk's target while it is open and reachable.
  int& goal = goal_[robot];
  if (goal >= 0 && goal < m && open[goal]) {
    claimed_.assign(m, 0);
    claimed_[goal] = 1;
    const Move move =
        toward_.FirstMove(*ctx.map, *ctx.sensor, here, aims, claimed_);
    if (move != Move::kStay) return move;
  }
  goal = -1;
  // With claims: the nearest of the open targets the robot owns (in
  // lattice moves among it and its neighbours), where it owns one.
  if (owned && static_cast<int>(owned->size()) == m) {
    claimed_.assign(m, 0);
    bool any = false;
    for (int k = 0; k < m; ++k) {
      claimed_[k] = (*owned)[k] && open[k];
      any = any || claimed_[k];
    }
    if (any) {
      const Move move =
          toward_.FirstMove(*ctx.map, *ctx.sensor, here, aims, claimed_, &goal);
      if (move != Move::kStay) return move;
    }
  }
  // Leave to a neighbour the open targets it is nearer to (straight line;
  // ties to the lower index); all of them when each is nearer to one.
  const Vec2 p = lattice.Point(here);
  claimed_.assign(open.begin(), open.end());
  bool any = false;
  for (int k = 0; k < m; ++k) {
    if (!open[k]) continue;
    const double mine = (aims[k] - p).squaredNorm();
    for (int j : ctx.comm->Neighbors(robot)) {
      if (j == robot) continue;
      const double theirs =
          (aims[k] - lattice.Point((*ctx.robot_lattice)[j])).squaredNorm();
      if (theirs < mine || (theirs == mine && j < robot)) {
        claimed_[k] = 0;
        break;
      }
    }
    any = any || claimed_[k];
  }
  return toward_.FirstMove(*ctx.map, *ctx.sensor, here, aims,
                           any ? claimed_ : open, &goal);
}

// --- NoUndo
// --------------------------------------------------------------------

Move NoUndo::Replace(const DecisionContext& ctx, int robot, Move best,
                     const float* logits,
                     const std::vector<std::uint8_t>* owned,
                     const SearchMemory* memory, DeadlockWalk* walk) {
  const Move out = walk->Start(ctx, robot, owned, memory);
  if (out != Move::kStay) return out;
  if (ctx.sensor && !walk->open().any()) {
    // Nothing open in the robot's own belief (a tracking mission after
    // success): the network's best valid move that does not undo the last.
    const Lattice& lattice = ctx.map->lattice();
    const int here = (*ctx.robot_lattice)[robot];
    const int next =
        BestValidMove(lattice, here, logits, static_cast<int>(best));
    if (next >= 0) {
      ++idle_moves_;
      return static_cast<Move>(next);
    }
  }
  ++stays_;
  return Move::kStay;
}

// --- Approach ----------------------------------------------------------------

bool Approach::Replace(const DecisionContext& ctx, int robot, Move best,
                       const std::vector<std::uint8_t>& owned,
                       const SearchMemory* memory, ClaimsShaper* claims,
                       DeadlockWalk* walk, Move* move) {
  if (!ctx.sensor) return false;
  const Lattice& lattice = ctx.map->lattice();
  const int here = (*ctx.robot_lattice)[robot];
  const int next = lattice.Next(here, best);
  // The claims of this step own open targets only, at these aims.
  const int m = static_cast<int>(owned.size());
  int at_here = -1, at_next = -1;  // moves to the nearest; -1: none
  for (int k = 0; k < m; ++k) {
    if (!owned[k]) continue;
    const Vec2 aim = OpenAims::AimOf(ctx, robot, k, memory);
    const int a = claims->Distance(aim, here);
    if (a >= 0 && (at_here < 0 || a < at_here)) at_here = a;
    if (next < 0) continue;
    const int b = claims->Distance(aim, next);
    if (b >= 0 && (at_next < 0 || b < at_next)) at_next = b;
  }
  if (at_here <= 0 || (at_next >= 0 && at_next < at_here)) return false;
  const Move out = walk->Start(ctx, robot, &owned, memory);
  if (out == Move::kStay) return false;
  ++walks_;
  *move = out;
  return true;
}

// --- RulesLayer
// ----------------------------------------------------------------

RulesLayer::RulesLayer(const IgbNetParams& params)
    : params_(params),
      memory_(params.search, params.share_search),
      claims_(params.claims),
      walk_(params.max_reversals, params.max_walk) {}

void RulesLayer::Reset(int num_robots, int num_targets) {
  memory_.Reset(num_robots, num_targets);
  claims_.Reset();
  walk_.Reset(num_robots);
  no_undo_.Reset();
  approach_.Reset();
}

void RulesLayer::Shape(const DecisionContext& ctx,
                       const std::vector<int>& rows) {
  // Search memory is the deciding robots' (async decisions: a robot on its
  // way has not reached the point it would record a miss at); claims are
  // the whole team's.
  DecidingRows(ctx, rows, &deciding_);
  memory_.Update(ctx, deciding_);
  claims_.Shape(ctx, rows, memory_.aims());
}

const std::vector<std::vector<std::uint8_t>>* RulesLayer::shown() const {
  return claims_.mode() == TargetClaimsMode::kNone ? nullptr : &claims_.shown();
}

bool RulesLayer::Shaped(const DecisionContext& ctx, int b, int robot,
                        bool shows_aims) const {
  return claims_.Narrowed(b) || (shows_aims && memory_.Moved(ctx, robot));
}

bool RulesLayer::Walk(const DecisionContext& ctx, int b, int robot,
                      Move* move) {
  const int reversals = ctx.history ? ctx.history->reversals(robot) : 0;
  return walk_.Walk(ctx, robot, reversals, claims_.Owned(b), memory_.aims(),
                    move);
}

Move RulesLayer::Arbitrate(const DecisionContext& ctx, int b, int robot,
                           Move best, const float* logits, bool* replaced) {
  *replaced = false;
  const std::vector<std::uint8_t>* owned = claims_.Owned(b);
  Move walk = Move::kStay;
  if (params_.approach && owned && claims_.Unplanned(b) &&
      approach_.Replace(ctx, robot, best, *owned, memory_.aims(), &claims_,
                        &walk_, &walk)) {
    *replaced = true;
    return walk;
  }
  const Move last = ctx.history ? ctx.history->last(robot) : Move::kStay;
  if (!params_.no_undo || !IsReversal(last, best)) return best;
  *replaced = true;
  return no_undo_.Replace(ctx, robot, best, logits, claims_.Owned(b),
                          memory_.aims(), &walk_);
}

std::vector<std::pair<std::string, long>> RulesLayer::Counters() const {
  std::vector<std::pair<std::string, long>> c = walk_.Counters();
  for (auto& p : no_undo_.Counters()) c.push_back(p);
  for (auto& p : approach_.Counters()) c.push_back(p);
  for (auto& p : memory_.Counters()) c.push_back(p);
  return c;
}

}  // namespace aia
