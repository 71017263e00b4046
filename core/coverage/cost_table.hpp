#pragma once
// Static motion costs mc_static of papers 002 (eq. 1) and 000 (eq. 1/3), as data.
//
// relative[k]: cost of the neighbour k·45° counter-clockwise from the heading
//   (0 straight, 1 left 45°, 2 left 90°, 3 left 135°, 4 reverse, 5 right 135°, 6 right 90°,
//   7 right 45°). Left and right must differ (paper 002 §2.1: no randomness in decisions).
// absolute[d]: cost of moving in world direction d (0 = E, 1 = NE, 2 = N, ... 7 = SE).
//   Zero for spiral. Boustrophedon needs it: a memoryless rule that only sees relative directions
//   cannot tell "keep sweeping" from "turn into the next lane", so the sweep axis lives here.
#include <array>
#include <string>
#include <vector>

namespace rover::coverage {

struct MotionCostTable {
  std::array<double, 8> relative{};
  std::array<double, 8> absolute{};

  double cost(int relativeDir, int absoluteDir) const {
    return relative[relativeDir] + absolute[absoluteDir];
  }
};

// Spiral: turning left (towards the covered side) < straight < right, diagonals after their
// orthogonal neighbour, reversal last. All values < 1.1 = the smallest visited penalty, so any
// unvisited neighbour beats any visited one (paper 000: mc_visited >= 1.1).
MotionCostTable spiralTable();
// Boustrophedon: lanes along x (E/W cheapest), lane shift to the north, then south.
MotionCostTable boustrophedonTable();

// From 8 relative values, or 16 (relative then absolute). Throws InvalidParameter (field `field`)
// on a wrong count, a negative value, or equal left/right costs.
MotionCostTable tableFromList(const std::vector<double>& values, const std::string& field);
std::vector<double> tableToList(const MotionCostTable& table);
void validateTable(const MotionCostTable& table, const std::string& field);

}  // namespace rover::coverage
