#include "aia/runtime/policy_states.h"

#include "aia/core/check.h"

namespace aia {

PolicyStates::PolicyStates(std::size_t capacity) : capacity_(capacity) {
  AIA_CHECK(capacity >= 1);
}

std::shared_ptr<PolicyStates::Entry> PolicyStates::For(
    std::uint64_t id, int step,
    const std::function<std::unique_ptr<Policy>()>& make) {
  std::shared_ptr<Entry>& slot = entries_[id];
  if (!slot || step != slot->next_step) {
    slot = std::make_shared<Entry>();
    slot->policy = make();
    slot->next_step = step;
  }
  std::shared_ptr<Entry> entry = slot;  // kept while Forget runs
  entry->last_use = ++uses_;
  Forget();
  return entry;
}

// O(entries) per forgotten one; the capacity is small and a mission is
// forgotten at most once per decision.
void PolicyStates::Forget() {
  while (entries_.size() > capacity_) {
    auto oldest = entries_.begin();
    for (auto it = entries_.begin(); it != entries_.end(); ++it)
      if (it->second->last_use < oldest->second->last_use) oldest = it;
    entries_.erase(oldest);
  }
}

}  // namespace aia
