// Hostile and careless uploads through POST /api/maps over loopback (issue 14): datasets that
// reach outside the upload or onto the network are refused with the file named and no server path;
// zips work; errors are words; PNG overviews come from a fixed ladder in a size-capped cache.
#include <doctest/doctest.h>

#include <arpa/inet.h>
#include <cpl_vsi.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

#include "tests/loopback_listener.hpp"
#include "api_server.hpp"
#include "maps/dem_io.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/api/layer_cache.hpp"

using namespace rover;
using rover::test::request;
using rover::test::TempDir;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// This file's server: one mission worker, four queued missions, uploads up to 64 MiB.
struct Server : test::ApiServer {
  static test::ApiServerOptions options() {
    test::ApiServerOptions o;
    o.queue = 4;
    o.http.maxUploadBytes = 64ull << 20;
    return o;
  }
  explicit Server(const std::string& data) : ApiServer(data, options()) {}
  test::HttpResult upload(const std::string& filename, const std::string& bytes, const std::string& query = "") {
    return request(port(), "POST", "/api/maps?filename=" + filename + query, bytes, "application/octet-stream");
  }
  std::size_t mapCount() { return get("/api/maps").json().size(); }
};

std::string readBytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

std::string vrtOver(const std::string& source, bool relative = false) {
  return "<VRTDataset rasterXSize=\"16\" rasterYSize=\"4\"><VRTRasterBand dataType=\"Byte\" band=\"1\" "
         "subClass=\"VRTRawRasterBand\"><SourceFilename relativetoVRT=\"" + std::string(relative ? "1" : "0") +
         "\">" + source + "</SourceFilename><ImageOffset>0</ImageOffset><PixelOffset>1</PixelOffset>"
         "<LineOffset>16</LineOffset></VRTRasterBand></VRTDataset>";
}

std::string pds3Label(const std::string& image, int lines = 8, int samples = 32) {
  return "PDS_VERSION_ID = PDS3\r\nRECORD_TYPE = FIXED_LENGTH\r\nRECORD_BYTES = " + std::to_string(samples) +
         "\r\nFILE_RECORDS = " + std::to_string(lines) + "\r\n^IMAGE = (\"" + image +
         "\", 1)\r\nOBJECT = IMAGE\r\n  LINES = " + std::to_string(lines) + "\r\n  LINE_SAMPLES = " +
         std::to_string(samples) + "\r\n  SAMPLE_TYPE = UNSIGNED_INTEGER\r\n  SAMPLE_BITS = 8\r\nEND_OBJECT = IMAGE\r\nEND\r\n";
}

// A GeoTIFF of the synthetic terrain, `size` cells a side of 0.25 m, as bytes.
std::string terrainTiff(const TempDir& s, int size) {
  maps::SyntheticTerrainParams p;
  p.size = size;
  const std::string path = s.str("terrain-" + std::to_string(size) + ".tif");
  maps::writeGeoTiff(path, maps::generateTerrain(p).z);
  return readBytes(path);
}

// Zip bytes made by GDAL itself (/vsizip/ write support), members in order.
std::string zipOf(const TempDir& s, const std::string& name, const std::vector<std::pair<std::string, std::string>>& members) {
  const std::string zip = s.str(name);
  for (const auto& [member, bytes] : members) {
    VSILFILE* f = VSIFOpenL(("/vsizip/" + zip + "/" + member).c_str(), "wb");
    REQUIRE(f);
    VSIFWriteL(bytes.data(), 1, bytes.size(), f);
    VSIFCloseL(f);
  }
  return readBytes(zip);
}

std::string multipart(const std::string& boundary, const std::vector<std::pair<std::string, std::string>>& files) {
  std::string body;
  for (const auto& [name, bytes] : files)
    body += "--" + boundary + "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"" + name + "\"\r\n\r\n" + bytes + "\r\n";
  return body + "--" + boundary + "--\r\n";
}

