#include "core/team/route_generator.hpp"

namespace rover::team {

std::unique_ptr<RouteGenerator> makeRouteGenerator(RouteMethod method, const RouteParams& params) {
  switch (method) {
    case RouteMethod::Lawnmower:
      return std::make_unique<LawnmowerRoute>(params.targets);
    case RouteMethod::Lhc:
      return std::make_unique<LhcRoute>(params);
    case RouteMethod::Orienteering:
      return std::make_unique<OrienteeringRoute>(params);
    case RouteMethod::LhcGwConv:
      break;
  }
  return std::make_unique<LhcGwConvRoute>(params);
}

CellIndex teamStartCell(const SearchGrid& grid, const std::vector<Pose>& starts) {
  Eigen::Vector2d c(0, 0);
  for (const auto& s : starts) c += Eigen::Vector2d(s.x, s.y);
  if (!starts.empty()) c /= static_cast<double>(starts.size());
  return grid.cellAt(c);
}

Route computeRoute(const SearchGrid& grid, CellIndex start, RouteMethod method,
                   const RouteParams& params) {
  return makeRouteGenerator(method, params)->generate(grid, start);
}

}  // namespace rover::team
