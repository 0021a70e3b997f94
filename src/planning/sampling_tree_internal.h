// What the files of the sampling tree share (planning/sampling_tree.h):
// sampling_tree.cc (the nodes and the search), sampling_index.cc (the
// spatial indexes of open targets and robots), sampling_rollouts.cc (the
// tours and the rollouts that finish a node) and sampling_path.cc (the
// returned path: idle rewriting, useful-until, the plan). Its own types:
// node_arena.h (the nodes' storage), aim_table.h (where each target is
// planned to be seen), bucket_grid.h (the indexes' grids).
#ifndef AIA_SRC_PLANNING_SAMPLING_TREE_INTERNAL_H_
#define AIA_SRC_PLANNING_SAMPLING_TREE_INTERNAL_H_

#include <limits>

namespace aia {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Entries of a packed upper triangle of a dim x dim block.
inline int PackedSize(int dim) { return dim * (dim + 1) / 2; }

}  // namespace aia

#endif  // AIA_SRC_PLANNING_SAMPLING_TREE_INTERNAL_H_
