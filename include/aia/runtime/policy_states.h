// Policy instances kept per mission, for a caller that decides for many
// missions by turns (the Python module's aia.builtin_policy, deciding for
// each mission it is handed, also for missions on several threads of
// aia.evaluate). A mission's policy is started afresh (created and Reset)
// at its first decision and at a step that is not the one after its last,
// so that deciding at every step repeats `aia run`; only the `capacity`
// missions decided for most recently keep theirs.
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
    int next_step = 0;  // the step its next decision continues from
    std::uint64_t last_use = 0;
  };

  explicit PolicyStates(std::size_t capacity = 256);

  // The entry of mission `id` deciding at `step`: the kept one when its last
  // decision was at `step - 1` (or it was just made for `step`), otherwise a
  // new one whose policy `make` returns (created and Reset). The least
  // recently used entries beyond the capacity are forgotten; the returned
  // one stays valid while it is held. After deciding, call Decided. Not
  // thread-safe: the caller serializes (the Python module holds the GIL).
  std::shared_ptr<Entry> For(
      std::uint64_t id, int step,
      const std::function<std::unique_ptr<Policy>()>& make);
  // Records that `entry` decided at `step`.
  static void Decided(Entry* entry, int step) { entry->next_step = step + 1; }

  std::size_t size() const { return entries_.size(); }
  bool Has(std::uint64_t id) const { return entries_.count(id) > 0; }

 private:
  void Forget();

  std::size_t capacity_;
  std::map<std::uint64_t, std::shared_ptr<Entry>> entries_;  // by mission id
  std::uint64_t uses_ = 0;
};

}  // namespace aia

#endif  // AIA_RUNTIME_POLICY_STATES_H_
