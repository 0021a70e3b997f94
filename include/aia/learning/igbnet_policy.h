// The `igbnet` policy (docs/learning.md): robot i's move from its own fused
// belief, its neighbours' positions in this step's graph and the map only.
// A scorer (learning/scorer.h: the channels and the network) and, with
// policy.coordination rules, a hand-written coordination layer around it
// (learning/coordination.h). The model is loaded once per process (shared
// by every episode and thread that uses the same file).
#ifndef AIA_LEARNING_IGBNET_POLICY_H_
#define AIA_LEARNING_IGBNET_POLICY_H_

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "aia/core/fields.h"
#include "aia/learning/coordination.h"
#include "aia/learning/network.h"
#include "aia/learning/scorer.h"
#include "aia/planning/policy.h"
#include "aia/planning/registry.h"

namespace aia {

// Where `policy.model` points when a scenario does not say: the model
// trained for the coordination, models/igbnet.pt for rules (the default
// model, trained with them) and models/igbnet_learned.pt for none (the
// network alone); an installed aia's own PREFIX/share/aia/models/NAME
// (core/plugin.h, InstalledDataDir), else models/NAME under the working
// folder if it is there, else under the source tree.
std::string DefaultModelPath(Coordination coordination = Coordination::kRules);

// The model at `path`, loaded once per process; errors as IgbNet::Load.
std::shared_ptr<const IgbNet> LoadModelOnce(const std::string& path,
                                            const std::string& error_file,
                                            int error_line,
                                            const std::string& key);

// The policy: each step, the coordination layer's shapers (with
// coordination rules) change what the network is shown, a robot on the
// rules' deadlock walk takes its walk's move, the scorer gives every other
// active robot's logits, each takes its most probable valid move (ties to
// the lower move index), and the layer's arbiters may choose or change it.
// With coordination none nothing but the network decides.
class IgbNetPolicy : public NamedPolicy<IgbNetPolicy> {
 public:
  explicit IgbNetPolicy(std::shared_ptr<const IgbNet> net,
                        IgbNetParams params = {});
  // With another scorer (tests: fixed logits).
  explicit IgbNetPolicy(std::unique_ptr<MoveScorer> scorer,
                        IgbNetParams params = {});
  static constexpr std::string_view kName = "igbnet";
  void Reset(const Map& map, int num_robots, int num_targets,
             std::uint64_t seed) override;
  PolicyStatus Decide(const DecisionContext& ctx,
                      std::vector<Move>* moves) override;
  // What each robot learned from its missed measurements (empty until the
  // first decision and without the rules' search memory).
  const SearchMemory& search() const;
  // Since Reset: decisions (robot moves decided); the rules' parts' own
  // counters: walk_moves (moves the deadlock walk made, those no_undo
  // started included), no_undo_stays, idle_moves (no_undo's moves of a
  // robot with nothing open), misses (points added to the search memory);
  // shaped_moves (the network's moves on an input a shaper changed: claims
  // hid an open target, or the memory moved an aim the input shows);
  // handwritten_moves (chosen by an arbiter, or shaped; 0 with
  // coordination none); bfloat16_decisions (the network's decisions made
  // in bfloat16, policy.precision). Every key with either coordination.
  std::vector<std::pair<std::string, long>> Counters() const override;
  // The last step's logits, robot-major (4 per robot; zero for inactive
  // robots and for those the walk moved, which the network did not score),
  // for tools and tests.
  const std::vector<float>& logits() const { return logits_; }

 private:
  std::unique_ptr<MoveScorer> scorer_;
  IgbNetParams params_;
  std::unique_ptr<RulesLayer> rules_;  // null with coordination none
  ScoringRows team_;
  std::vector<float> batch_logits_, logits_;
  std::vector<std::uint8_t> walking_;  // per row: moved by the walk this step
  BeliefDigest digest_;                // this step's, for every part
  NeighbourhoodHolds holds_;  // this step's, with policy.open neighbours
  // The knowledge digest_ and holds_ were worked out from (in async, a
  // round without a sensing tick or a failure keeps them).
  KnowledgeMark known_;
  long decisions_ = 0, shaped_moves_ = 0, handwritten_moves_ = 0,
       bfloat16_decisions_ = 0;
};

// Adds `igbnet` to a registry.
void AddLearnedPolicies(PolicyRegistry* registry);

}  // namespace aia

#endif  // AIA_LEARNING_IGBNET_POLICY_H_
