// Maps announced before their COG (issue 24): an upload at or above the catalog's background size
// is committed with its elevation raw (the grid, its levels and a VRT) and its dem.tif written
// afterwards by the compressor. Its tiles, exports and missions work meanwhile; its record says
// storage.elevation "raw", then "cog"; deleting it mid-compression and restarting with it raw
// lose nothing and leave nothing behind. A COG that does not fit the disk budget is not written,
// a failed compression is tried again while the server runs (on a clock the tests move), and
// nothing read from the raw files is kept across the swap.
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <iostream>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "api_server.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "server/store/disk_budget.hpp"
#include "tests/wait_until.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::ApiServerOptions;
using rover::test::TempDir;
using nlohmann::json;

namespace {

// A 331 × 517 map of 1 m cells (odd sizes: every level's last block is cut) with a block of
// nodata (rows 40..119, columns 200..299).
std::string oddDem(const TempDir& tmp) {
  Raster<float> dem(GridGeometry{331, 517, 1.0, 1.0}, 0.0f);
  for (int r = 0; r < 331; ++r)
    for (int c = 0; c < 517; ++c)
      dem(r, c) = (r >= 40 && r < 120 && c >= 200 && c < 300)
                      ? std::numeric_limits<float>::quiet_NaN()
                      : static_cast<float>(20 * std::sin(0.031 * c) * std::cos(0.027 * r) + 0.01 * c * r / 50.0);
  maps::writeGeoTiff(tmp.str("odd.tif"), dem);
  std::ifstream in(tmp.str("odd.tif"), std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

ApiServerOptions rawFirst() {
  ApiServerOptions o;
  o.backgroundCells = 0;  // every upload is stored raw first
  o.defaultMap = false;
  return o;
}

std::string storage(ApiServer& s, const std::string& id) {
  return s.get("/api/maps/" + id).json()["storage"]["elevation"];
}

// Every tile address of the map: each zoom up to the native one and one above it.
std::vector<std::string> tileAddresses(ApiServer& s, const std::string& id) {
  const json tiles = s.get("/api/maps/" + id).json()["tiles"];
  std::vector<std::string> out;
  const int native = tiles["native_zoom"];
  for (int z = 0; z <= native + 1; ++z) {
    const int nx = tiles["tile_counts"][z][0], ny = tiles["tile_counts"][z][1];
    for (int x = 0; x < nx; ++x)
      for (int y = 0; y < ny; ++y)
        for (const char* layer : {"elevation/", "hillshade/", "slope/", "traversability/"})
          out.push_back(std::string(layer) + std::to_string(z) + "/" + std::to_string(x) + "/" + std::to_string(y) + ".png");
    out.push_back("elevation/" + std::to_string(z) + "/0/0.f32");
  }
  return out;
}

using Hold = rover::test::CompressionHold;

using Compressor = api::ElevationCompressor;

// The compressor's clock (ElevationCompressor::setClock), moved by the test: a retry comes when
// the test moves it, never after a wait. Declared before the server whose thread reads it.
struct TestClock {
  std::atomic<Compressor::Clock::rep> ticks{0};
  Compressor::Clock::time_point now() const { return Compressor::Clock::time_point(Compressor::Clock::duration(ticks.load())); }
  void on(ApiServer& s) {
    s.maps.compressor().setClock([this] { return now(); });
  }
  void advance(ApiServer& s, Compressor::Clock::duration by) {
    ticks += by.count();
    s.maps.compressor().wake();
  }
};

// Fails the first `failing` compression jobs (a transient error: a full disk, a lost mount).
struct Failing {
  std::atomic<int> runs{0};
  int failing = 0;
  void on(ApiServer& s) {
    s.maps.compressor().setBeforeJob([this](const std::string&, const std::function<bool()>&) {
      if (++runs <= failing) throw std::runtime_error("injected failure");
    });
  }
};

// Waits until the map's job has failed `n` times and is not about to run again.
Compressor::Status failedTimes(ApiServer& s, const std::string& id, int n) {
  Compressor::Status st;
  rover::test::waitUntil(
      [&] {
        st = s.maps.compressor().status(id);
        return st.failures == n && st.state != Compressor::State::Queued && st.state != Compressor::State::Running;
      },
      "the map's compression to fail " + std::to_string(n) + " times");
  return st;
}

// Waits until the map's job has ended (it is neither queued nor running) and returns its state.
Compressor::Status settled(ApiServer& s, const std::string& id) {
  Compressor::Status st;
  rover::test::waitUntil(
      [&] {
        st = s.maps.compressor().status(id);
        return st.state != Compressor::State::Queued && st.state != Compressor::State::Running;
      },
      "the map's compression job to end");
  return st;
}

// What std::cerr receives meanwhile (the compressor's log). Read it only once the compressor has
// said (through its state) that it wrote.
struct LogCapture {
  std::ostringstream text;
  std::streambuf* old = std::cerr.rdbuf(text.rdbuf());
  ~LogCapture() { std::cerr.rdbuf(old); }
};

// The files of a map's folder but its layer cache, relative to it.
std::set<std::string> filesOf(const std::string& mapDir) {
  std::set<std::string> out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(mapDir)) {
    const std::string rel = std::filesystem::relative(e.path(), mapDir).string();
    if (rel.rfind("layers", 0) != 0) out.insert(rel);
  }
  return out;
}

}  // namespace

TEST_CASE("raw maps: tiles of a map stored raw are byte for byte those of its COG; storage goes raw -> cog") {
  TempDir tmp;
  Hold hold;  // declared first: it outlives the server whose jobs it holds
  ApiServer s(tmp.str("data"), rawFirst());
  const std::string bytes = oddDem(tmp);
  // Map A compressed at once; map B, the same cells, held raw.
  const auto upA = s.post("/api/maps?name=a&filename=odd.tif", bytes, "image/tiff");
  REQUIRE(upA.status == 201);
  const std::string a = upA.json()["id"];
  CHECK(upA.json()["storage"]["elevation"] == "raw");
  s.maps.compressor().waitIdle(a, rover::test::kHangDeadline);
  CHECK(storage(s, a) == "cog");
  CHECK(std::filesystem::exists(s.dir.mapDir(a) + "/dem.tif"));
  CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(a) + "/dem~raw"));
  CHECK(maps::pyramidInfo(s.dir.mapDir(a) + "/dem.tif").layout == "COG");

  hold.on(s);
  // Uploaded as dem.tif: the client's file is not kept under the name the map gives its COG.
  const auto upB = s.post("/api/maps?name=b&filename=dem.tif", bytes, "image/tiff");
  REQUIRE(upB.status == 201);
  const std::string b = upB.json()["id"];
  rover::test::waitUntil([&] { return hold.held.load() == 1; }, rover::test::kHangDeadline, "B's job to start");
  CHECK(storage(s, b) == "raw");
  CHECK(s.get("/api/maps/" + b).json()["storage"]["codec"] == "none");
  CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(b) + "/dem.tif"));
  // The raw VRT reads as the COG does: the same header, sizes and overview sizes.
  const std::string vrt = s.dir.mapDir(b) + "/dem~raw/dem.vrt";
  const maps::PyramidInfo cog = maps::pyramidInfo(s.dir.mapDir(a) + "/dem.tif"), raw = maps::pyramidInfo(vrt);
  CHECK(raw.rows == cog.rows);
  CHECK(raw.cols == cog.cols);
  CHECK(raw.overviews == cog.overviews);
  const maps::DemHeader ha = maps::readDemHeader(s.dir.mapDir(a) + "/dem.tif"), hb = maps::readDemHeader(vrt);
  CHECK(hb.geometry.rows == ha.geometry.rows);
  CHECK(hb.geometry.cellWidth == ha.geometry.cellWidth);
  CHECK(hb.geo.geotransform == ha.geo.geotransform);
  for (const std::string& tile : tileAddresses(s, a)) {
    CAPTURE(tile);
    const auto fromCog = s.get("/api/maps/" + a + "/tiles/" + tile);
    const auto fromRaw = s.get("/api/maps/" + b + "/tiles/" + tile);
    REQUIRE(fromCog.status == 200);
    REQUIRE(fromRaw.status == 200);
    CHECK(fromCog.body == fromRaw.body);
  }
  // The rest of the map works raw: a PNG overview, the full-size elevation export (waits for
  // nothing on a map this small: made from the map in memory), a mission area's header.
  CHECK(s.get("/api/maps/" + b + "/layers/hillshade.png?max=256").status == 200);
  const auto exported = s.get("/api/maps/" + b + "/layers/elevation.tif");
  CHECK(exported.status == 200);
  CHECK(exported.body == s.get("/api/maps/" + a + "/layers/elevation.tif").body);

  hold.release = true;
  rover::test::waitUntil([&] { return storage(s, b) == "cog"; }, rover::test::kHangDeadline, "B's storage to be cog");
  CHECK(s.get("/api/maps/" + b).json()["storage"]["codec"] == "zstd");
  CHECK(std::filesystem::exists(s.dir.mapDir(b) + "/dem.tif"));
  CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(b) + "/dem~raw"));
  // The same COG as A's: the same levels compressed the same way.
  std::ifstream fa(s.dir.mapDir(a) + "/dem.tif", std::ios::binary), fb(s.dir.mapDir(b) + "/dem.tif", std::ios::binary);
  CHECK(std::string((std::istreambuf_iterator<char>(fa)), {}) == std::string((std::istreambuf_iterator<char>(fb)), {}));
  // Tiles not asked for while raw, now from the COG: still A's bytes.
  for (const char* tile : {"slope/3/1/1.png", "elevation/2/1/0.f32"})
    CHECK(s.get("/api/maps/" + b + "/tiles/" + tile).body == s.get("/api/maps/" + a + "/tiles/" + tile).body);
}

