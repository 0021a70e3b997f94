// What a dataset sample tells the loss about the moves: the valid moves of
// the lattice point nearest the robot (ValidMoveBits), worked out by hand.
#include "aia/learning/dataset.h"

#include <gtest/gtest.h>

#include "aia/world/lattice.h"

namespace aia {
namespace {

constexpr std::uint8_t Bit(Move m) { return 1u << static_cast<int>(m); }

TEST(DatasetTest, ValidMoveBitsAreTheMovesOfTheNearestLatticePoint) {
  // 4 x 4 points of 0.5 m and a 0.04 m wall at x = 1.0 between columns 1
  // and 2: both sides are free, but no move crosses it.
  const Lattice lat({2.0, 2.0}, 0.5, 0.15, {Box{{0.98, 0.0}, {1.02, 2.0}}});
  // The corner (0, 0): right and up.
  EXPECT_EQ(ValidMoveBits(lat, {0.25, 0.25}),
            Bit(Move::kRight) | Bit(Move::kUp));
  // Beside the wall at (1, 1): everything but right; from a position that
  // physics left 0.2 m off the point, the same.
  const std::uint8_t beside =
      Bit(Move::kLeft) | Bit(Move::kUp) | Bit(Move::kDown);
  EXPECT_EQ(ValidMoveBits(lat, {0.75, 0.75}), beside);
  EXPECT_EQ(ValidMoveBits(lat, {0.60, 0.90}), beside);
  // Across it at (2, 3), the top row: right and down.
  EXPECT_EQ(ValidMoveBits(lat, {1.25, 1.75}),
            Bit(Move::kRight) | Bit(Move::kDown));
}

TEST(DatasetTest, SamplesByWorldListsEachWorldsSamplesInOrder) {
  Dataset d;
  d.worlds.resize(3);
  for (int w : {1, 0, 1, 2, 0}) {
    DatasetSample s;
    s.world = w;
    d.samples.push_back(s);
  }
  const std::vector<std::vector<int>> by = SamplesByWorld(d);
  ASSERT_EQ(by.size(), 3u);
  EXPECT_EQ(by[0], (std::vector<int>{1, 4}));
  EXPECT_EQ(by[1], (std::vector<int>{0, 2}));
  EXPECT_EQ(by[2], (std::vector<int>{3}));
}

}  // namespace
}  // namespace aia
