// The igbnet policy's coordination layer (learning/coordination.h), part by
// part, with a scorer of fixed logits in place of the network: each expected
// move is worked out by hand. `none` takes the most probable valid move and
// nothing else; each rule changes only what its comment says.
#include "aia/learning/coordination.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "aia/learning/igbnet_policy.h"
#include "aia/learning/scorer.h"
#include "aia/world/lattice.h"
#include "support/team_fixture.h"

namespace aia {
namespace {

using Logits = std::array<float, kNumMoves>;  // left, right, up, down

// Each robot's logits, whatever it is shown; remembers what the shapers
// showed it at the last step.
class FixedScorer : public MoveScorer {
 public:
  explicit FixedScorer(std::vector<Logits> logits, bool shows_aims = false)
      : logits_(std::move(logits)), shows_aims_(shows_aims) {}
  void Reset(const Map&, int, int) override {}
  void Score(const DecisionContext&, const ScoringRows& rows,
             const ScorerView& view, float* logits) override {
    for (int b = 0; b < rows.size(); ++b)
      std::copy(logits_[rows.rows[b]].begin(), logits_[rows.rows[b]].end(),
                logits + b * kNumMoves);
    shown_given = view.shown != nullptr;
    shown = view.shown ? *view.shown : std::vector<std::vector<std::uint8_t>>();
    aims_given = view.aims != nullptr;
    unread = view.unread ? *view.unread : std::vector<std::uint8_t>();
  }
  bool ShowsAims() const override { return shows_aims_; }

  bool shown_given = false, aims_given = false;
  std::vector<std::vector<std::uint8_t>> shown;
  std::vector<std::uint8_t> unread;

