// The motion lattice (docs/design.md, World): points at ((i + 0.5) step, (j +
// 0.5) step), moves of one step left/right/up/down. A point is free when a
// robot disc of the given radius there touches no obstacle; a move is valid
// when both ends are free and the disc swept along it touches no obstacle
// either (so a thin wall between two free points is not crossed).
#ifndef AIA_WORLD_LATTICE_H_
#define AIA_WORLD_LATTICE_H_

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "aia/core/geometry.h"
#include "aia/core/rng.h"
#include "aia/core/types.h"

namespace aia {

class Lattice {
 public:
  Lattice() = default;
  Lattice(const Vec2& workspace, double step, double radius,
          const std::vector<Box>& obstacles);

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int size() const { return nx_ * ny_; }
  double step() const { return step_; }

  int Index(int ix, int iy) const { return iy * nx_ + ix; }
  int Ix(int idx) const { return idx % nx_; }
  int Iy(int idx) const { return idx / nx_; }
  Vec2 Point(int idx) const {
    return {(Ix(idx) + 0.5) * step_, (Iy(idx) + 0.5) * step_};
  }
  bool Free(int idx) const { return free_[idx] != 0; }
  int NumFree() const { return num_free_; }
  // A number no other lattice built in this process has (a copy keeps it;
  // 0 for an empty one): what is computed from a lattice can be kept by it.
  std::uint64_t id() const { return id_; }

  // Destination of a move from `idx`, or -1 when the move is invalid.
  int Next(int idx, Move m) const {
    return m == Move::kStay ? idx
                            : next_[static_cast<size_t>(idx) * kNumMoves +
                                    static_cast<int>(m)];
  }
  bool Valid(int idx, Move m) const { return Next(idx, m) >= 0; }
  int NumValidMoves(int idx) const;

  // The lattice point nearest to p (ignoring obstacles), clamped to the grid.
  int NearestPoint(const Vec2& p) const;
  // The free lattice point nearest to p (Euclidean), or -1 if none is free.
  int NearestFree(const Vec2& p) const;

  // Connected component id of each free point (-1 for blocked points), by
  // valid moves; components are numbered by size, 0 the largest.
  const std::vector<int>& components() const { return component_; }
  int NumComponents() const { return num_components_; }

 private:
  int nx_ = 0, ny_ = 0;
  double step_ = 0.5;
  int num_free_ = 0;
  int num_components_ = 0;
  std::uint64_t id_ = 0;
  std::vector<std::uint8_t> free_;
  std::vector<int> next_;  // size() * kNumMoves
  std::vector<int> component_;
};

// f(q, ix, iy) for each point of the (2 span + 1)^2 window of lattice
// points centred on point c, clamped to the lattice, row by row (iy outer,
// ix inner).
template <typename F>
void ForEachInWindow(const Lattice& lattice, int c, int span, F&& f) {
  const int cx = lattice.Ix(c), cy = lattice.Iy(c);
  const int x1 = std::min(lattice.nx() - 1, cx + span);
  const int y1 = std::min(lattice.ny() - 1, cy + span);
  for (int iy = std::max(0, cy - span); iy <= y1; ++iy)
    for (int ix = std::max(0, cx - span); ix <= x1; ++ix)
      f(lattice.Index(ix, iy), ix, iy);
}

// Breadth-first distances (in moves) over valid moves from a set of sources;
// -1 where unreachable. `dist` is resized to the lattice size; `queue` is
// scratch space (pass the same vector each call to avoid allocation).
void BfsDistances(const Lattice& lattice, const int* sources, int num_sources,
                  std::vector<int>* dist, std::vector<int>* queue);

// The first move of a shortest path down a distance field from `from`: the
// valid move to a point whose distance is one less (lowest move index first).
// kStay when `from` is a source or cannot reach one.
Move StepDownField(const Lattice& lattice, const std::vector<int>& dist,
                   int from);

// The move that takes a robot from lattice point a to its neighbour b; kStay
// when b is a itself or no neighbour of a.
Move MoveBetween(const Lattice& lattice, int a, int b);

// A uniformly random valid move from `from`, or kStay when there is none.
Move RandomValidMove(const Lattice& lattice, int from, Rng& rng);

// The world rule (docs/design.md, World), the same for every policy: an invalid
// move (into an obstacle or out of the workspace) is replaced by a uniformly
// random valid one; with none the robot stays. A stay is a valid decision:
// the robot holds its lattice point. Sets *replaced when the wanted move was
// not applied as is.
Move ApplyWorldRule(const Lattice& lattice, int from, Move wanted, Rng& rng,
                    bool* replaced);

}  // namespace aia

#endif  // AIA_WORLD_LATTICE_H_
