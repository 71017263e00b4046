// Disk budgets (server/store/disk_budget.hpp) and compact PDM storage (issue 22): a map's PDMs,
// layers and results past its budget answer 413/507 naming the reason and the field; a Gaussian
// PDM is stored as its components, a stored pdm.tif of an older version still loads.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/pdm/pdm.hpp"
#include "maps/dem_io.hpp"
#include "server/api/error_table.hpp"
#include "server/json/pdm_json.hpp"
#include "server/store/disk_budget.hpp"
#include "api_server.hpp"

namespace rover::test {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Uploads a flat rows × cols GeoTIFF (1 m cells) as a map; returns its id.
std::string flatMap(ApiServer& s, const TempDir& tmp, int rows, int cols) {
  Raster<float> z(GridGeometry{rows, cols, 1.0, 1.0}, 0.0f);
  const std::string path = tmp.str("flat.tif");
  maps::writeGeoTiff(path, z);
  auto r = request(s.port(), "POST", "/api/maps?filename=flat.tif&name=flat", readAll(path), "image/tiff");
  REQUIRE(r.status == 201);
  return r.json()["id"];
}

}  // namespace

TEST_CASE("disk budget: one object larger than a map's budget is 413, a full map or server 507, a release makes room") {
  store::DiskBudget b;
  store::DiskBudgetLimits l;
  l.perMapBytes = 1000;
  l.globalBytes = 3000;
  b.setLimits(l);
  try {
    b.charge("pdms/big", store::DiskUse::Pdm, "m1", 1001, "body");
    FAIL("a PDM larger than the whole map budget was charged");
  } catch (const store::OverBudget& e) {
    CHECK(rover::api::httpStatus(e.refusal()) == 413);
    CHECK(e.code() == "too_large");
    CHECK(e.field() == "body");
    CHECK(std::string(e.what()).find("more than a map's whole disk budget") != std::string::npos);
  }
  b.charge("pdms/a", store::DiskUse::Pdm, "m1", 600, "body");
  b.charge("missions/x", store::DiskUse::Result, "m1", 300);
  try {
    b.charge("pdms/b", store::DiskUse::Pdm, "m1", 200, "body");
    FAIL("the map's budget was passed");
  } catch (const store::OverBudget& e) {
    CHECK(rover::api::httpStatus(e.refusal()) == 507);
    CHECK(e.code() == "disk_budget_full");
    CHECK(std::string(e.what()).find("the map's disk budget is full") != std::string::npos);
  }
  CHECK(b.usedByMap("m1") == 900);
  CHECK_NOTHROW(b.requireRoom(store::DiskUse::Pdm, "m1"));  // 900 of 1000: room for a small one
  b.charge("pdms/b", store::DiskUse::Pdm, "m2", 200, "body");  // another map has its own budget
  // Maps and studies count globally only.
  b.charge("maps/m3", store::DiskUse::Map, "m3", 1500);
  try {
    b.charge("studies/s", store::DiskUse::Study, "", 500);
    FAIL("the global budget was passed");
  } catch (const store::OverBudget& e) {
    CHECK(rover::api::httpStatus(e.refusal()) == 507);
    CHECK(std::string(e.what()).find("the server's disk budget is full") != std::string::npos);
  }
  b.release("maps/m3");
  b.charge("studies/s", store::DiskUse::Study, "", 500);
  b.charge("studies/s", store::DiskUse::Study, "", 700);  // a growing study replaces its charge
  CHECK(b.used() == 600 + 300 + 200 + 700);
  b.release("pdms/a");
  CHECK(b.usedByMap("m1") == 300);
  b.charge("pdms/c", store::DiskUse::Pdm, "m1", 650, "body");
}

