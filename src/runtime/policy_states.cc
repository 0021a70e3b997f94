#include "aia/runtime/policy_states.h"

namespace aia {

std::shared_ptr<PolicyStates::Entry> PolicyStates::For(
    std::uint64_t id, int round,
    const std::function<std::unique_ptr<Policy>()>& make) {
  std::shared_ptr<Entry>& slot = entries_[id];
  if (!slot || round != slot->next_round) {
    slot = std::make_shared<Entry>();
    slot->policy = make();
    slot->next_round = round;
  }
  return slot;
}

}  // namespace aia
