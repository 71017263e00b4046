#pragma once
// "ours" (issue 25): a team route that sees the whole PDM. LHC_GW_CONV (paper 001 §3.5) is a
// local method: from the start it climbs to the best neighbour, so on a PDM of separated
// Gaussians it stays round the first one it reaches (on the caldera case all 64 targets stayed
// round one of three, p = 0.290). Here the route is an orienteering problem over the search
// cells (Tsiligirides 1984; Vansteenwegen et al. 2011 survey): the open path from the start cell
// that collects the most original mass within a length budget, solved by greedy insertion by
// mass per added metre, 2-opt to shorten, and swaps of a visited cell for a heavier unvisited
// one, until no move improves it or the round limit is reached. Deterministic, no clock: the
// same grid gives the same route on every machine.
//
// Choices made here where the issue leaves room:
// - The budget is the length of a hill climb of the same number of targets in straight steps,
//   targets × footprint metres, so a mission on this route drives no farther than LHC's (whose
//   diagonal steps make it up to √2 longer).
// - Travel cost between two cells is the straight distance between their centres (the team
//   drives straight between targets; the RRT* and the lattice find the way round obstacles),
//   and only cells of the start's 8-connected passable region are candidates: the reachable
//   ground at the route's scale.
// - Candidates are the 1024 heaviest such cells (ties row-major): a route of 64 targets never
//   reaches further down the ranking on a PDM with any structure, and it bounds the cost at
//   O(rounds · candidates · targets) distance evaluations (a few ms for 64 targets).
// - With no mass anywhere in reach, the route is the lawnmower's (nothing to prefer).
// - Two phases when the budget is longer than kOrienteeringHorizonM (issue 25 reads the team's
//   curve at 300 m per rover): the path of most mass within the horizon (and the horizon's share
//   of the targets) first, then whole-PDM orienteering on from its end with the rest. It replaces
//   the one-phase route only when it has strictly more mass by the horizon. A budget shorter than
//   the horizon gives the one-phase route unchanged.
#include "core/team/route_search.hpp"

namespace rover::team {

inline constexpr int kOrienteeringCandidates = 1024;
// Route metres by which the rovers have driven some 300 m each: in the swinton missions they
// drive 1.2x the straight legs (388 m per rover for a 319 m route, mean of 20; RRT* round slopes
// and teammates, the way from the starts into the slots).
inline constexpr double kOrienteeringHorizonM = 250.0;

// The route from `start` of at most `params.targets` targets and at most
// params.targets × grid.footprint metres (straight segments between centres), collecting the
// most original mass the heuristic finds. Throws InvalidParameter "targets", InvalidInput
// "start" outside the grid.
Route orienteeringRoute(const SearchGrid& grid, CellIndex start, const RouteParams& params);

}  // namespace rover::team
