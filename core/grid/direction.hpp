#pragma once
// The 8 moves of a grid rover. Direction d in 0..7 is the heading d·45° counter-clockwise from east
// (0 = E, 1 = NE, 2 = N, ... 7 = SE), the same convention as headings in the local frame.
#include <array>
#include <cmath>
#include <numbers>

namespace rover {

constexpr int kDirections = 8;
// Column and row offsets per direction; north is row - 1 because row 0 is the top of the grid.
constexpr std::array<int, 8> kDirCol{1, 1, 0, -1, -1, -1, 0, 1};
constexpr std::array<int, 8> kDirRow{0, -1, -1, -1, 0, 1, 1, 1};

constexpr bool isDiagonal(int dir) {
  return (dir & 1) != 0;
}
// dirOf's table, rows -1..1 × cols -1..1. At namespace scope: a constexpr array local to the
// function is rebuilt on the stack at every call, and the load right after those stores stalled
// the coverage engine's every move (a twelfth of a laine-fig6 study's cycles).
inline constexpr std::array<int, 9> kDirByOffset{3, 2, 1, 4, -1, 0, 5, 6, 7};
// Direction of a one-cell move (dRow, dCol), each in -1..1; -1 for (0, 0).
constexpr int dirOf(int dRow, int dCol) {
  return kDirByOffset[(dRow + 1) * 3 + (dCol + 1)];
}
// Direction after turning `rel` steps of 45° counter-clockwise (left); rel may be negative.
constexpr int rotateDir(int dir, int rel) {
  return ((dir + rel) % 8 + 8) % 8;
}
// Signed turn from `from` to `to` in 45° steps, in [-3, 4] (4 = reversal).
constexpr int turnSteps(int from, int to) {
  int d = ((to - from) % 8 + 8) % 8;
  return d > 4 ? d - 8 : d;
}
inline double dirToRadians(int dir) {
  return dir * std::numbers::pi / 4.0;
}
// Nearest of the 8 directions to a heading in radians (counter-clockwise from east).
inline int radiansToDir(double heading) {
  long k = std::lround(heading / (std::numbers::pi / 4.0));
  return static_cast<int>(((k % 8) + 8) % 8);
}

}  // namespace rover