// A 400 naming `file`, no server path in it.
void checkRefused(const test::HttpResult& r, const std::string& file, const std::string& dataDir) {
  CHECK(r.status == 400);
  const json e = r.json()["error"];
  const std::string msg = e.value("message", "");
  CHECK(e.value("field", "") == "file");
  CHECK_MESSAGE(msg.find(file) != std::string::npos, msg);
  CHECK_MESSAGE(msg.find(dataDir) == std::string::npos, msg);
  CHECK_MESSAGE(msg.find("/tmp") == std::string::npos, msg);
  CHECK_MESSAGE(msg.find("/vsi") == std::string::npos, msg);
  CHECK_MESSAGE(msg.find("root:") == std::string::npos, msg);
}

using rover::test::Listener;

}  // namespace

TEST_CASE("hostile upload: VRTs reading /etc/passwd, /proc/self/cmdline or the database are refused") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  const std::size_t before = s.mapCount();
  checkRefused(s.upload("passwd.vrt", vrtOver("/etc/passwd")), "passwd.vrt", data);
  checkRefused(s.upload("cmdline.vrt", vrtOver("/proc/self/cmdline")), "cmdline.vrt", data);
  // The staging folder is DATA/tmp/ID/: the database is two levels up.
  checkRefused(s.upload("db.vrt", vrtOver("../../roverplan.db", true)), "db.vrt", data);
  // In a zip, or next to a harmless GeoTIFF, a VRT still refuses the whole upload.
  checkRefused(s.upload("pack.zip", zipOf(tmp, "pack.zip", {{"a.vrt", vrtOver("/etc/passwd")}})), "a.vrt", data);
  CHECK(s.mapCount() == before);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("hostile upload: a PDS3 label whose ^IMAGE points outside the upload is refused") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  auto r = s.upload("evil.lbl", pds3Label("../../../../../../../../../../etc/passwd"));
  checkRefused(r, "evil.lbl", data);
  CHECK(r.json()["error"]["message"].get<std::string>().find("'passwd'") != std::string::npos);
  // The database, by its place relative to the staging folder.
  checkRefused(s.upload("db.lbl", pds3Label("../../roverplan.db", 4, 16)), "db.lbl", data);
  // The label and its image as a multipart pair are fine.
  const std::string b = "PdsPair";
  r = request(s.port(), "POST", "/api/maps?name=pair",
              multipart(b, {{"P.LBL", pds3Label("P.IMG")}, {"P.IMG", std::string(256, '\x07')}}),
              "multipart/form-data; boundary=" + b);
  CHECK_MESSAGE(r.status == 201, r.body);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("hostile upload: a /vsicurl/ source is refused and no connection is made") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  Listener net;
  const std::string url = "/vsicurl/http://127.0.0.1:" + std::to_string(net.port) + "/secret.bin";
  checkRefused(s.upload("curl.vrt", vrtOver(url)), "curl.vrt", data);
  auto r = s.upload("curl.lbl", pds3Label(url));
  CHECK(r.status == 400);
  CHECK(r.json()["error"]["message"].get<std::string>().find("127.0.0.1") == std::string::npos);
  CHECK_FALSE(net.contacted(200));
}