TEST_CASE("raw maps: deleting a map while its COG is written leaves no folder, no job and no crash") {
  TempDir tmp;
  Hold hold;  // declared first: it outlives the server whose jobs it holds
  std::future<int> deleting;
  std::atomic<bool> started{false};
  ApiServer s(tmp.str("data"), rawFirst());
  const std::string bytes = oddDem(tmp);
  SUBCASE("deleted before its job writes: the job finds no record and leaves") {
    hold.on(s);
    const auto up = s.post("/api/maps?name=gone&filename=odd.tif", bytes, "image/tiff");
    REQUIRE(up.status == 201);
    const std::string id = up.json()["id"];
    rover::test::waitUntil([&] { return hold.held.load() == 1; }, rover::test::kHangDeadline, "the job to start");
    // The DELETE waits for the job, which is released once the row is gone.
    std::thread releaser([&] {
      rover::test::pollUntil([&] { return !s.db.getMap(id); });
      hold.release = true;
    });
    const auto r = rover::test::request(s.port(), "DELETE", "/api/maps/" + id);
    releaser.join();
    CHECK(r.status == 200);
    CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
    CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(id)));
    CHECK(s.get("/api/maps/" + id).status == 404);
  }
  SUBCASE("deleted while the COG is written: cancelled or finished, the folder goes") {
    std::string id;
    s.maps.compressor().setBeforeJob([&](const std::string& job, const std::function<bool()>&) {
      // The DELETE starts as the write does; whichever wins, nothing of the map stays.
      deleting = std::async(std::launch::async,
                            [&, job] { return rover::test::request(s.port(), "DELETE", "/api/maps/" + job).status; });
      started = true;
    });
    const auto up = s.post("/api/maps?name=gone&filename=odd.tif", bytes, "image/tiff");
    REQUIRE(up.status == 201);
    id = up.json()["id"];
    rover::test::waitUntil([&] { return started.load(); }, rover::test::kHangDeadline, "the job to start");
    CHECK(deleting.get() == 200);
    CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
    CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(id)));
    CHECK(s.get("/api/maps/" + id).status == 404);
  }
  // Nothing of the map is charged to the disk any more (no tile was made: no layer file either).
  CHECK(s.dir.budget().used() == 0);
}

