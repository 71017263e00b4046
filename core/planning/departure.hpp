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

// The order in which the rovers standing at `starts` can leave, each one while every rover after
// it still stands at its start: a rover has a way out when, keeping `safety` from every start
// still standing, over `passable` ground, it can get past all of them — to farther than `safety`
// outside their bounding box (with `passable`, ten safety distances farther: out of a pocket of
// passable ground round them). The test runs on a grid of an eighth of the safety distance (coarser for starts
// spread over more than 50 safety distances) and
// keeps the safety distance less one grid step (so a rover exactly the safety distance from a
// neighbour can move away from it). Rounds: every rover with a
// way out in a round leaves in that round, by index; one with a way out past the rovers of the
// first round leaves in the second, and so on. For starts the check accepts (pairwise at least
// `safety`) on open ground the order always exists: the outermost rover can always move away.
// Returns the rovers in order; the rovers left with no way out in `boxedIn` (empty: all leave).
struct Departure {
  std::vector<int> order;
  std::vector<int> boxedIn;
};
Departure departureOrder(const std::vector<Eigen::Vector2d>& starts, double safety,
                         const PassableGround& passable = {});

}  // namespace rover::planning
