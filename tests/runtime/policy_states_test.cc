// PolicyStates (runtime/policy_states.h): a mission keeps its policy while
// it decides step after step, starts afresh otherwise, and only the
// missions used most recently are kept.
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
                                            std::uint64_t id, int step) {
  auto entry = states->For(id, step, [&] {
    return std::make_unique<NumberedPolicy>(++made->count);
  });
  PolicyStates::Decided(entry.get(), step);
  return entry;
}

TEST(PolicyStatesTest, AMissionKeepsItsPolicyFromStepToStep) {
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

TEST(PolicyStatesTest, AStepThatIsNotTheNextStartsAfresh) {
  PolicyStates states;
  Made made;
  Decide(&states, &made, 7, 0);
  Decide(&states, &made, 7, 1);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 5)), 2);  // skipped steps
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 0)), 3);  // restarted
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 7, 0)), 4);  // the same step
  // A mission first seen at a later step (resumed) starts there.
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 9, 12)), 5);
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 9, 13)), 5);
}

TEST(PolicyStatesTest, OnlyTheMostRecentlyUsedAreKept) {
  PolicyStates states(2);
  Made made;
  Decide(&states, &made, 1, 0);
  Decide(&states, &made, 2, 0);
  Decide(&states, &made, 1, 1);  // 1 used after 2
  const auto held = Decide(&states, &made, 2, 1);
  Decide(&states, &made, 3, 0);  // forgets 1, the least recently used
  EXPECT_EQ(states.size(), 2u);
  EXPECT_FALSE(states.Has(1));
  EXPECT_TRUE(states.Has(2));
  EXPECT_TRUE(states.Has(3));
  EXPECT_EQ(NumberOf(*Decide(&states, &made, 1, 2)), 4);  // afresh
  // 2 was forgotten now, but the entry held is still whole.
  EXPECT_FALSE(states.Has(2));
  EXPECT_EQ(NumberOf(*held), 2);
  EXPECT_EQ(held->next_step, 2);
}

}  // namespace
}  // namespace aia
