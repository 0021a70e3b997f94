// PolicyStates (runtime/policy_states.h): a mission keeps its policy while
// it decides round after round, starts afresh otherwise, and keeps it
// however many missions take turns until it is dropped.
#include "aia/runtime/policy_states.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace aia {
namespace {

// Counts how many were made; each knows its number.
struct Made {
  int count = 0;
};

class NumberedPolicy : public Policy {
 public:
  explicit NumberedPolicy(int number) : number(number) {}
  std::string_view name() const override { return "numbered"; }
  void Reset(const Map&, int, int, std::uint64_t) override {}
  PolicyStatus Decide(const DecisionContext&, std::vector<Move>*) override {
    return PolicyStatus::kOk;
  }
  const int number;
};

int NumberOf(const PolicyStates::Entry& e) {
  return static_cast<const NumberedPolicy&>(*e.policy).number;
}

std::shared_ptr<PolicyStates::Entry> Decide(PolicyStates* states, Made* made,
                                            std::uint64_t id, int round) {
  auto entry = states->For(id, round, [&] {
    return std::make_unique<NumberedPolicy>(++made->count);
  });
  PolicyStates::Decided(entry.get(), round);
  return entry;
}

TEST(PolicyStatesTest, AMissionKeepsItsPolicyFromRoundToRound) {
  PolicyStates states;
  Made made;
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 0)), 1);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 1)), 1);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 2)), 1);
  // Another mission has its own.
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 8, 0)), 2);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 3)), 1);
  EXPECT_EQ(made.count, 2);
}

TEST(PolicyStatesTest, ARoundThatIsNotTheNextStartsAfresh) {
  PolicyStates states;
  Made made;
  Decide(&states, &made, 7, 0);
  Decide(&states, &made, 7, 1);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 5)), 2);  // skipped rounds
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 0)), 3);  // restarted
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 0)), 4);  // the same round
  // A mission first seen at a later round (resumed) starts there.
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 9, 12)), 5);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 9, 13)), 5);
}

// VectorMissions of 257 missions deciding in turn lost every policy's
// state at every step while 256 were kept.
TEST(PolicyStatesTest, EveryMissionKeepsItsPolicyUntilDropped) {
  PolicyStates states;
  Made made;
  constexpr int kMissions = 1000;
  for (int round = 0; round < 3; ++round)
    for (int id = 1; id <= kMissions; ++id)
      EXPECT_EQ(NumberOf(*Decide(&states, &made, id, round)), id);
  EXPECT_EQ(made.count, kMissions);
  const auto held = Decide(&states, &made, 2, 3);
  states.Drop(2);
  EXPECT_FALSE(states.Has(2));
  EXPECT_TRUE(states.Has(1));
  // The entry held is still whole; a decision after the drop starts afresh.
  EXPECT_EQ(NumberOf(*held), 2);
  EXPECT_EQ(held->next_round, 4);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 2, 4)), kMissions + 1);
}

}  // namespace
}  // namespace aia