TEST_CASE("hostile upload: zips holding a GeoTIFF or a PDS3 pair import, PDM rasters are confined too") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  const std::string tif = terrainTiff(tmp, 64);
  auto r = s.upload("dem.zip", zipOf(tmp, "dem.zip", {{"inner/dem.tif", tif}}), "&name=zipped");
  REQUIRE_MESSAGE(r.status == 201, r.body);
  CHECK(r.json()["cols"] == 64);
  CHECK(r.json()["source_files"] == json::array({"dem.zip"}));
  std::string image;
  for (int i = 0; i < 8 * 32; ++i) image += static_cast<char>(i % 40);
  r = s.upload("pds.zip", zipOf(tmp, "pds.zip", {{"X.LBL", pds3Label("X.IMG")}, {"X.IMG", image}}));
  REQUIRE_MESSAGE(r.status == 201, r.body);
  CHECK(r.json()["driver"] == "PDS");
  CHECK(r.json()["name"] == "X.LBL");

  // A PDM raster is read in a folder of its own, through the same door.
  const std::string map = r.json()["id"];
  r = request(s.port(), "POST", "/api/maps/" + map + "/pdms?filename=w.vrt", vrtOver("/etc/passwd"), "application/octet-stream");
  CHECK(r.status == 400);
  const std::string msg = r.json()["error"]["message"];
  CHECK_MESSAGE(msg.find("VRT") != std::string::npos, msg);
  CHECK(msg.find(data) == std::string::npos);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("hostile upload: careless files get errors in words") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  auto messageOf = [](const test::HttpResult& r) { return r.json()["error"].value("message", std::string()); };
  auto r = s.upload("LDEM_4.IMG", std::string(8192, '\x02'));
  CHECK(r.status == 400);
  CHECK_MESSAGE(messageOf(r).find("LDEM_4.IMG: the label is missing") == 0, messageOf(r));
  const std::string tif = terrainTiff(tmp, 64);
  r = s.upload("cut.tif", tif.substr(0, tif.size() / 2));
  CHECK(r.status == 400);
  CHECK_MESSAGE(messageOf(r).find("cut.tif: truncated or corrupt GeoTIFF") == 0, messageOf(r));
  r = s.upload("dem.tif", tif, "&cell=100");  // the map is 16 m across
  CHECK(r.status == 400);
  CHECK(r.json()["error"]["field"] == "cell");
  CHECK_MESSAGE(messageOf(r).find("larger than the map") != std::string::npos, messageOf(r));
  for (const auto& m : {messageOf(r)}) CHECK(m.find(data) == std::string::npos);
  // A file name longer than the file system takes (was 500 from a failed rename), and a map name
  // holding a NUL: 400 naming the field.
  r = s.upload(std::string(256, 'a') + ".tif", tif);
  CHECK(r.status == 400);
  CHECK(r.json()["error"]["field"] == "filename");
  r = s.upload("dem.tif", tif, "&name=a%00b");  // the HTTP edge refuses a NUL in the target
  CHECK(r.status == 400);
  r = request(s.port(), "POST", "/api/maps/" + s.defaultMap() + "/pdms", R"({"name":"a\u0000b","random":2})",
              "application/json");
  CHECK(r.status == 400);
  CHECK(r.json()["error"]["field"] == "name");
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("hostile upload: 40 distinct ?max= values make at most the ladder's files") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  auto r = s.upload("big.tif", terrainTiff(tmp, 1000));
  REQUIRE(r.status == 201);
  const std::string id = r.json()["id"];
  for (int i = 1; i <= 40; ++i) {
    auto png = request(s.port(), "GET", "/api/maps/" + id + "/layers/elevation.png?max=" + std::to_string(i * 37));
    REQUIRE(png.status == 200);
    CHECK(png.body.substr(1, 3) == "PNG");
  }
  std::vector<std::string> files;
  std::uintmax_t bytes = 0;
  for (const auto& f : fs::directory_iterator(fs::path(s.dir.mapDir(id)) / "layers")) {
    files.push_back(f.path().filename().string());
    bytes += f.file_size();
  }
  std::sort(files.begin(), files.end());
  // 37..1480: rungs 256 and 512, and the full 1000² rendering for anything above 512.
  CHECK(files == std::vector<std::string>{"elevation-256.png", "elevation-512.png", "elevation.png"});
  MESSAGE("40 distinct max values on a 1000² map: " << files.size() << " files, " << bytes << " bytes");
  // Overviews of the old naming (any ?max= had its own file) are deleted at the next start.
  const fs::path layers = fs::path(s.dir.mapDir(id)) / "layers";
  std::ofstream((layers / "elevation-1480.png").string()) << "stale";
  std::ofstream((layers / "pdm-0123456789abcdef-777.png").string()) << "stale";
  { api::MapCatalog restarted(s.db, s.dir); }
  CHECK_FALSE(fs::exists(layers / "elevation-1480.png"));
  CHECK_FALSE(fs::exists(layers / "pdm-0123456789abcdef-777.png"));
  CHECK(fs::exists(layers / "elevation-512.png"));

  // Two GETs of the same new layer at once both succeed; one file results.
  std::vector<std::thread> gets;
  std::atomic<int> ok{0};
  for (int i = 0; i < 2; ++i)
    gets.emplace_back([&] { ok += request(s.port(), "GET", "/api/maps/" + id + "/layers/slope.png?max=300").status == 200; });
  for (auto& t : gets) t.join();
  CHECK(ok == 2);
  CHECK(fs::exists(fs::path(s.dir.mapDir(id)) / "layers" / "slope-512.png"));
}