TEST_CASE("disk budget: PDMs past a map's budget answer 413 or 507 with the reason and field, a delete makes room") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  store::DiskBudgetLimits l;
  l.perMapBytes = 1500;  // a Gaussian PDM takes a few hundred bytes
  s.dir.budget().setLimits(l);
  std::vector<std::string> made;
  HttpResult r;
  for (int i = 0; i < 20; ++i) {
    r = s.postJson("/api/maps/" + map + "/pdms", {{"random", 3}, {"seed", i + 1}});
    if (r.status != 201) break;
    made.push_back(r.json()["id"]);
  }
  REQUIRE(!made.empty());
  CHECK(made.size() < 20);
  checkError(r, 507, "disk_budget_full", "body");
  CHECK(r.json()["error"]["message"].get<std::string>().find("the map's disk budget is full") != std::string::npos);
  CHECK(r.json()["error"]["message"].get<std::string>().find(tmp.path.string()) == std::string::npos);
  CHECK(s.dir.budget().usedByMap(map) <= 1500);
  CHECK(s.get("/api/maps/" + map + "/pdms").json().size() == made.size());  // nothing half-stored
  CHECK(fs::is_empty(tmp.path / "data" / "tmp"));
  // A raster PDM larger than the whole budget: 413, whatever is deleted.
  maps::writeGeoTiff(tmp.str("raster.tif"), *s.maps.pdmMass(made[0]));
  const std::string tif = readAll(tmp.path / "raster.tif");
  REQUIRE(tif.size() > 1500);
  CHECK(request(s.port(), "DELETE", "/api/maps/" + map + "/pdms/" + made[0]).status == 200);
  checkError(request(s.port(), "POST", "/api/maps/" + map + "/pdms?name=r&filename=p.tif", tif, "image/tiff"), 413,
             "too_large", "body");
  // The delete gave its bytes back: another Gaussian PDM fits again.
  CHECK(s.postJson("/api/maps/" + map + "/pdms", {{"random", 3}, {"seed", 99}}).status == 201);
  // A map whose budget is full: a mission on it is refused before it runs (its result could not
  // be kept).
  l.perMapBytes = s.dir.budget().usedByMap(map);
  s.dir.budget().setLimits(l);
  checkError(s.postJson("/api/missions", {{"map", map}, {"planner", "coverage"},
                                          {"rovers", {{{"x", 10.5}, {"y", 10.5}, {"heading", 0}}}},
                                          {"params", {{"coverage", 0.5}}}}),
             507, "disk_budget_full", "map");
}

TEST_CASE("PDMs: a random 3-component PDM on a 4 M-cell map is stored in under 1 MB and plans on the same mass") {
  TempDir tmp;
  ApiServerOptions o;
  o.defaultMap = false;
  ApiServer s(tmp.str("data"), o);
  const std::string map = flatMap(s, tmp, 2000, 2000);
  auto r = s.postJson("/api/maps/" + map + "/pdms", {{"random", 3}, {"seed", 4}});
  REQUIRE(r.status == 201);
  const std::string pdm = r.json()["id"];
  const fs::path stored = tmp.path / "data" / "pdms" / pdm;
  const std::uint64_t bytes = store::bytesUnder(stored.string());
  MESSAGE("a random-3 PDM on 2000 x 2000 cells: " << bytes << " bytes stored");
  CHECK(bytes < (1u << 20));
  CHECK(fs::exists(stored / "components.json"));
  CHECK(!fs::exists(stored / "pdm.tif"));
  // What missions and layers get, also from a catalog that never saw it made: the components
  // discretised on the map, as when it was made.
  auto data = s.maps.get(map);
  const auto comps = pdm::randomGaussians(data->dem.geometry(), 3, 4);
  const Raster<float> expected = pdm::discretise(comps, data->dem.geometry(), data->valid);
  api::MapCatalog reader(s.db, s.dir);
  for (const auto& mass : {s.maps.pdmMass(pdm), reader.pdmMass(pdm)}) {
    REQUIRE(mass->geometry.cellCount() == expected.geometry.cellCount());
    CHECK(mass->values == expected.values);
  }
  CHECK(s.get("/api/maps/" + map + "/layers/pdm.png?max=256&pdm=" + pdm).status == 200);

  // A PDM stored by an older version (pdm.tif, no components.json) still loads.
  r = s.postJson("/api/maps/" + map + "/pdms", {{"random", 2}, {"seed", 8}});
  REQUIRE(r.status == 201);
  const std::string old = r.json()["id"];
  const fs::path oldDir = tmp.path / "data" / "pdms" / old;
  Raster<float> oldMass = *s.maps.pdmMass(old);
  oldMass.at(0) = 0.5f;  // tell the file apart from a discretisation
  maps::writeGeoTiff((oldDir / "pdm.tif").string(), oldMass);
  fs::remove(oldDir / "components.json");
  api::MapCatalog later(s.db, s.dir);  // the server's catalog keeps the mass it made in memory
  CHECK(later.pdmMass(old)->at(0) == 0.5f);
}

}  // namespace rover::test