TEST_CASE("raw maps: a server stopped with a map still raw compresses it at its next start; it reads meanwhile") {
  TempDir tmp;
  const std::string bytes = oddDem(tmp);
  std::string id, tileBefore;
  {
    Hold hold;  // never released: the server stops with the map raw (declared first: it outlives it)
    ApiServer s(tmp.str("data"), rawFirst());
    hold.on(s);
    const auto up = s.post("/api/maps?name=raw&filename=odd.tif", bytes, "image/tiff");
    REQUIRE(up.status == 201);
    id = up.json()["id"];
    rover::test::waitUntil([&] { return hold.held.load() == 1; }, rover::test::kHangDeadline, "the job to start");
    tileBefore = s.get("/api/maps/" + id + "/tiles/hillshade/2/1/1.png").body;
    REQUIRE(!tileBefore.empty());
  }
  ApiServer s(tmp.str("data"), rawFirst());
  rover::test::waitUntil([&] { return storage(s, id) == "cog"; }, rover::test::kHangDeadline, "the map's storage to be cog");
  CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(id) + "/dem~raw"));
  CHECK(s.get("/api/maps/" + id + "/tiles/elevation/0/0/0.png").status == 200);
  CHECK(s.get("/api/maps/" + id + "/tiles/hillshade/2/1/1.png").body == tileBefore);
}

