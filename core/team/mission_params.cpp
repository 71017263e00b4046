#include "core/team/mission_params.hpp"

#include <cmath>

#include "core/common/error.hpp"

namespace rover::team {

void TeamMissionParams::validate() const {
  validateRouteParams(route);
  coordination.validate();
  if (!std::isfinite(footprint) || !(footprint > 0) || footprint > 1e4)
    throwInvalidParameter("footprint_m", "must be a number of metres in (0, 10000]");
  if (!std::isfinite(sensingDiameter) || !(sensingDiameter > 0) || sensingDiameter > footprint)
    throwInvalidParameter("sensing_diameter_m", "must be > 0 and at most the footprint");
  const auto& t = traversability;
  if (!std::isfinite(t.highRiskDeg) || t.highRiskDeg <= 0 || t.highRiskDeg > 90)
    throwInvalidParameter("high_risk_deg", "must be in (0, 90]");
  if (!std::isfinite(t.impassableDeg) || t.impassableDeg < t.highRiskDeg || t.impassableDeg > 90)
    throwInvalidParameter("impassable_deg", "must be in [high_risk_deg, 90]");
  if (!std::isfinite(exceedanceLimit) || !(exceedanceLimit > 0) || exceedanceLimit > M_PI / 2)
    throwInvalidParameter("exceedance_limit", "must be in (0, 90] degrees");
  if (!std::isfinite(hybridCell) || !(hybridCell > 0) || hybridCell > footprint)
    throwInvalidParameter("hybrid_cell_m", "must be > 0 and at most the footprint");
  if (!std::isfinite(hybridCoverage) || !(hybridCoverage > 0) || hybridCoverage > 1)
    throwInvalidParameter("hybrid_coverage", "must be in (0, 1]");
  if (!std::isfinite(keepOutMargin) || keepOutMargin < 0 || keepOutMargin > 10)
    throwInvalidParameter("keep_out_margin", "must be a number of metres in [0, 10]");
  if (subTeamSize < 0 || subTeamSize > 64)
    throwInvalidParameter("sub_team_size", "must be a whole number of rovers in [0, 64] (0 = one team)");
  for (std::size_t z = 0; z < keepOut.zones.size(); ++z)
    for (const Ring& ring : keepOut.zones[z])
      for (const auto& v : ring)
        if (!v.allFinite())
          throw Error(ErrorCode::InvalidInput, "keep_out",
                      "keep_out: zone " + std::to_string(z) + " has a vertex that is not finite");
}

}  // namespace rover::team