 private:
  std::vector<Logits> logits_;
  bool shows_aims_;
};

// A 12 x 2 m corridor, lattice points at x = 0.25 .. 11.75 and y = 0.25 ..
// 1.75; one target believed at (10, 1.25) (sensor range 2 m): the only
// nearest point that measures it from the west is (8.25, 1.25).
const char* kCorridor = R"(
workspace: {size: [12, 2]}
robots: {count: 2, step: 0.5, start: [[3.25, 1.25], [1.25, 0.75]]}
targets: {list: [{position: [10.5, 1.25], prior_mean: [10.0, 1.25]}]}
sensor: {range: 2.0}
)";

// A team at `at` whose robots made `moves` (in order; kStay: none) to get
// there, deciding with `policy`.
struct Step {
  testing::TeamFixture team;
  MoveHistory history;
  std::vector<double> prior;
  Step(const char* yaml, const std::vector<Vec2>& at,
       const std::vector<std::vector<Move>>& moves)
      : team(yaml) {
    const Lattice& lattice = team.world.map.lattice();
    for (std::size_t i = 0; i < at.size(); ++i)
      team.positions[i] = lattice.NearestPoint(at[i]);
    history.Reset(team.world.NumRobots());
    for (std::size_t i = 0; i < moves.size(); ++i)
      for (Move m : moves[i]) history.Record(static_cast<int>(i), m);
    prior.assign(team.world.NumTargets(), 0.0);
  }
  std::vector<Move> Decide(IgbNetPolicy* policy, bool reset = true) {
    DecisionContext ctx = team.Context();
    ctx.central = nullptr;
    ctx.log_det_prior = &prior;
    ctx.history = &history;
    if (reset)
      policy->Reset(team.world.map, team.world.NumRobots(),
                    team.world.NumTargets(), 1);
    std::vector<Move> moves(team.world.NumRobots());
    policy->Decide(ctx, &moves);
    return moves;
  }
  // Every robot's belief of every target localized.
  void Localize() {
    for (int i = 0; i < team.beliefs.rows(); ++i)
      for (int k = 0; k < team.world.NumTargets(); ++k) {
        team.beliefs.Omega(i, k) *= 1e6;
        team.beliefs.Xi(i, k) *= 1e6;
      }
  }
};

long Counter(const Policy& policy, const std::string& name) {
  for (const auto& [key, value] : policy.Counters())
    if (key == name) return value;
  ADD_FAILURE() << "no counter " << name;
  return -1;
}

IgbNetParams Rules(int max_reversals, bool no_undo) {
  IgbNetParams p;
  p.max_reversals = max_reversals;
  p.no_undo = no_undo;
  p.claims = TargetClaimsMode::kNone;
  p.search = false;
  return p;
}

IgbNetParams None() {
  IgbNetParams p;
  p.coordination = Coordination::kNone;
  return p;
}

// Robot 0 on the top row (up is invalid): logits up 3 > down 2 > right 1 >
// left 0 give down. Robot 1: left and right tie at 2, the lower index wins:
// left. Robot 0 came up, so down undoes it: `none` takes it anyway, and
// nothing is counted as hand-written.
TEST(CoordinationTest, NoneTakesTheNetworksMostProbableValidMove) {
  Step s(kCorridor, {{3.25, 1.75}, {1.25, 0.75}}, {{Move::kUp}, {}});
  IgbNetPolicy policy(std::make_unique<FixedScorer>(
                          std::vector<Logits>{{0, 1, 3, 2}, {2, 2, 0, 0}}),
                      None());
  EXPECT_EQ(s.Decide(&policy), (std::vector<Move>{Move::kDown, Move::kLeft}));
  EXPECT_EQ(Counter(policy, "decisions"), 2);
  EXPECT_EQ(Counter(policy, "handwritten_moves"), 0);
  EXPECT_EQ(Counter(policy, "walk_moves"), 0);
}

// No undo: robot 0 at (3.25, 1.25) came right; its network prefers left
// (the undo). It walks instead: ten moves east along y = 1.25 to (8.25,
// 1.25), first move right. Robot 1 (not undoing) takes its network's move.
TEST(CoordinationTest, NoUndoWalksWhereTheNetworkWouldUndo) {
  Step s(kCorridor, {{3.25, 1.25}, {1.25, 0.75}}, {{Move::kRight}, {}});
  IgbNetPolicy policy(std::make_unique<FixedScorer>(
                          std::vector<Logits>{{5, 0, 0, 0}, {0, 0, 5, 0}}),
                      Rules(0, true));
  EXPECT_EQ(s.Decide(&policy), (std::vector<Move>{Move::kRight, Move::kUp}));
  EXPECT_EQ(Counter(policy, "walk_moves"), 1);
  EXPECT_EQ(Counter(policy, "no_undo_stays"), 0);
  EXPECT_EQ(Counter(policy, "handwritten_moves"), 1);
}

// At (8.75, 1.25) robot 0 can measure the target (1.25 m off): where its
// network would undo its last move it stays, and the world applies the
// stay as it is.
TEST(CoordinationTest, NoUndoStaysWhereTheRobotCanMeasure) {
  Step s(kCorridor, {{8.75, 1.25}, {1.25, 0.75}}, {{Move::kRight}, {}});
  IgbNetPolicy policy(std::make_unique<FixedScorer>(
                          std::vector<Logits>{{5, 0, 0, 0}, {0, 0, 5, 0}}),
                      Rules(0, true));
  const std::vector<Move> moves = s.Decide(&policy);
  EXPECT_EQ(moves[0], Move::kStay);
  EXPECT_EQ(Counter(policy, "no_undo_stays"), 1);
  EXPECT_EQ(Counter(policy, "handwritten_moves"), 1);
  Rng rng(1);
  bool replaced = true;
  EXPECT_EQ(ApplyWorldRule(s.team.world.map.lattice(), s.team.positions[0],
                           moves[0], rng, &replaced),
            Move::kStay);
  EXPECT_FALSE(replaced);
}

// Nothing open in robot 0's belief: where its network would undo (left,
// logit 5) it takes the best other valid move: up (3), not down (1) or
// right (0).
TEST(CoordinationTest, NoUndoMovesOnWhereNothingIsOpen) {
  Step s(kCorridor, {{3.25, 1.25}, {1.25, 0.75}}, {{Move::kRight}, {}});
  s.Localize();
  IgbNetPolicy policy(std::make_unique<FixedScorer>(
                          std::vector<Logits>{{5, 0, 3, 1}, {0, 0, 5, 0}}),
                      Rules(0, true));
  EXPECT_EQ(s.Decide(&policy)[0], Move::kUp);
  EXPECT_EQ(Counter(policy, "idle_moves"), 1);
  EXPECT_EQ(Counter(policy, "handwritten_moves"), 1);
}

// The deadlock walk: robot 0 went right, then left (one reversal): with
// max_reversals 1 it walks east (right) before its network (left) is asked.
// Having walked one move (to (3.75, 1.25), another reversal), with max_walk
// 1 it hands back: the network's left; with max_walk 0 it walks on. A
// walking robot's logits are read by nothing: the scorer is told so (its
// row unread) and the policy's logits for it are 0.
TEST(CoordinationTest, DeadlockWalkAfterAReversalForAtMostMaxWalkMoves) {
  const std::vector<std::uint8_t> walking = {1, 0}, none = {0, 0};
  const std::vector<float> robot1 = {0, 0, 5, 0};
  for (const int max_walk : {0, 1}) {
    IgbNetParams params = Rules(1, false);
    params.max_walk = max_walk;
    auto scorer = std::make_unique<FixedScorer>(
        std::vector<Logits>{{5, 0, 0, 0}, {0, 0, 5, 0}});
    FixedScorer* seen = scorer.get();
    IgbNetPolicy policy(std::move(scorer), params);
    Step first(kCorridor, {{3.25, 1.25}, {1.25, 0.75}},
               {{Move::kRight, Move::kLeft}, {}});
    EXPECT_EQ(first.Decide(&policy)[0], Move::kRight);
    EXPECT_EQ(seen->unread, walking);
    EXPECT_EQ(std::vector<float>(policy.logits().begin(),
                                 policy.logits().begin() + kNumMoves),
              std::vector<float>(kNumMoves, 0.0f));
    EXPECT_EQ(std::vector<float>(policy.logits().begin() + kNumMoves,
                                 policy.logits().end()),
              robot1);
    Step second(kCorridor, {{3.75, 1.25}, {1.25, 0.75}},
                {{Move::kRight, Move::kLeft, Move::kRight}, {}});
    EXPECT_EQ(second.Decide(&policy, false)[0],
              max_walk == 1 ? Move::kLeft : Move::kRight)
        << "max_walk " << max_walk;
    EXPECT_EQ(seen->unread, max_walk == 1 ? none : walking);
    EXPECT_EQ(Counter(policy, "walk_moves"), max_walk == 1 ? 1 : 2);
  }
}

// Claims (route): robot 0 next to target 0, robot 1 next to target 1; each
// is shown only its own. With claims none the scorer is shown every target
// (no view). Both moves are the network's on a shaped input: counted.
TEST(CoordinationTest, ClaimsShowEachRobotItsOwnTarget) {
  const char* two = R"(
workspace: {size: [12, 2]}
robots: {count: 2, step: 0.5, start: [[1.25, 1.25], [10.75, 1.25]]}
targets: {list: [{position: [2.0, 1.25], prior_mean: [2.0, 1.25]},
                 {position: [10.0, 1.25], prior_mean: [10.0, 1.25]}]}
sensor: {range: 2.0}
)";
  for (const TargetClaimsMode mode :
       {TargetClaimsMode::kRoute, TargetClaimsMode::kNearest,
        TargetClaimsMode::kNone}) {
    Step s(two, {{1.25, 1.25}, {10.75, 1.25}}, {});
    IgbNetParams params = Rules(0, false);
    params.claims = mode;
    auto scorer = std::make_unique<FixedScorer>(
        std::vector<Logits>{{0, 0, 5, 0}, {0, 0, 5, 0}});
    FixedScorer* seen = scorer.get();
    IgbNetPolicy policy(std::move(scorer), params);
    s.Decide(&policy);
    if (mode == TargetClaimsMode::kNone) {
      EXPECT_FALSE(seen->shown_given);
      EXPECT_EQ(Counter(policy, "shaped_moves"), 0);
      continue;
    }
    ASSERT_TRUE(seen->shown_given);
    ASSERT_EQ(seen->shown.size(), 2u);
    EXPECT_EQ(seen->shown[0], (std::vector<std::uint8_t>{1, 0}));
    EXPECT_EQ(seen->shown[1], (std::vector<std::uint8_t>{0, 1}));
    EXPECT_EQ(Counter(policy, "shaped_moves"), 2);
    EXPECT_EQ(Counter(policy, "handwritten_moves"), 2);
  }
}

