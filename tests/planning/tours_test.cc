#include "aia/planning/tours.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

namespace aia {
namespace {

// Points on a line: point p is at coordinate p - 50, target k's region is
// the single point `at[k]`, and a leg is the distance walked.
class LineLegs : public LegOracle {
 public:
  explicit LineLegs(std::vector<int> at) : at_(std::move(at)) {}
  Leg Compute(int from, int, int k) override {
    return {std::abs(at_[k] - from), at_[k]};
  }
  bool TimeVarying(int) const override { return false; }

 private:
  std::vector<int> at_;
};

TEST(ToursTest, OneRobotVisitsTheNearSideFirst) {
  // Robot at 50; targets at 49 and 53. Near first: arrivals 1 and 5
  // (latency 6, makespan 5); far first: 3 and 7 (latency 10).
  LineLegs legs({53, 49});
  TourPlanner planner;
  for (TourObjective objective :
       {TourObjective::kLatency, TourObjective::kMakespan}) {
    const Tours t =
        planner.Plan({50}, {0, 1}, {1.0, 1.0}, {objective, 1000}, legs);
    EXPECT_EQ(t.order[0], (std::vector<int>{1, 0}));
    EXPECT_EQ(t.makespan, 5);
    EXPECT_DOUBLE_EQ(t.latency, 6.0);
  }
}

TEST(ToursTest, TwoRobotsSplitTheLine) {
  // Robots at 40 and 60; targets at 41, 42, 43, 44 and 70: robot 0 walks
  // 41..44 (arrivals 1, 2, 3, 4), robot 1 goes to 70 (10): latency 20 and
  // makespan 10, optimal for both objectives.
  LineLegs legs({41, 42, 43, 44, 70});
  TourPlanner planner;
  for (TourObjective objective :
       {TourObjective::kLatency, TourObjective::kMakespan}) {
    const Tours t = planner.Plan({40, 60}, {4, 3, 2, 1, 0}, {1, 1, 1, 1, 1},
                                 {objective, 10000}, legs);
    EXPECT_EQ(t.order[0], (std::vector<int>{0, 1, 2, 3}));
    EXPECT_EQ(t.order[1], (std::vector<int>{4}));
    EXPECT_DOUBLE_EQ(t.latency, 20.0);
    EXPECT_EQ(t.makespan, 10);
  }
}

TEST(ToursTest, WeightsOrderTheVisits) {
  // One robot at 50; targets at 47 (weight 1) and 52 (weight 10). Latency:
  // 52 first costs 2 * 10 + 7 = 27, 47 first 3 + 8 * 10 = 83. The makespan
  // prefers 52 first too (7 against 8).
  LineLegs legs({47, 52});
  TourPlanner planner;
  const Tours t = planner.Plan({50}, {0, 1}, {1.0, 10.0},
                               {TourObjective::kLatency, 1000}, legs);
  EXPECT_EQ(t.order[0], (std::vector<int>{1, 0}));
  EXPECT_DOUBLE_EQ(t.latency, 27.0);
}

TEST(ToursTest, UnreachableTargetsAreLeftOut) {
  class Legs : public LegOracle {
   public:
    Leg Compute(int from, int, int k) override {
      if (k == 1) return {};
      return {1, from + 1};
    }
    bool TimeVarying(int) const override { return false; }
  } legs;
  TourPlanner planner;
  const Tours t = planner.Plan({0, -1}, {0, 1}, {1, 1}, {}, legs);
  EXPECT_EQ(t.order[0], (std::vector<int>{0}));
  EXPECT_TRUE(t.order[1].empty());  // inactive robot
  EXPECT_EQ(t.unassigned, (std::vector<int>{1}));
}

}  // namespace
}  // namespace aia
