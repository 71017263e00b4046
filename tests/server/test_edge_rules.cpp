// Rules at the API's edge (issue 13's hardening list): names hold no hidden controls, a default
// map name made from a file is clean and short, echoed user text is cut on a character boundary,
// JSON routes take only application/json, and the DEM import options (crop in CRS units or
// pixels, vertical scale, body) are read by the one parser the CLI uses, on real DEMs.
#include <doctest/doctest.h>

#include <cpl_vsi.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "api_server.hpp"
#include "maps/dem_io.hpp"
#include "server/json/json_edge.hpp"

using rover::GridGeometry;
using rover::Raster;
namespace maps = rover::maps;
namespace test = rover::test;
using rover::test::ApiServer;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// Percent-encodes every byte (a query value of any bytes).
std::string urlEncoded(const std::string& s) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c)) {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

std::string smallDem(const TempDir& tmp) {
  Raster<float> z(GridGeometry{30, 40, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 30; ++r)
    for (int c = 0; c < 40; ++c) z(r, c) = 0.05f * c + 0.02f * r;
  z.geo.valid = true;
  z.geo.geotransform = {500000, 1, 0, 4100030, 0, -1};
  const std::string path = tmp.str("small.tif");
  maps::writeGeoTiff(path, z);
  return path;
}

// Each kind of hidden character, as UTF-8.
const std::vector<std::string> kHidden{"\x01", "\x7f", "\xc2\x85" /* U+0085 NEL */, "\xe2\x80\xae" /* U+202E RLO */,
                                       "\xe2\x81\xa7" /* U+2067 RLI */, "\xe2\x80\x8b" /* U+200B ZWSP */,
                                       "\xe2\x80\x8f" /* U+200F RLM */, "\xef\xbb\xbf" /* U+FEFF */};

json coverageMission(const std::string& map) {
  return {{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 20}, {"y", 20}, {"heading", 0}}}},
          {"params", {{"coverage", 0.2}}}, {"pace", 0}};
}

bool validUtf8(const std::string& s) {
  try {
    (void)json(s).dump();
    return true;
  } catch (const json::exception&) {
    return false;
  }
}

}  // namespace

TEST_CASE("edge: names and labels refuse C0, C1, bidi override/isolate, zero-width and BOM characters") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  auto launched = s.postJson("/api/missions", coverageMission(map));
  REQUIRE(launched.status == 202);
  const std::string id = launched.json()["id"];
  const std::string dem = readBytes(smallDem(tmp));
  for (const auto& h : kHidden) {
    CAPTURE(json(h).dump(-1, ' ', true));
    const std::string name = "site" + h + "A";
    json m = coverageMission(map);
    m["name"] = name;
    checkError(s.postJson("/api/missions", m), 400, "invalid_field", "name");
    checkError(request(s.port(), "PATCH", "/api/missions/" + id, json{{"label", name}}.dump(), "application/json"), 400,
               "invalid_field", "label");
    checkError(s.postJson("/api/maps/" + map + "/pdms", {{"name", name}, {"random", 2}}), 400, "invalid_field", "name");
    checkError(request(s.port(), "POST", "/api/maps?filename=small.tif&name=" + urlEncoded(name), dem, "image/tiff"), 400,
               "invalid_field", "name");
  }
  // Plain non-ASCII text is a name like any other.
  // (A label is versioned, issue 26: the write names the version it read.)
  const auto version = request(s.port(), "GET", "/api/missions/" + id).json()["version"].get<long long>();
  auto ok = request(s.port(), "PATCH", "/api/missions/" + id,
                    json{{"label", "cratère Kepler — 北"}, {"version", version}}.dump(), "application/json");
  CHECK(ok.status == 200);
  CHECK(ok.json()["label"] == "cratère Kepler — 北");
  s.waitFinished(id);
}

