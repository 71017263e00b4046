// Coverage on any DEM (issue 11): square coverage cells of the true ground size whatever the
// raster's pixel shape, the body read from the CRS, and the planner with its defaults on every
// real DEM in ../shared/dems (ROVER_SHARED_DEMS overrides the folder). How long each takes is
// printed by tests/bench/dem_planners.sh, not checked here.
#include <doctest/doctest.h>

#include <cpl_conv.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "core/coverage/coverage_entry.hpp"
#include "core/coverage/terrain_world.hpp"
#include "core/planning/planner.hpp"
#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

fs::path demsDir() {
  if (const char* env = std::getenv("ROVER_SHARED_DEMS")) return env;
  return fs::path(ROVER_SOURCE_DIR) / ".." / "shared" / "dems";
}

struct TempFile {
  fs::path path = fs::temp_directory_path() / ("roverplan-cov-" + std::to_string(::getpid()) + "-" +
                                               std::to_string(std::rand()) + ".tif");
  ~TempFile() {
    std::error_code ec;
    fs::remove(path, ec);
  }
};

// A flat GeoTIFF in `proj4` with the given geotransform.
void writeFlat(const std::string& path, int rows, int cols, const std::array<double, 6>& gt,
               const std::string& proj4) {
  maps::ensureGdal();
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  REQUIRE(OSRImportFromProj4(srs, proj4.c_str()) == OGRERR_NONE);
  char* wkt = nullptr;
  OSRExportToWkt(srs, &wkt);
  Raster<float> z(GridGeometry{rows, cols, 1.0, 1.0}, 0.0f);
  z.geo.valid = true;
  z.geo.geotransform = gt;
  z.geo.crsWkt = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  maps::writeGeoTiff(path, z);
}

// The ground size of a coverage cell, measured independently of the loader: its edge midpoints
// taken to the map's CRS (maps/georef), then by PROJ to an azimuthal equidistant projection centred
// on the cell (distances from the centre are true there).
std::pair<double, double> groundSize(const maps::LoadedDem& d, const GridGeometry& grid,
                                     CellIndex c) {
  const GridGeometry& m = d.dem.geometry();
  const Eigen::Vector2d centre = cellToLocal(grid, c);
  const double h = grid.cellWidth / 2;
  OGRSpatialReferenceH src = OSRNewSpatialReference(d.dem.z.geo.crsWkt.c_str());
  OSRSetAxisMappingStrategy(src, OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReferenceH geog = OSRCloneGeogCS(src);
  OSRSetAxisMappingStrategy(geog, OAMS_TRADITIONAL_GIS_ORDER);
  const Eigen::Vector2d C = maps::localToCrs(m, d.dem.z.geo, centre);
  double lon = C.x(), lat = C.y(), z0 = 0;
  if (!OSRIsGeographic(src)) {
    OGRCoordinateTransformationH toGeog = OCTNewCoordinateTransformation(src, geog);
    OCTTransform(toGeog, 1, &lon, &lat, &z0);
    OCTDestroyCoordinateTransformation(toGeog);
  }
  OGRSpatialReferenceH aeqd = OSRClone(geog);
  OSRSetAE(aeqd, lat, lon, 0, 0);
  OSRSetAxisMappingStrategy(aeqd, OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformationH t = OCTNewCoordinateTransformation(src, aeqd);
  double xs[4], ys[4], zs[4] = {0, 0, 0, 0};
  const Eigen::Vector2d pts[4] = {{centre.x() - h, centre.y()},
                                  {centre.x() + h, centre.y()},
                                  {centre.x(), centre.y() - h},
                                  {centre.x(), centre.y() + h}};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d P = maps::localToCrs(m, d.dem.z.geo, pts[i]);
    xs[i] = P.x();
    ys[i] = P.y();
  }
  REQUIRE(OCTTransform(t, 4, xs, ys, zs));
  OCTDestroyCoordinateTransformation(t);
  OSRDestroySpatialReference(aeqd);
  OSRDestroySpatialReference(geog);
  OSRDestroySpatialReference(src);
  return {std::hypot(xs[1] - xs[0], ys[1] - ys[0]), std::hypot(xs[3] - xs[2], ys[3] - ys[2])};
}

void checkTrueSquares(const maps::LoadedDem& d, double cell) {
  coverage::World w = coverage::worldFromDem(d.dem, cell);
  const GridGeometry& g = w.geometry();
  REQUIRE(g.rows >= 2);
  REQUIRE(g.cols >= 2);
  CHECK(g.cellWidth == cell);
  CHECK(g.cellHeight == cell);
  for (CellIndex c :
       {CellIndex{0, 0}, CellIndex{g.rows / 2, g.cols / 2}, CellIndex{g.rows - 1, g.cols - 1}}) {
    auto [we, sn] = groundSize(d, g, c);
    CAPTURE(c.row);
    CAPTURE(c.col);
    MESSAGE("cell " << cell << " m is " << we << " m east-west and " << sn
                    << " m north-south on the ground");
    CHECK(std::fabs(we / cell - 1) < 0.005);
    CHECK(std::fabs(sn / cell - 1) < 0.005);
  }
}

}  // namespace