TEST_CASE("raw maps: a COG that does not fit the server's disk budget is not written; the map stays raw, working, charged for what it holds") {
  TempDir tmp;
  Hold hold;  // declared first: they outlive the server whose thread uses them
  TestClock clock;
  ApiServer s(tmp.str("data"), rawFirst());
  clock.on(s);
  hold.on(s);
  const auto up = s.post("/api/maps?name=big&filename=odd.tif", oddDem(tmp), "image/tiff");
  REQUIRE(up.status == 201);
  const std::string id = up.json()["id"];
  rover::test::waitUntil([&] { return hold.held.load() == 1; }, rover::test::kHangDeadline, "the job to start");
  const std::string mapDir = s.dir.mapDir(id);
  const std::string base = "/api/maps/" + id + "/tiles/";
  const auto tileBefore = s.get(base + "hillshade/2/1/1.png");
  REQUIRE(tileBefore.status == 200);
  const std::uint64_t raw = store::bytesUnder(mapDir + "/dem~raw");
  const std::uint64_t used = s.dir.budget().used();
  CHECK(used == store::bytesUnder(mapDir));  // its raw files, classes.tif and the tile
  const std::set<std::string> files = filesOf(mapDir);
  // Room left for half the raw files: tiles fit, the COG (which may take up to their size) not.
  s.dir.budget().setLimits({used + raw / 2, store::DiskBudgetLimits::kUnlimited});
  {
    LogCapture log;
    hold.release = true;  // the job is running (held): it has ended once it is no longer
    const auto st = settled(s, id);
    CHECK(st.state == Compressor::State::WaitingRetry);
    CHECK(st.failures == 1);
    CHECK(log.text.str().find("compressing map " + id) != std::string::npos);
    CHECK(log.text.str().find("disk budget is full") != std::string::npos);
  }
  // Nothing written, nothing left, nothing charged but what is there.
  CHECK(storage(s, id) == "raw");
  CHECK(filesOf(mapDir) == files);
  CHECK(s.dir.budget().used() == used);
  // It works raw: its tiles (a cached one, one made now), an overview, a planning window, and its
  // record names no server path.
  CHECK(s.get(base + "hillshade/2/1/1.png").body == tileBefore.body);
  CHECK(s.get(base + "slope/1/0/0.png").status == 200);
  CHECK(s.get("/api/maps/" + id + "/layers/elevation.png?max=256").status == 200);
  PlanningWindow w;
  w.row0 = 10;
  w.col0 = 20;
  w.grid = GridGeometry{50, 60, 1.0, 1.0};
  CHECK(std::isfinite(s.maps.demWindow(id, w)->z.at(0)));
  const auto rec = s.get("/api/maps/" + id);
  CHECK(rec.body.find(tmp.path.string()) == std::string::npos);
  CHECK(rec.body.find("dem~raw") == std::string::npos);
  // Room made: the retry, due a minute after the failure, writes the COG; the raw files go and
  // the map is charged for what it holds.
  s.dir.budget().setLimits({});
  clock.advance(s, Compressor::kFirstRetryDelay);
  rover::test::waitUntil([&] { return storage(s, id) == "cog"; }, rover::test::kHangDeadline, "the map's storage to be cog");
  CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
  CHECK(s.maps.compressor().status(id).state == Compressor::State::Idle);
  CHECK_FALSE(std::filesystem::exists(mapDir + "/dem~raw"));
  CHECK(s.dir.budget().used() == store::bytesUnder(mapDir));
  CHECK(s.get(base + "hillshade/2/1/1.png").body == tileBefore.body);
}