TEST_CASE("edge: a default map name from a zip member is stripped of its folders and controls, and capped") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string tif = readBytes(smallDem(tmp));
  // A zip whose one member has folders, an escape sequence, a bidi override and 300 more letters.
  const std::string member = "deep/er/\x1b[31m\xe2\x80\xae" "evil" + std::string(300, 'a') + ".tif";
  const std::string zip = tmp.str("upload.zip");
  VSILFILE* f = VSIFOpenL(("/vsizip/" + zip + "/" + member).c_str(), "wb");
  REQUIRE(f != nullptr);
  VSIFWriteL(tif.data(), 1, tif.size(), f);
  VSIFCloseL(f);
  auto r = request(s.port(), "POST", "/api/maps?filename=upload.zip", readBytes(zip), "application/zip");
  REQUIRE_MESSAGE(r.status == 201, r.body);
  const std::string name = r.json()["name"];
  CHECK(name.find('/') == std::string::npos);
  CHECK(name.find("deep") == std::string::npos);
  CHECK(name.find('\x1b') == std::string::npos);
  CHECK(name.find("\xe2\x80\xae") == std::string::npos);
  CHECK(name.rfind("[31mevilaaa", 0) == 0);
  CHECK_NOTHROW(rover::json::checkName(name, "name"));  // the name passes the names' own rule
  CHECK(json(name).get<std::string>().size() <= rover::json::kMaxNameChars);
  CHECK(rover::json::cleanName("\xef\xbb\xbf \xc2\x85") == "");
}

TEST_CASE("edge: echoed names and ids are cut on a character boundary, never mid-UTF-8") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string map = s.defaultMap();
  // A key whose 64th byte falls inside a two-byte character.
  const std::string key = std::string(63, 'k') + "\xc3\xa9" + std::string(40, 'z');
  json m = coverageMission(map);
  m["params"][key] = 1;
  auto r = s.postJson("/api/missions", m);
  CHECK(r.status == 400);
  REQUIRE(r.json().is_object());  // the answer is valid JSON (a cut character made it unprintable)
  const std::string field = r.json()["error"]["field"];
  CHECK(validUtf8(field));
  CHECK(field == "params." + std::string(63, 'k') + "...");
  json top = coverageMission(map);
  top[key] = 1;
  r = s.postJson("/api/missions", top);
  CHECK(r.status == 400);
  CHECK(r.json()["error"]["code"] == "unknown_field");
  CHECK(r.json()["error"]["field"].get<std::string>().size() <= 67);
  auto launched = s.postJson("/api/missions", coverageMission(map));
  const std::string id = launched.json()["id"];
  r = request(s.port(), "PATCH", "/api/missions/" + id, json{{key, "x"}}.dump(), "application/json");
  CHECK(r.status == 400);
  CHECK(validUtf8(r.json()["error"]["message"]));
  // A long id in the path is echoed cut.
  const std::string longId(3000, 'q');
  for (const std::string& target : {"/api/missions/" + longId, "/api/maps/" + longId, "/api/maps/" + map + "/pdms/" + longId,
                                    "/api/missions/" + longId + "/result.json"}) {
    r = s.get(target);
    CHECK(r.status == 404);
    CHECK(r.json()["error"]["message"].get<std::string>().size() < 200);
  }
  s.waitFinished(id);
}

TEST_CASE("edge: JSON routes take only application/json (a cross-site text/plain post is refused)") {
  TempDir tmp;
  ApiServer s(tmp.str("data"));
  const std::string body = coverageMission(s.defaultMap()).dump();
  for (const char* type : {"text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x", ""})
    checkError(request(s.port(), "POST", "/api/missions", body, type), 415, "unsupported_media_type", "content-type");
  auto ok = request(s.port(), "POST", "/api/missions", body, "Application/JSON; charset=utf-8");
  REQUIRE(ok.status == 202);
  const std::string id = ok.json()["id"];
  checkError(request(s.port(), "PATCH", "/api/missions/" + id, R"({"label":"x"})", "text/plain"), 415,
             "unsupported_media_type", "content-type");
  CHECK(s.get("/api/missions/" + id).json()["label"] == "");
  s.waitFinished(id);
}

