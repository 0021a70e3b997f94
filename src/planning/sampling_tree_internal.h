// What the files of the sampling tree share (planning/sampling_tree.h):
// sampling_tree.cc (the nodes, their arena and the search),
// sampling_aims.cc (where each target is seen: aims, observation regions,
// BFS fields, spatial indexes), sampling_rollouts.cc (the tours and the
// rollouts that finish a node) and sampling_path.cc (the returned path: idle
// rewriting, useful-until, the plan).
#ifndef AIA_SRC_PLANNING_SAMPLING_TREE_INTERNAL_H_
#define AIA_SRC_PLANNING_SAMPLING_TREE_INTERNAL_H_

#include <limits>

namespace aia {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Entries of a packed upper triangle of a dim x dim block.
inline int PackedSize(int dim) { return dim * (dim + 1) / 2; }

// Moving targets' aims and fields are kept per span of this many depths (the
// predicted mean at the span's middle), for at most kMaxBuckets spans.
inline constexpr int kBucket = 4;
inline constexpr int kMaxBuckets = 64;

}  // namespace aia

#endif  // AIA_SRC_PLANNING_SAMPLING_TREE_INTERNAL_H_
