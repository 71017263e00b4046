#pragma once
// The route generator stage (SPEC §3.1): the team's targets over the search grid, from the search
// cell the team starts in. One small class per method over route_search's algorithms, chosen by
// makeRouteGenerator; the mission composes whichever it is given.
#include <array>
#include <memory>
#include <vector>

#include "core/common/enum_names.hpp"
#include "core/team/rover_sim.hpp"
#include "core/team/orienteering_route.hpp"
#include "core/team/route_search.hpp"

namespace rover::team {

enum class RouteMethod { LhcGwConv, Lhc, Lawnmower, Orienteering };

class RouteGenerator {
 public:
  virtual ~RouteGenerator() = default;
  // The route from `start`; impassable search cells are never targets. Throws InvalidInput
  // "start" outside the grid.
  virtual Route generate(const SearchGrid& grid, CellIndex start) const = 0;
};

// Local hill climbing over the search cells (paper 001 §3.5, Lin & Goodrich 2009), with or
// without global warming.
class HillClimbRoute : public RouteGenerator {
 public:
  HillClimbRoute(RouteParams p, bool globalWarming) : p_(p) { p_.globalWarming = globalWarming; }
  Route generate(const SearchGrid& grid, CellIndex start) const override {
    return lhcGwConv(grid, start, p_);
  }

 private:
  RouteParams p_;
};

// LHC_GW_CONV: the climb over every global-warming level, the best kept (eq. 8).
class LhcGwConvRoute final : public HillClimbRoute {
 public:
  explicit LhcGwConvRoute(const RouteParams& p) : HillClimbRoute(p, true) {}
};

// Plain hill climbing (k = 0 only): the baseline without global warming.
class LhcRoute final : public HillClimbRoute {
 public:
  explicit LhcRoute(const RouteParams& p) : HillClimbRoute(p, false) {}
};

// Boustrophedon lanes over the rows: the baseline that ignores the PDM.
class LawnmowerRoute final : public RouteGenerator {
 public:
  explicit LawnmowerRoute(int targets) : targets_(targets) {}
  Route generate(const SearchGrid& grid, CellIndex start) const override {
    return lawnmower(grid, start, targets_);
  }

 private:
  int targets_;
};

// ours (issue 25): the whole PDM as an orienteering problem (orienteering_route.hpp).
class OrienteeringRoute final : public RouteGenerator {
 public:
  explicit OrienteeringRoute(const RouteParams& p) : p_(p) {}
  Route generate(const SearchGrid& grid, CellIndex start) const override {
    return orienteeringRoute(grid, start, p_);
  }

 private:
  RouteParams p_;
};

std::unique_ptr<RouteGenerator> makeRouteGenerator(RouteMethod method, const RouteParams& params);

// The search cell the team starts in: the one holding the centroid of the rovers' starts.
CellIndex teamStartCell(const SearchGrid& grid, const std::vector<Pose>& starts);

// makeRouteGenerator(method, params)->generate(grid, start).
Route computeRoute(const SearchGrid& grid, CellIndex start, RouteMethod method,
                   const RouteParams& params);

}  // namespace rover::team

// The names of the values above (enum_names.hpp).
namespace rover {
template <>
struct EnumNames<team::RouteMethod> {
  static constexpr std::array<EnumName<team::RouteMethod>, 4> table{{
      {team::RouteMethod::LhcGwConv, "lhc_gw_conv"},
      {team::RouteMethod::Lhc, "lhc"},
      {team::RouteMethod::Lawnmower, "lawnmower"},
      {team::RouteMethod::Orienteering, "orienteering"},
  }};
};
}  // namespace rover