TEST_CASE("edge: a real DEM uploaded with a pixel or CRS crop, a vertical scale and a body") {
  const char* env = std::getenv("ROVER_SHARED_DEMS");
  const fs::path dems = env ? fs::path(env) : fs::path(ROVER_SOURCE_DIR) / ".." / "shared" / "dems";
  const fs::path kepler = dems / "moon_lola_kepler_crater" / "kepler.tif";
  if (!fs::exists(kepler)) {
    MESSAGE("SKIPPED: " << kepler.string() << " absent (set ROVER_SHARED_DEMS)");
    return;
  }
  TempDir tmp;
  test::ApiServerOptions o;
  o.http.maxUploadBytes = 64ull << 20;
  ApiServer s(tmp.str("data"), o);
  const std::string bytes = readBytes(kepler.string());
  // The expected numbers, read without any crop: the window's rows and columns by hand.
  const maps::LoadedDem whole = maps::loadDem(kepler.string());
  const int col0 = 100, row0 = 150, w = 200, h = 120;
  double lo = INFINITY, hi = -INFINITY;
  for (int r = row0; r < row0 + h; ++r)
    for (int c = col0; c < col0 + w; ++c) {
      const float v = whole.dem.z(r, c);
      if (std::isnan(v)) continue;
      lo = std::min(lo, 0.5 * v);
      hi = std::max(hi, 0.5 * v);
    }

  auto r = request(s.port(), "POST",
                   "/api/maps?filename=kepler.tif&name=kepler-px&crop_px=100,150,200,120&vertical_scale=0.5&body=moon",
                   bytes, "image/tiff");
  REQUIRE_MESSAGE(r.status == 201, r.body);
  json m = r.json();
  CHECK(m["cols"] == w);
  CHECK(m["rows"] == h);
  CHECK(m["elevation"]["min"].get<double>() == doctest::Approx(lo).epsilon(1e-6));
  CHECK(m["elevation"]["max"].get<double>() == doctest::Approx(hi).epsilon(1e-6));
  CHECK(m["vertical_scale"] == 0.5);
  CHECK(m["body"] == "moon");
  CHECK(m["body_source"] == "declared");
  CHECK(m["width_m"].get<double>() == doctest::Approx(w * whole.dem.geometry().cellWidth).epsilon(1e-6));

  // The same window in the file's CRS units: the same grid.
  const auto& gt = whole.dem.z.geo.geotransform;
  const double x0 = gt[0] + col0 * gt[1], yTop = gt[3] + row0 * gt[5];
  const std::string crop = std::to_string(x0) + "," + std::to_string(yTop + h * gt[5]) + "," +
                           std::to_string(w * gt[1]) + "," + std::to_string(-h * gt[5]);
  // As multipart fields this time, as the page sends them.
  const std::string b = "XyZbOuNdArY";
  std::string body;
  for (const auto& [k, v] : std::vector<std::pair<std::string, std::string>>{{"crop", crop}, {"vertical_scale", "0.5"}, {"body", "mars"}})
    body += "--" + b + "\r\nContent-Disposition: form-data; name=\"" + k + "\"\r\n\r\n" + v + "\r\n";
  body += "--" + b + "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"kepler.tif\"\r\nContent-Type: image/tiff\r\n\r\n" +
          bytes + "\r\n--" + b + "--\r\n";
  r = request(s.port(), "POST", "/api/maps", body, "multipart/form-data; boundary=" + b);
  REQUIRE_MESSAGE(r.status == 201, r.body);
  json crs = r.json();
  CHECK(crs["cols"] == w);
  CHECK(crs["rows"] == h);
  CHECK(crs["elevation"]["min"].get<double>() == doctest::Approx(lo).epsilon(1e-6));
  CHECK(crs["elevation"]["max"].get<double>() == doctest::Approx(hi).epsilon(1e-6));
  // The declared body sets the planners' default gravity on that map.
  auto planners = s.get("/api/planners?map=" + crs["id"].get<std::string>()).json();
  CHECK(planners[0]["map_defaults"]["body"] == "mars");
  CHECK(planners[0]["map_defaults"]["gravity"].get<double>() == doctest::Approx(3.71));

  // Bad options name their field (the CLI's parser's rules).
  const std::string q = "/api/maps?filename=kepler.tif&";
  checkError(request(s.port(), "POST", q + "crop_px=0,0,900,10", bytes, "image/tiff"), 400, "crop_px");
  checkError(request(s.port(), "POST", q + "crop_px=1,2,3", bytes, "image/tiff"), 400, "crop_px");
  checkError(request(s.port(), "POST", q + "crop=1,2,3,4&crop_px=1,2,3,4", bytes, "image/tiff"), 400, "crop_px");
  checkError(request(s.port(), "POST", q + "vertical_scale=0", bytes, "image/tiff"), 400, "vertical_scale");
  checkError(request(s.port(), "POST", q + "body=pluto", bytes, "image/tiff"), 400, "body");
  checkError(request(s.port(), "POST", q + "crop=nan,0,1,1", bytes, "image/tiff"), 400, "crop");
}
