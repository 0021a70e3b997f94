// The sampling tree's nodes (planning/sampling_tree.h) as a flat arena, a
// struct of arrays: per node the robots' lattice points, its packed
// information blocks, its parent, depth, unlocalized targets, accumulated
// cost J, det sum and a lower bound of its total cost. No per-node heap
// allocation: a node is a row of each array.
#ifndef AIA_PLANNING_NODE_ARENA_H_
#define AIA_PLANNING_NODE_ARENA_H_

#include <cstddef>
#include <new>
#include <utility>
#include <vector>

namespace aia {

// A tree whose arena may hold at most this many bytes is small: its solve
// takes no share of the process's tree budget (sampling_tree.cc), and its
// blocks come from malloc, whose freed pages the next solve reuses.
inline constexpr std::size_t kSmallTreeBytes = std::size_t{32} << 20;

// The arena's allocator: blocks larger than kSmallTreeBytes are mapped from
// the kernel (on 2 MiB boundaries, for transparent huge pages) and returned
// to it when freed, so that a finished large solve gives its memory back
// whatever the process's malloc keeps (jemalloc in build/aia keeps freed
// pages), and only the pages a tree fills are resident.
template <typename T>
struct ArenaAllocator {
  using value_type = T;
  ArenaAllocator() = default;
  template <typename U>
  ArenaAllocator(const ArenaAllocator<U>&) {}  // NOLINT: allocator rebind
  T* allocate(std::size_t n);
  void deallocate(T* p, std::size_t n);
  // resize() leaves new numbers uninitialized (default-initialized): each
  // row is written whole before it is read (NodeArena::Open's caller), and
  // zeroing it first cost a tenth of a small solve.
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <typename U>
  bool operator==(const ArenaAllocator<U>&) const {
    return true;
  }
  template <typename U>
  bool operator!=(const ArenaAllocator<U>&) const {
    return false;
  }
};
template <typename T>
using ArenaVector = std::vector<T, ArenaAllocator<T>>;

class NodeArena {
 public:
  // Empties it for nodes of `robots` lattice points and `stride` numbers of
  // information; the storage is kept for the next solve.
  void Reset(int robots, int stride);

  int size() const { return static_cast<int>(parent_.size()); }
  const int* Pos(int v) const {
    return pos_.data() + static_cast<std::size_t>(v) * n_;
  }
  const double* Info(int v) const {
    return info_.data() + static_cast<std::size_t>(v) * stride_;
  }
  int parent(int v) const { return parent_[v]; }
  int depth(int v) const { return depth_[v]; }
  int unloc(int v) const { return unloc_[v]; }
  double cost(int v) const { return cost_[v]; }
  double det_sum(int v) const { return det_sum_[v]; }
  double lower(int v) const { return lower_[v]; }
  int MaxDepth() const;

  // A new node, number size(), in two steps: Open() copies its points and
  // returns its information row to fill (a parent's row, Info(), may be read
  // meanwhile); Close() gives the rest and makes it count.
  double* Open(const int* positions);
  void Close(int parent, int depth, int unloc, double det_sum, double cost,
             double lower);

  // Room for `nodes` nodes at once (no copies as the arena grows), and the
  // memory given back to the kernel.
  void Reserve(std::size_t nodes);
  void Release();
  // The storage the nodes fill.
  std::size_t bytes() const;

 private:
  int n_ = 0, stride_ = 0;
  ArenaVector<int> pos_;      // nodes x n
  ArenaVector<double> info_;  // nodes x stride
  ArenaVector<int> parent_, depth_, unloc_;
  ArenaVector<double> cost_, det_sum_, lower_;
};

}  // namespace aia

#endif  // AIA_PLANNING_NODE_ARENA_H_
