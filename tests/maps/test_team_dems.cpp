// The team planners (team-search and hybrid, timed coordination) on every real DEM in
// ../shared/dems (ROVER_SHARED_DEMS overrides the folder): rover-scale sites are planned with
// paper 001's defaults and must come out collision-free, every leg accounted for; orbital-scale
// rasters (pixels larger than the team footprint) are refused naming footprint_m, and planned
// once the footprint is a few of their pixels (where that stays within the parameter's 1 km).
// How long each takes is printed by tests/bench/dem_planners.sh, not checked here.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/common/error.hpp"
#include "core/planning/planner.hpp"
#include "core/team/formation.hpp"
#include "core/team/mission_params.hpp"
#include "maps/dem_io.hpp"
#include "maps/georef.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

fs::path demsDir() {
  if (const char* env = std::getenv("ROVER_SHARED_DEMS")) return env;
  return fs::path(ROVER_SOURCE_DIR) / ".." / "shared" / "dems";
}

double metric(const PlanResult& r, const std::string& key) {
  for (const auto& m : r.metrics)
    if (m.key == key) return m.value;
  FAIL("no metric " << key);
  return 0;
}

}  // namespace

TEST_CASE("team planners on every DEM in ../shared/dems") {
  const fs::path dir = demsDir();
  if (!fs::exists(dir)) {
    MESSAGE("SKIPPED: " << dir.string() << " absent (set ROVER_SHARED_DEMS)");
    return;
  }
  const char* files[] = {"mars_gale_hirise_1m/missionDEM.tif", "moon_kepler_rescaled_025m/kepler_site.tif",
                         "moon_lola_kepler_crater/kepler.tif", "moon_lola_ldem4_global/LDEM_4.IMG",
                         "earth_luxembourg_srtm/elev.tif"};
  PlannerRegistry reg = makeBuiltinRegistry();
  for (const std::string file : files) {
    CAPTURE(file);
    const fs::path path = dir / file;
    if (!fs::exists(path)) {
      MESSAGE("SKIPPED: " << path.string() << " absent");
      continue;
    }
    maps::LoadedDem d = maps::loadDem(path.string());
    auto dem = std::make_shared<terrain::Dem>(std::move(d.dem));
    const GridGeometry& g = dem->geometry();
    const double pixel = std::max(g.cellWidth, g.cellHeight);
    PlanningProblem problem;
    problem.dem = dem;
    problem.body = maps::bodyOfCrs(dem->z.geo.crsWkt);
    problem.threads = 2;
    ParamSet params{{"targets", std::int64_t{4}}, {"seed", std::int64_t{3}}};
    team::TeamMissionParams mp;
    if (pixel > mp.footprint) {
      // Orbital scale: the paper's 5 m footprint is smaller than a pixel.
      problem.rovers = {{{g.widthMetres() / 2, g.heightMetres() / 2}, 0.0}};
      try {
        reg.get("team-search").validate(problem, params);
        FAIL("a footprint smaller than a pixel was accepted");
      } catch (const Error& e) {
        CHECK(e.field() == "footprint_m");
      }
      mp.footprint = std::min(8 * pixel, 1000.0);  // the parameter table's bound
      if (mp.footprint < pixel) {  // LOLA's 7.6 km pixels: no team footprint fits; refused above
        MESSAGE(file << ": pixels of " << pixel << " m, larger than any team footprint");
        continue;
      }
      params["footprint_m"] = mp.footprint;
      problem.rovers.clear();
    }
    const auto starts = team::formationStarts(*dem, mp, {g.widthMetres() / 2, g.heightMetres() / 2}, 3);
    for (const auto& s : starts) problem.rovers.push_back({{s.x, s.y}, s.heading});
    for (const std::string name : {"team-search", "hybrid"}) {
      CAPTURE(name);
      const Planner& planner = reg.get(name);
      planner.validate(problem, params);
      const PlanResult r = planner.run(problem, params, nullptr, nullptr);
      MESSAGE(file << " " << name << ": " << metric(r, "targets_reached") << " reached, "
                   << metric(r, "targets_short") << " short, " << metric(r, "targets_skipped")
                   << " skipped, " << metric(r, "targets_no_slot") << " without a slot, "
                   << metric(r, "unreachable_area_m2") << " m² unreachable");
      CHECK(metric(r, "collisions") == 0);
      // Every leg the route asked for is accounted for: reached, short, skipped or slot-less.
      if (name == "team-search")
        CHECK(metric(r, "targets_reached") + metric(r, "targets_short") + metric(r, "targets_skipped") +
                  metric(r, "targets_no_slot") ==
              doctest::Approx(3 * metric(r, "targets")));
      CHECK(metric(r, "targets_reached") > 0);
    }
  }
}
