#pragma once
// Which rovers can leave their starts while the others stand, and in what order they leave
// (issue 25). A rover standing at its start is an obstacle from t = 0: no rover comes closer than
// the safety distance to it until it has gone. A rover boxed in by standing rovers therefore
// leaves after them: the order takes every rover that has a way out past the rovers still
// standing, lowest index first, and repeats with the rest. Pure geometry on the rovers' centres
// (the safety distance is between centres), optionally on passable ground.
#include <Eigen/Core>
#include <functional>
#include <vector>

namespace rover::planning {

// A point a rover may drive over (an empty function: everywhere).
using PassableGround = std::function<bool(const Eigen::Vector2d&)>;

// How much farther than the safety distance a rover's way out keeps from every rover still
// standing (issue 25). A way out that keeps only the safety distance may be a lane a few
// centimetres wide between two standing rovers' safety discs (the generated formation's 2.25 m
// lattice leaves 0.25 m); no RRT* path followed by the simulated rover threads that, and the
// coordinator, which plans the rovers in this order, left 7 of 64 rovers at their starts for the
// whole mission. With the margin a way out is a corridor at least 2 × 0.5 m wide for the rover's
// centre, and the rovers inside a formation leave after the ones round them.
inline constexpr double kDepartureMargin = 0.5;  // m

// The order in which the rovers standing at `starts` can leave, each one while every rover after
// it still stands at its start. The rule: a rover has a way out when, over `passable` ground, it
// can get past all the rovers still standing — to farther than safety + kDepartureMargin outside
// their bounding box (with `passable`, ten safety distances farther: out of a pocket of passable
// ground round them) — keeping safety + kDepartureMargin from each of them, or, from one it
// already stands nearer than that, the distance it stands at (it may move away, never closer).
// The test runs on a grid of an eighth of the safety distance (coarser for starts spread over
// more than 50 safety distances); the distance kept from a nearer neighbour is less one grid
// step, the grid's resolution (so a rover exactly the safety distance from a neighbour can move
// away from it). Rounds: every rover with a way out in a round leaves in that round, by index;
// one with a way out past the rovers of the first round leaves in the second, and so on: the
// outer rovers of a block or lattice leave first, the inner ones after. For starts the check
// accepts (pairwise at least `safety`) on open ground the order always exists: the rover with
// the largest x (then y) can always move away from every other. Returns the rovers in order,
// how many of them leave in the first round, and the rovers left with no way out in `boxedIn`
// (empty: all leave).
struct Departure {
  std::vector<int> order;
  std::vector<int> boxedIn;
  int firstRound = 0;  // how many of `order` leave in the first round (free to leave at once)
};
Departure departureOrder(const std::vector<Eigen::Vector2d>& starts, double safety,
                         const PassableGround& passable = {});

}  // namespace rover::planning