TEST_CASE(
    "coverage grid: an equirectangular raster at 60° latitude gives square cells of the true "
    "size") {
  // Projected metres of an equidistant cylindrical CRS true at the equator: at 60° one pixel of
  // 1 projected metre is 0.5 m east-west on the ground.
  const double R = 3396190, y0 = R * 60.0 * kDeg;
  TempFile f;
  writeFlat(f.path.string(), 200, 400, {1000.0, 1.0, 0, y0 + 100, 0, -1.0},
            "+proj=eqc +lat_ts=0 +lat_0=0 +lon_0=0 +R=3396190 +units=m +no_defs");
  maps::LoadedDem d = maps::loadDem(f.path.string());
  CHECK(d.dem.geometry().cellWidth == doctest::Approx(0.5).epsilon(0.001));
  checkTrueSquares(d, 4.0);
  CHECK(coverage::worldFromDem(d.dem, 4.0).geometry().cols == 50);  // 200 m of ground
}

TEST_CASE(
    "coverage grid: a geographic raster (degrees, WGS 84) gives square cells of the true size") {
  TempFile f;
  const double step = 1e-4;  // about 5.6 m east-west and 11.1 m north-south at 60° N
  writeFlat(f.path.string(), 100, 200, {10.0, step, 0, 60.0 + 100 * step / 2, 0, -step},
            "+proj=longlat +datum=WGS84 +no_defs");
  maps::LoadedDem d = maps::loadDem(f.path.string());
  REQUIRE(d.info.geographic);
  checkTrueSquares(d, 20.0);
  CHECK(maps::bodyOfCrs(d.dem.z.geo.crsWkt) == terrain::Body::Earth);
}

TEST_CASE("body from the CRS: Mars, Moon, Earth and none") {
  auto wktOf = [](const char* proj4) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    OSRImportFromProj4(srs, proj4);
    char* wkt = nullptr;
    OSRExportToWkt(srs, &wkt);
    std::string s = wkt;
    CPLFree(wkt);
    OSRDestroySpatialReference(srs);
    return s;
  };
  CHECK(maps::bodyOfCrs(wktOf("+proj=eqc +R=3396190 +units=m")) == terrain::Body::Mars);
  CHECK(maps::bodyOfCrs(wktOf("+proj=longlat +R=1737400")) == terrain::Body::Moon);
  CHECK(maps::bodyOfCrs(wktOf("+proj=utm +zone=32 +datum=WGS84")) == terrain::Body::Earth);
  CHECK(maps::bodyOfCrs("") == terrain::Body::Unknown);
  CHECK(maps::bodyOfCrs("not a CRS") == terrain::Body::Unknown);
}

