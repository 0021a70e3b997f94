// Policy instances kept per mission, for a caller that decides for many
// missions by turns (the Python module's aia.builtin_policy, deciding for
// each mission it is handed, also for missions on several threads of
// aia.evaluate). A mission's policy is started afresh (created and Reset)
// at its first decision and at a round (DecisionContext::round) that is not
// the one after its last, so that deciding at every round repeats `aia
// run`, in async too, where the step may repeat. A mission's entry is kept
// until the caller drops it (the mission ended): however many missions
// take turns, none loses its policy's state.
#ifndef AIA_RUNTIME_POLICY_STATES_H_
#define AIA_RUNTIME_POLICY_STATES_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>

#include "aia/planning/policy.h"

namespace aia {

class PolicyStates {
 public:
  struct Entry {
    std::unique_ptr<Policy> policy;
    int next_round = 0;  // the round its next decision continues from
  };

  // The entry of mission `id` deciding at `round`: the kept one when its
  // last decision was at `round - 1` (or it was just made for `round`), else
  // a new one whose policy `make` returns (created and Reset). The returned
  // entry stays valid while it is held, dropped or not. After deciding, call
  // Decided. Not thread-safe: the caller serializes.
  std::shared_ptr<Entry> For(
      std::uint64_t id, int round,
      const std::function<std::unique_ptr<Policy>()>& make);
  // Records that `entry` decided at `round`.
  static void Decided(Entry* entry, int round) {
    entry->next_round = round + 1;
  }
  // Forgets mission `id` (it ended: deleted, restarted, its evaluation run
  // over); a later decision for it starts afresh.
  void Drop(std::uint64_t id) { entries_.erase(id); }

  std::size_t size() const { return entries_.size(); }
  bool Has(std::uint64_t id) const { return entries_.count(id) > 0; }

 private:
  std::map<std::uint64_t, std::shared_ptr<Entry>> entries_;  // by mission id
};

}  // namespace aia

#endif  // AIA_RUNTIME_POLICY_STATES_H_
