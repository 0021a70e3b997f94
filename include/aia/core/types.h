// Small shared vocabulary: 2-D vectors, moves, ids.
#ifndef AIA_CORE_TYPES_H_
#define AIA_CORE_TYPES_H_

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string_view>

namespace aia {

using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;

inline constexpr double kPi = 3.14159265358979323846;

// A robot's decision. The paper's admissible set U = {left, right, up, down},
// plus kStay: the robot holds its lattice point. The world applies a stay as
// it is (world/lattice.h, ApplyWorldRule), and applies one where no move is
// valid or the robot has failed. The built-in policies choose from U; only
// the igbnet policy's no-undo rule (learning/coordination.h) chooses a stay.
enum class Move : std::uint8_t {
  kLeft = 0,
  kRight = 1,
  kUp = 2,
  kDown = 3,
  kStay = 4
};

inline constexpr int kNumMoves = 4;  // |U|
inline constexpr std::array<Move, kNumMoves> kMoves = {
    Move::kLeft, Move::kRight, Move::kUp, Move::kDown};

// Lattice offset of a move, in lattice units (x to the right, y up).
inline constexpr std::array<int, 2> MoveDelta(Move m) {
  switch (m) {
    case Move::kLeft:
      return {-1, 0};
    case Move::kRight:
      return {1, 0};
    case Move::kUp:
      return {0, 1};
    case Move::kDown:
      return {0, -1};
    default:
      return {0, 0};
  }
}

// The move that undoes m (left and right, up and down); kStay for kStay.
inline constexpr Move Opposite(Move m) {
  return m == Move::kStay ? Move::kStay
                          : static_cast<Move>(static_cast<int>(m) ^ 1);
}

}  // namespace aia

#endif  // AIA_CORE_TYPES_H_