TEST_CASE("raw maps: a failed compression is tried again while the server runs, 1, 2, 4 ... 30 min after, 8 times at most") {
  TempDir tmp;
  TestClock clock;  // declared first: they outlive the server whose thread uses them
  Failing fail;
  ApiServer s(tmp.str("data"), rawFirst());
  clock.on(s);
  const std::string bytes = oddDem(tmp);
  auto upload = [&] {
    const auto up = s.post("/api/maps?name=flaky&filename=odd.tif", bytes, "image/tiff");
    REQUIRE(up.status == 201);
    return up.json()["id"].get<std::string>();
  };
  SUBCASE("a transient failure: compressed on a retry") {
    fail.failing = 2;
    fail.on(s);
    const std::string id = upload();
    auto st = failedTimes(s, id, 1);
    CHECK(st.state == Compressor::State::WaitingRetry);
    CHECK(st.retryAt == clock.now() + std::chrono::minutes(1));
    CHECK(storage(s, id) == "raw");
    CHECK(s.get("/api/maps/" + id + "/tiles/elevation/1/0/0.png").status == 200);
    clock.advance(s, std::chrono::minutes(1));
    st = failedTimes(s, id, 2);
    CHECK(st.state == Compressor::State::WaitingRetry);
    CHECK(st.retryAt == clock.now() + std::chrono::minutes(2));
    clock.advance(s, std::chrono::minutes(2));
    rover::test::waitUntil([&] { return storage(s, id) == "cog"; }, rover::test::kHangDeadline, "the map's storage to be cog");
    CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
    CHECK(s.maps.compressor().status(id).failures == 0);
    CHECK(fail.runs == 3);
    CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(id) + "/dem~raw"));
  }
  SUBCASE("a lasting failure: tried 8 times, then left raw and readable until the next start") {
    fail.failing = 1000;
    fail.on(s);
    const std::string id = upload();
    std::vector<long> waits;  // minutes between a failure and its retry
    for (int n = 1; n < Compressor::kAttempts; ++n) {
      const auto st = failedTimes(s, id, n);
      REQUIRE(st.state == Compressor::State::WaitingRetry);
      waits.push_back(std::chrono::duration_cast<std::chrono::minutes>(st.retryAt - clock.now()).count());
      clock.advance(s, st.retryAt - clock.now());
    }
    CHECK(waits == std::vector<long>{1, 2, 4, 8, 16, 30, 30});
    CHECK(failedTimes(s, id, Compressor::kAttempts).state == Compressor::State::GaveUp);
    clock.advance(s, std::chrono::hours(24));
    CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));  // nothing is pending
    CHECK(fail.runs == Compressor::kAttempts);
    CHECK(storage(s, id) == "raw");
    CHECK(s.get("/api/maps/" + id + "/tiles/slope/2/1/1.png").status == 200);
  }
  SUBCASE("deleted while it waits for a retry: the DELETE waits for no job, and no retry comes") {
    fail.failing = 1000;
    fail.on(s);
    const std::string id = upload();
    CHECK(failedTimes(s, id, 1).state == Compressor::State::WaitingRetry);
    CHECK(rover::test::request(s.port(), "DELETE", "/api/maps/" + id).status == 200);
    CHECK(s.maps.compressor().status(id).state == Compressor::State::Idle);
    CHECK_FALSE(std::filesystem::exists(s.dir.mapDir(id)));
    clock.advance(s, std::chrono::hours(1));
    CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
    CHECK(fail.runs == 1);
    CHECK(s.dir.budget().used() == 0);
  }
}

TEST_CASE("raw maps: a header read from the raw VRT as the COG replaces it is not kept; the COG's is read afresh") {
  TempDir tmp;
  Hold hold;  // declared first: it outlives the server whose jobs it holds
  ApiServer s(tmp.str("data"), rawFirst());
  hold.on(s);
  const auto up = s.post("/api/maps?name=swap&filename=odd.tif", oddDem(tmp), "image/tiff");
  REQUIRE(up.status == 201);
  const std::string id = up.json()["id"];
  rover::test::waitUntil([&] { return hold.held.load() == 1; }, rover::test::kHangDeadline, "the job to start");
  // The whole swap (COG written, record "cog", raw files removed) runs between the header's read
  // from the VRT and its keeping.
  bool swapped = false;
  s.maps.raceHooks.afterHeaderRead = [&](const std::string& map) {
    if (map != id || swapped) return;
    swapped = true;
    hold.release = true;
    CHECK(s.maps.compressor().waitIdle(id, rover::test::kHangDeadline));
  };
  const auto read = s.maps.storedHeader(id);  // on this thread: the hook runs here
  REQUIRE(swapped);
  CHECK(read->info.driver == "VRT");
  CHECK(storage(s, id) == "cog");
  const auto after = s.maps.storedHeader(id);
  CHECK(after->info.driver == "GTiff");
  CHECK(after->info.path == s.dir.mapDir(id) + "/dem.tif");
  CHECK(after->geometry.rows == read->geometry.rows);
  CHECK(after->geometry.cols == read->geometry.cols);
  CHECK(s.get("/api/maps/" + id + "/tiles/elevation/2/1/1.png").status == 200);
}
