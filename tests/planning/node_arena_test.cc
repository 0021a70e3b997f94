#include "aia/planning/node_arena.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>

namespace aia {
namespace {

// A block past kSmallTreeBytes is mapped on a 2 MiB boundary (so that the
// kernel can back it with huge pages); every number of it can be written
// and read back, also at its end (the mapping's trimmed tail), and a block
// of the small kind is still an ordinary one.
TEST(NodeArenaTest, LargeBlocksAreWholeAndOnHugePageBoundaries) {
  for (const std::size_t extra : {std::size_t{1}, std::size_t{4093}}) {
    const std::size_t n = kSmallTreeBytes / sizeof(double) + extra;
    ArenaVector<double> v;
    v.reserve(n);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(v.data()) % (2u << 20), 0u);
    v.resize(n);
    std::iota(v.begin(), v.end(), 0.0);
    EXPECT_EQ(v.front(), 0.0);
    EXPECT_EQ(v.back(), static_cast<double>(n - 1));
  }
  ArenaVector<int> small(1000, 7);
  EXPECT_EQ(std::accumulate(small.begin(), small.end(), 0), 7000);
}

// Rows opened and closed read back as written, across the growth of the
// arena's vectors past the mapped size (each Info row is copied whole).
TEST(NodeArenaTest, RowsReadBackAcrossGrowth) {
  NodeArena arena;
  const int robots = 3, stride = 5;
  arena.Reset(robots, stride);
  const int nodes = static_cast<int>(kSmallTreeBytes / (8 * stride)) + 100;
  for (int v = 0; v < nodes; ++v) {
    const int pos[robots] = {v, v + 1, v + 2};
    double* info = arena.Open(pos);
    for (int s = 0; s < stride; ++s) info[s] = v * 10.0 + s;
    arena.Close(v - 1, v % 7, v % 3, 0.5 * v, 2.0 * v, 1.0 * v);
  }
  ASSERT_EQ(arena.size(), nodes);
  for (int v : {0, 1, nodes / 2, nodes - 1}) {
    EXPECT_EQ(arena.Pos(v)[2], v + 2);
    EXPECT_EQ(arena.Info(v)[4], v * 10.0 + 4);
    EXPECT_EQ(arena.parent(v), v - 1);
    EXPECT_EQ(arena.cost(v), 2.0 * v);
  }
  EXPECT_EQ(arena.MaxDepth(), 6);
  arena.Release();
  EXPECT_EQ(arena.size(), 0);
}

}  // namespace
}  // namespace aia