TEST_CASE("coverage with default parameters (frontier on) on every DEM in ../shared/dems") {
  const fs::path dir = demsDir();
  if (!fs::exists(dir)) {
    MESSAGE("SKIPPED: " << dir.string() << " absent (set ROVER_SHARED_DEMS)");
    return;
  }
  struct Site {
    const char* file;
    terrain::Body body;
  };
  const Site sites[] = {{"mars_gale_hirise_1m/missionDEM.tif", terrain::Body::Mars},
                        {"moon_lola_kepler_crater/kepler.tif", terrain::Body::Moon},
                        {"moon_lola_ldem4_global/LDEM_4.IMG", terrain::Body::Moon},
                        {"earth_luxembourg_srtm/elev.tif", terrain::Body::Earth},
                        {"moon_kepler_rescaled_025m/kepler_site.tif", terrain::Body::Moon}};
  PlannerRegistry reg = makeBuiltinRegistry();
  const Planner& planner = reg.get("coverage");
  for (const Site& s : sites) {
    CAPTURE(s.file);
    const fs::path path = dir / s.file;
    if (!fs::exists(path)) {
      MESSAGE("SKIPPED: " << path.string() << " absent");
      continue;
    }
    maps::LoadedDem d = maps::loadDem(path.string());
    PlanningProblem p;
    p.body = maps::bodyOfCrs(d.dem.z.geo.crsWkt);
    CHECK(p.body == s.body);
    const coverage::CoverageParams defaults;
    const double cell =
        coverage::resolveCoverageCell(d.dem.geometry(), defaults.coverageCell, defaults.cellBudget);
    p.world = coverage::worldFromDem(d.dem, cell, defaults.traversability());
    p.dem = std::make_shared<terrain::Dem>(std::move(d.dem));
    // Start on the middle cell of the largest free region that passes the mission check.
    std::vector<int> sizes;
    auto label = coverage::freeComponents(p.world, sizes);
    const int largest =
        static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
    std::vector<int> pool;
    for (int i = 0; i < static_cast<int>(label.size()); ++i)
      if (label[i] == largest) pool.push_back(i);
    const ParamSet params{{"frontier", true}};
    bool placed = false;
    for (std::size_t k = 0; k < pool.size() && !placed;
         k += std::max<std::size_t>(1, pool.size() / 50)) {
      p.rovers = {{cellToLocal(p.world.geometry(),
                               p.world.geometry().cell(pool[(pool.size() / 2 + k) % pool.size()])),
                   0.0}};
      try {
        planner.validate(p, params);
        placed = true;
      } catch (const Error&) {
      }
    }
    REQUIRE(placed);
    PlanResult r = planner.run(p, params, nullptr, nullptr);
    const GridGeometry& g = p.world.geometry();
    MESSAGE(std::string(s.file) << ": cell " << cell << " m, " << g.rows << " x " << g.cols
                                << ", reachable "
                                << (r.metric("free_cells") - r.metric("unreachable_cells"))
                                << ", stop " << enumName(r.stopReason) << ", coverage of reachable "
                                << r.metric("coverage_reachable") << ", path length ratio "
                                << r.metric("path_length_ratio") << ", energy "
                                << r.metric("energy_j") << " J, max pitch "
                                << r.metric("max_pitch_deg") << "°, g " << r.metric("gravity_m_s2"));
    CHECK(static_cast<std::int64_t>(g.rows) * g.cols <= defaults.cellBudget);
    CHECK((r.stopReason == StopReason::GoalReached || r.stopReason == StopReason::NothingLeft));
    CHECK(r.metric("coverage_reachable") >= defaults.coverage - 1e-9);
    CHECK(r.metric("energy_j") > 0);
    CHECK(std::isfinite(r.metric("energy_j")));
    CHECK(r.metric("max_pitch_deg") > 0);
    CHECK(r.metric("max_pitch_deg") < defaults.impassableDeg + 1e-3);
    CHECK(r.metric("gravity_m_s2") == terrain::bodyGravity(s.body));
  }
}