TEST_CASE("layer cache: least recently used files go past the cap, each file is made once") {
  TempDir tmp;
  const fs::path maps = tmp.path / "maps";
  fs::create_directories(maps / "m1" / "layers");
  api::LayerCache cache(maps.string(), 2500);
  std::atomic<int> made{0}, asking{0};
  // The first making holds on until all eight threads are asking (an event, not a pause), so the
  // others ask while the file is being made.
  auto make = [&](const std::string& path) {
    ++made;
    test::pollUntil([&] { return asking.load() == 8; });
    std::ofstream(path, std::ios::binary) << std::string(1000, 'x');
  };
  auto file = [&](const std::string& n) { return (maps / "m1" / "layers" / n).string(); };
  // Eight threads ask for the same file at once: it is made once.
  std::vector<std::thread> ts;
  for (int i = 0; i < 8; ++i)
    ts.emplace_back([&] {
      ++asking;
      cache.get(file("a.png"), make);
    });
  for (auto& t : ts) t.join();
  CHECK(made == 1);
  cache.get(file("b.png"), make);
  cache.get(file("a.png"), make);  // a is now more recent than b
  cache.get(file("c.png"), make);  // 3000 bytes > 2500: b goes
  CHECK(made == 3);
  CHECK(fs::exists(file("a.png")));
  CHECK_FALSE(fs::exists(file("b.png")));
  CHECK(fs::exists(file("c.png")));
  CHECK(cache.bytes() == 2000);
  // tryUse counts as a use and never makes a file: a becomes more recent than c, so e evicts c.
  CHECK(cache.tryUse(file("a.png")));
  CHECK_FALSE(cache.tryUse(file("z.png")));
  cache.get(file("e.png"), make);
  CHECK(made == 4);
  CHECK(fs::exists(file("a.png")));
  CHECK_FALSE(fs::exists(file("c.png")));
  CHECK_FALSE(cache.tryUse(file("c.png")));
  CHECK(cache.bytes() == 2000);
  // A new cache over the same folder counts what is there, less what `stale` names.
  std::ofstream((maps / "m1" / "layers" / "elevation-3013.png").string()) << std::string(10, 'x');
  api::LayerCache again(maps.string(), 2500, [](const std::string& f) { return f == "elevation-3013.png"; });
  CHECK(again.bytes() == 2000);
  CHECK_FALSE(fs::exists(maps / "m1" / "layers" / "elevation-3013.png"));
  // A failure in making leaves nothing behind and the next request tries again.
  CHECK_THROWS(cache.get(file("d.png"), [](const std::string&) { throw std::runtime_error("render failed"); }));
  cache.get(file("d.png"), make);
  CHECK(fs::exists(file("d.png")));
}

TEST_CASE("hostile upload: a coverage cell the map cannot hold is refused without the stored file's path") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  const std::string map = request(s.port(), "GET", "/api/maps").json()[0]["id"];
  const json mission = {{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 10}, {"y", 10}, {"heading", 0}}}},
                        {"params", {{"coverage_cell", 0.001}}}};
  auto r = request(s.port(), "POST", "/api/missions", mission.dump(), "application/json");
  CHECK(r.status == 400);
  const std::string msg = r.json()["error"].value("message", "");
  CHECK(r.json()["error"]["field"] == "params.coverage_cell");
  CHECK_MESSAGE(msg.find("fits") != std::string::npos, msg);  // says which cell size would run
  CHECK_MESSAGE(msg.find(data) == std::string::npos, msg);
  CHECK_MESSAGE(msg.find("dem.tif") == std::string::npos, msg);
}