// Approach: robot 0 at (3.25, 1.25) owns the target (robot 1 is farther):
// ten moves to (8.25, 1.25) or, from (3.25, 1.75), ten to (8.25, 1.75),
// which measures it too (1.82 m off). Its network's up keeps the ten, so
// with nearest claims (no route plan) the robot walks: right. Its
// network's right (nine) is taken. With route claims (a plan for 2 robots
// x 1 target) or approach false the network's up is taken. Robot 1 owns
// nothing: its network's move (up) in every case.
TEST(CoordinationTest, ApproachWalksWhereTheNetworkDoesNotNearItsTarget) {
  struct Case {
    TargetClaimsMode claims;
    bool approach;
    Logits logits;
    Move expected;
    long walks;
  };
  for (const Case& c :
       {Case{TargetClaimsMode::kNearest, true, {0, 0, 5, 0}, Move::kRight, 1},
        Case{TargetClaimsMode::kNearest, true, {0, 5, 0, 0}, Move::kRight, 0},
        Case{TargetClaimsMode::kRoute, true, {0, 0, 5, 0}, Move::kUp, 0},
        Case{TargetClaimsMode::kNearest, false, {0, 0, 5, 0}, Move::kUp, 0}}) {
    Step s(kCorridor, {{3.25, 1.25}, {1.25, 0.75}}, {});
    IgbNetParams params = Rules(0, true);
    params.claims = c.claims;
    params.approach = c.approach;
    IgbNetPolicy policy(std::make_unique<FixedScorer>(
                            std::vector<Logits>{c.logits, {0, 0, 5, 0}}),
                        params);
    const std::vector<Move> moves = s.Decide(&policy);
    EXPECT_EQ(moves[0], c.expected) << static_cast<int>(c.claims) << " "
                                    << c.approach << " " << c.logits[2];
    EXPECT_EQ(moves[1], Move::kUp);
    EXPECT_EQ(Counter(policy, "approach_walks"), c.walks);
    EXPECT_EQ(Counter(policy, "walk_moves"), c.walks);
  }
}

// A rule's key away from its default with coordination none would do
// nothing: FirstRuleKeySet names it (the policy's loader refuses it).
TEST(CoordinationTest, NoneNamesARuleKeyThatWouldDoNothing) {
  IgbNetParams p = None();
  EXPECT_EQ(FirstRuleKeySet(p), "");
  p.no_undo = false;
  EXPECT_EQ(FirstRuleKeySet(p), "policy.no_undo");
  p.max_reversals = 3;
  EXPECT_EQ(FirstRuleKeySet(p), "policy.max_reversals");
  p = None();
  p.approach = false;
  EXPECT_EQ(FirstRuleKeySet(p), "policy.approach");
  // The last rule key too; the network's precision is not a rule.
  p = None();
  p.precision = Precision::kFloat32;
  EXPECT_EQ(FirstRuleKeySet(p), "");
  p.refresh = 0.01;
  EXPECT_EQ(FirstRuleKeySet(p), "policy.refresh");
}

}  // namespace
}  // namespace aia