TEST_CASE("hostile upload: an ENVI header promising more cells than its .bin holds is refused") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  const std::size_t before = s.mapCount();
  auto header = [](int rows, int cols, const std::string& offset) {
    return "ENVI\nsamples = " + std::to_string(cols) + "\nlines = " + std::to_string(rows) +
           "\nbands = 1\nheader offset = " + offset +
           "\nfile type = ENVI Standard\ndata type = 2\ninterleave = bsq\nbyte order = 0\n"
           "map info = {UTM, 1, 1, 500000, 4000000, 1, 1, 33, North, WGS-84}\n";
  };
  const std::string b = "EnviPair", type = "multipart/form-data; boundary=" + b;
  // The tester's upload: 17 100 bytes that a header calls 7000 × 7000 int16 cells (98 MB).
  auto r = request(s.port(), "POST", "/api/maps?name=fake",
                   multipart(b, {{"x.bin", std::string(17100, '\x10')}, {"x.hdr", header(7000, 7000, "0")}}), type);
  checkRefused(r, "x.bin", data);
  CHECK_MESSAGE(r.json()["error"]["message"] ==
                    "x.bin: x.hdr describes 7000 × 7000 cells but x.bin holds only 17 KB: truncated or mismatched",
                r.body);
  // A header offset past the end of the data: every cell would read as 0.
  r = request(s.port(), "POST", "/api/maps?name=far",
              multipart(b, {{"x.bin", std::string(95 * 90 * 2, '\x10')}, {"x.hdr", header(95, 90, "99999999999")}}),
              type);
  checkRefused(r, "x.hdr describes 95 × 90 cells after a header offset of", data);
  CHECK(s.mapCount() == before);
  // The same pair with all its data imports.
  r = request(s.port(), "POST", "/api/maps?name=real",
              multipart(b, {{"x.bin", std::string(95 * 90 * 2, '\x10')}, {"x.hdr", header(95, 90, "0")}}), type);
  CHECK_MESSAGE(r.status == 201, r.body);
  CHECK(fs::is_empty(s.dir.tmpDir()));
}

TEST_CASE("hostile upload: an option given twice is refused naming it, whichever way it is given") {
  TempDir tmp;
  const std::string data = tmp.str("data");
  Server s(data);
  const std::size_t before = s.mapCount();
  const std::string tif = terrainTiff(tmp, 64);
  auto checkTwice = [&](const test::HttpResult& r, const std::string& field) {
    CHECK(r.status == 400);
    CHECK(r.json()["error"]["code"] == "invalid_parameter");
    CHECK(r.json()["error"]["field"] == field);
  };
  // Twice in the query (the last one used to win), in the query and a field (the query won), and
  // as two fields (the first won).
  checkTwice(s.upload("dem.tif", tif, "&cell=0.5&cell=4"), "cell");
  const std::string b = "TwiceB", type = "multipart/form-data; boundary=" + b;
  auto field = [&](const std::string& name, const std::string& value) {
    return "--" + b + "\r\nContent-Disposition: form-data; name=\"" + name + "\"\r\n\r\n" + value + "\r\n";
  };
  const std::string filePart = "--" + b + "\r\nContent-Disposition: form-data; name=\"file\"; filename=\"dem.tif\"\r\n\r\n" +
                               tif + "\r\n--" + b + "--\r\n";
  checkTwice(request(s.port(), "POST", "/api/maps?vertical_scale=2", field("vertical_scale", "3") + filePart, type),
             "vertical_scale");
  checkTwice(request(s.port(), "POST", "/api/maps", field("name", "a") + field("name", "b") + filePart, type), "name");
  // Once is fine, either way.
  CHECK(request(s.port(), "POST", "/api/maps", field("name", "once") + field("cell", "2") + filePart, type).status == 201);
  CHECK(s.mapCount() == before + 1);
  CHECK(fs::is_empty(s.dir.tmpDir()));
  // Any route: a repeated query parameter is named, not guessed.
  checkTwice(s.get("/api/maps?limit=1&limit=2"), "limit");
}
