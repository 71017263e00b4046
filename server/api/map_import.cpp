#include "server/api/map_catalog.hpp"

// MapCatalog's imports: the client's DEM files staged and read in the import jail (server/jail/),
// stored as the map's GeoTIFF with its metadata row; and the generated default map.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <thread>

#include "core/common/error.hpp"
#include "maps/dem_digest.hpp"
#include "maps/dem_io.hpp"
#include "maps/dem_pyramid.hpp"
#include "maps/georef.hpp"
#include "maps/grid_file.hpp"
#include "maps/render.hpp"
#include "maps/tile_grid.hpp"
#include "maps/synthetic_terrain.hpp"
#include "server/api/import_stages.hpp"
#include "server/api/map_files.hpp"
#include "server/http/http_types.hpp"
#include "server/json/json_edge.hpp"
#include "server/missions/bulk_heap.hpp"

namespace rover::api {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

constexpr std::size_t kMaxFileNameBytes = 200;

std::string safeName(const std::string& name, const std::string& fallback) {
  std::string base = fs::path(name).filename().string(), out;
  for (char c : base) out += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '_';
  if (out.empty() || out == "." || out == "..") out = fallback;
  return out;
}

nlohmann::json metaFor(const maps::LoadedDem& d, const terrain::ClassShares& shares,
                       const std::vector<std::string>& sources, const std::string& digest) {
  const GridGeometry& g = d.dem.geometry();
  using TC = terrain::TerrainClass;
  return {{"rows", g.rows},
          {"cols", g.cols},
          {"cell_size_m", g.cellWidth},
          {"cell_height_m", g.cellHeight},
          {"width_m", g.widthMetres()},
          {"height_m", g.heightMetres()},
          {"crs", d.info.crsName},
          {"geographic", d.info.geographic},
          {"driver", d.info.driver},
          {"source_files", sources},
          {"dem_sha256", digest},
          {"resampling", d.info.resampling},
          {"elevation", {{"min", d.info.minHeight}, {"max", d.info.maxHeight}}},
          {"classes",
           {{"traversable_pct", shares.percent(TC::Traversable)},
            {"high_risk_pct", shares.percent(TC::HighRisk)},
            {"impassable_pct", shares.percent(TC::Impassable)},
            {"nodata_pct", shares.percent(TC::NoData)}}}};
}

}  // namespace

jail::JailLimits MapCatalog::defaultImportLimits(std::int64_t maxCells) {
  jail::JailLimits l;
  const auto cells = static_cast<std::uint64_t>(std::max<std::int64_t>(maxCells, 0));
  // Address space: 1 GiB for the program, GDAL and its block cache, 24 bytes a cell for the grid
  // and the warper's buffers, and 96 MiB a core for the warper's threads (stack + malloc arena).
  l.memoryBytes = (1ull << 30) + 24 * cells + (96ull << 20) * std::max(1u, std::thread::hardware_concurrency());
  l.fileBytes = 4 * cells + (64ull << 20);  // the float32 grid it writes back, and its JSON
  l.cpuSeconds = 600;
  l.deadlineSeconds = 300;
  return l;
}

void MapCatalog::setImportJail(jail::JailConfig config) {
  std::lock_guard lock(mutex_);
  jail_ = std::move(config);
}

jail::JailConfig MapCatalog::importJail() const {
  std::lock_guard lock(mutex_);
  return jail_;
}

maps::LoadedDem MapCatalog::importJailed(const std::string& inDir, jail::ImportRequest req, std::string& rasterName,
                                         ImportStages* stages, const GridRows* rows) {
  const jail::JailConfig config = importJail();
  const bool pdm = req.kind == "pdm";
  const std::string invalid = pdm ? "invalid_pdm" : "invalid_dem";
  const std::string what = pdm ? "the PDM raster" : "the file";
  req.allowHdf5 = jail::isolation() == jail::Isolation::Bubblewrap;
  const std::string out = dir_.stagingDir();
  struct RemoveOut {
    std::string path;
    ~RemoveOut() { store::DataDir::removeTree(path); }
  } removeOut{out};
  jail::writeImportRequest(out, req);
  const jail::JailRun run = jail::runJailed(config, inDir, out);
  if (stages) stages->done("worker");
  auto logWorker = [&](const std::string& why) {
    // What the worker said on stderr stays in the server's log; the client gets our words.
    std::ifstream log(fs::path(out) / "worker.log");
    std::string tail((std::istreambuf_iterator<char>(log)), {});
    if (tail.size() > 2000) tail = tail.substr(tail.size() - 2000);
    std::cerr << "import worker: " << why << (tail.empty() ? "" : ": " + tail) << std::endl;
  };
  switch (run.end) {
    case jail::JailRun::End::NotStarted:
      throw std::runtime_error("the import worker did not start: " + run.detail);
    case jail::JailRun::End::DeadlinePassed:
      throw ApiError(400, "import_timeout",
                     "the importer did not finish reading " + what + " within " +
                         std::to_string(static_cast<long long>(config.limits.deadlineSeconds)) + " s",
                     "file");
    case jail::JailRun::End::Signalled:
      if (run.signal == SIGXCPU)
        throw ApiError(413, "too_large", what + " needs more than the " + std::to_string(config.limits.cpuSeconds) +
                                             " s of CPU time an import may use", "file");
      if (run.signal == SIGXFSZ)
        throw ApiError(413, "too_large", what + " makes a grid larger than an import may write", "file");
      logWorker("ended by signal " + std::to_string(run.signal));
      throw ApiError(400, "import_crashed",
                     "the importer crashed (signal " + std::to_string(run.signal) + ") reading " + what, "file");
    case jail::JailRun::End::Exited:
      break;
  }
  if (run.exitStatus == 1) {
    if (auto e = jail::readWorkerError(out)) throw ApiError(e->status, e->code, e->message, e->field);
  }
  if (run.exitStatus != 0) {
    logWorker("exit status " + std::to_string(run.exitStatus));
    throw ApiError(400, "import_failed", "the importer failed reading " + what + " (exit status " +
                                             std::to_string(run.exitStatus) + ")", "file");
  }
  try {
    if (!rows) {
      jail::WorkerResult r = jail::readWorkerResult(out, req.load.maxCells);
      rasterName = r.rasterName;
      return std::move(r.dem);
    }
    jail::WorkerResult r = jail::readWorkerHeader(out, req.load.maxCells);
    const int cols = r.dem.dem.geometry().cols;
    jail::readWorkerGrid(out, r.dem.dem.geometry(), r.dem.info, std::max(1, (4 << 20) / (4 * cols)),
                         [&](int r0, int n, const float* v) { (*rows)(r.dem.dem, r0, n, v); });
    rasterName = r.rasterName;
    return std::move(r.dem);
  } catch (const maps::DiskFull&) {
    throw;  // `rows` writing into the data dir: the disk's fault (storingGeoTiff answers it)
  } catch (const maps::GridFileError&) {
    throw;  // the server's own file: a 500 (server/api/error_table), logged with its path
  } catch (const Error& e) {
    throw ApiError(400, invalid, e.what(), e.field());
  } catch (const std::runtime_error& e) {
    logWorker(e.what());
    throw ApiError(400, invalid, "the importer's output for " + what + " does not read", "file");
  }
}

store::MapRecord MapCatalog::importDem(const std::vector<UploadedFile>& files, const std::string& name,
                                       const maps::DemImport& options) {
  const double cellSize = options.load.cellSize;
  if (files.empty()) throw ApiError(400, "invalid_input", "no DEM file in the request", "file");
  if (!(cellSize >= 0) || !std::isfinite(cellSize) || cellSize > 1e5)
    throw ApiError(400, "invalid_parameter", "cell must be a positive number of metres", "cell");
  rover::json::checkName(name, "name");  // the same rule as every other name (server/json/json_edge.hpp)
  const std::string staging = dir_.stagingDir();
  try {
    std::vector<std::string> sources;
    for (std::size_t i = 0; i < files.size(); ++i) {
      std::string fallback = "upload";
      fallback += std::to_string(i);
      // A file name must fit the file system once staged (NAME_MAX 255) with room for a prefix;
      // cutting it instead would break the names a PDS3 label gives its image.
      if (files[i].filename.size() > kMaxFileNameBytes)
        throw ApiError(400, "invalid_field",
                       "a file name of " + std::to_string(files[i].filename.size()) + " bytes is longer than the " +
                           std::to_string(kMaxFileNameBytes) + " allowed",
                       "filename");
      std::string fname = safeName(files[i].filename, fallback);
      if (std::find(sources.begin(), sources.end(), fname) != sources.end()) {
        std::string unique = std::to_string(i);
        unique += '_';
        fname = unique + fname;
      }
      fs::rename(files[i].path, fs::path(staging) / fname);
      sources.push_back(fname);
    }
    // The client's files are parsed in the import jail (server/jail/): a crash, hang or memory
    // bomb in GDAL ends that worker, never this process.
    jail::ImportRequest req;
    req.kind = "dem";
    req.sources = sources;
    req.load = options.load;
    req.load.maxCells = maxCells_;
    std::string raster;
    ImportStages stages;
    // GDAL's writers allocate and free buffers of several MiB per strip: kept in the heap for the
    // import (server/missions/bulk_heap.hpp), returned when it ends.
    const missions::BulkHeap bulkHeap;
    // The heights never sit in this process's memory (issue 24: an import holds no full-size
    // float copy; the worker's grid is the only one, and it has ended). They stream from the
    // worker's output in checked chunks of 4 MiB into the server's own grid file (in the staging
    // folder, never the worker's file, which a process the worker left behind could
    // still change), sampled for the colour ramp on the way, while a second thread computes the
    // classes from it in bands of rows as they arrive, writes classes.tif and the class shares.
    // The grid file then stays as the map's elevation, raw: its overview levels computed on both
    // cores (maps/average_levels.hpp) and a VRT over them (maps::writeRawDem) that every reader
    // opens as it opens dem.tif. The map is committed so, and its dem.tif (the ZSTD COG, ~10 s of
    // CPU on 300 M cells) is written afterwards by the catalog's compressor (issue 24: the first
    // tiles of a 300 M-cell map within 20 s on 2 cores). Memory: the chunk,
    // the classes (a byte a cell, from the first chunk on, plus a third for the pyramid's
    // levels), a band of 256 rows, GDAL's block cache and write buffers; the file's pages are the
    // kernel's page cache.
    // "~" is outside every staged upload's name (safeName), so no client file is overwritten.
    const fs::path rawDir = fs::path(staging) / kRawDemDir;
    fs::create_directory(rawDir);
    const std::string gridFile = (rawDir / "grid.f32").string();
    std::optional<maps::DemDigest> digester;
    std::optional<maps::ElevationSample> sample;
    std::optional<maps::GridFileWriter> writer;
    terrain::ClassShares shares;
    double classSeconds = 0, pyramidSeconds = 0;
    // The classes, classes.tif and the digest, on a second thread from the stream's first chunk:
    // its bands wait for their rows (GridRowsGate), so they run on the core the stream leaves
    // idle, then alongside dem.tif. Destroyed in reverse order: on a failed stream the guard
    // first wakes the thread (abort), the future then waits for it to end, and only then does
    // the gate it waits on go — so the gate is declared first, the future, then the guard.
    maps::GridRowsGate gate;
    std::future<void> alongside;
    struct AbortGate {
      maps::GridRowsGate& gate;
      ~AbortGate() { gate.abort(); }
    } abortGate{gate};
    auto classesAlongside = [&](GridGeometry g, std::vector<double> rowCellWidth, GeoReference geo) {
      auto since = [](auto from) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count(); };
      auto from = std::chrono::steady_clock::now();
      // The digest reads the bands' rows as they pass (0.2 s of CPU on 49 M cells, off the path
      // to the first tiles).
      // On both cores: with the COG written after the commit, the classes are what the first tiles
      // wait for (issue 24), and the stream's copy leaves a core idle.
      terrain::Traversability t = maps::traversabilityOfGridFile(
          gridFile, g, rowCellWidth, 256, [&](const float* v, std::size_t n) { digester->add(v, n); }, &gate, 0);
      t.classes.geo = geo;
      classSeconds = since(from);
      from = std::chrono::steady_clock::now();
      storingGeoTiff([&] { maps::writeClassPyramid((fs::path(staging) / kClassFile).string(), t.classes); });
      pyramidSeconds = since(from);
      shares = t.shares;  // only the shares are kept (the record's classes)
    };
    const GridRows streamed = [&](const terrain::Dem& header, int r0, int n, const float* v) {
      const GridGeometry& g = header.geometry();
      if (!writer) {
        writer.emplace(gridFile, g);
        digester.emplace(g, header.rowCellWidth);
        sample.emplace(static_cast<std::size_t>(g.cellCount()));
        alongside = std::async(std::launch::async, classesAlongside, g, header.rowCellWidth, header.z.geo);
      }
      const std::size_t first = static_cast<std::size_t>(r0) * g.cols, cells = static_cast<std::size_t>(n) * g.cols;
      writer->append(v, cells);
      writer->flush();
      sample->add(first, v, cells);
      gate.publish(r0 + n);
    };
    maps::LoadedDem d;
    storingGeoTiff([&] {
      d = importJailed(staging, req, raster, &stages, &streamed);
      writer->close();
    });
    const GridGeometry& g = d.dem.geometry();
    const bool background = g.cellCount() >= backgroundCells_.load();
    if (sample->needsEveryCell()) {  // a sparse grid: its finite heights counted, then sampled, read back by rows
      std::vector<float> rows(static_cast<std::size_t>(std::max(1, (4 << 20) / (4 * g.cols))) * g.cols);
      const int step = static_cast<int>(rows.size() / g.cols);
      for (const bool counting : {true, false})
        for (int r0 = 0; r0 < g.rows; r0 += step) {
          const int n = std::min(step, g.rows - r0);
          maps::readGridRows(gridFile, g.cols, r0, n, rows.data());
          const std::size_t cells = static_cast<std::size_t>(n) * g.cols;
          if (counting)
            sample->countFinite(rows.data(), cells);
          else
            sample->addEvery(rows.data(), cells);
        }
    }
    // Every tile's ramp, fixed at import (the full-size picture's: maps::colourRange).
    const maps::ColourRange ramp = sample->range();
    stages.done("grid");
    {
      // The future's destructor waits, so the grid file outlives the thread when the levels throw.
      storingGeoTiff([&] { maps::writeRawDem((rawDir / kRawDemVrt).string(), gridFile, g, d.dem.z.geo); });
      stages.done("levels");
      if (!background) {
        storingGeoTiff([&] {
          maps::writeDemCogFromRaw((fs::path(staging) / kDemFile).string(), (rawDir / kRawDemVrt).string());
        });
        stages.done("dem.tif");
      }
      alongside.get();
    }
    if (!background) {
      store::DataDir::removeTree(rawDir.string());
    } else {
      // A client's file staged as dem.tif (an upload named so) is not kept: the map's folder
      // names its COG so, and every reader would take it for one (the COG used to overwrite it).
      fs::remove(fs::path(staging) / kDemFile);
    }
    stages.done("then waiting for classes.tif");
    const std::string digest = digester->hex();
    char alongsideLine[128];
    std::snprintf(alongsideLine, sizeof alongsideLine, "alongside the levels: classes %.2f s, classes.tif %.2f s",
                  classSeconds, pyramidSeconds);
    stages.note(alongsideLine);
    store::MapRecord rec;
    rec.id = store::DataDir::newId();
    // A default name comes from the file (a zip member's may hold anything): its last path part,
    // hidden controls and bad bytes dropped, at most 200 characters.
    if (name.empty()) {
      rec.name = rover::json::cleanName(fs::path(raster).filename().string());
      if (rec.name.empty()) rec.name = "upload";
    } else {
      rec.name = name;
    }
    rec.createdAt = store::nowIso();
    rec.meta = metaFor(d, shares, sources, digest);
    rec.meta["colour_range"] = {ramp.lo, ramp.hi};
    const int overviews = maps::tileGridOf(g.rows, g.cols).nativeZoom;
    rec.meta["storage"] = background ? rawStorage(overviews) : cogStorage(overviews);
    // The body the planners assume: declared with the upload, else read from the CRS.
    const terrain::Body body = options.body ? *options.body : maps::bodyOfCrs(d.dem.z.geo.crsWkt);
    rec.meta["body"] = terrain::bodyName(body);
    rec.meta["body_source"] = options.body ? "declared" : "crs";
    rec.meta["vertical_scale"] = options.load.verticalScale;
    rec.meta["vertical_offset"] = options.load.verticalOffset;
    if (options.load.crop) rec.meta["crop"] = *options.load.crop;
    if (options.load.cropPixels) rec.meta["crop_px"] = *options.load.cropPixels;
    // Files first, then the row: a crash in between leaves an orphan folder nobody lists.
    dir_.commitDir(staging, dir_.mapDir(rec.id), store::DiskCharge{store::DiskUse::Map, rec.id, "file"});
    db_.insertMap(rec);
    if (background) compressor_->enqueue(rec.id);  // dem.tif from the raw files
    stages.done("commit");
    std::cerr << "import " << d.dem.geometry().cols << "x" << d.dem.geometry().rows << ": " << stages.line() << std::endl;
    return rec;
  } catch (...) {
    store::DataDir::removeTree(staging);
    throw;
  }
}

void MapCatalog::ensureDefaultMap() {
  if (!db_.listMaps().empty()) return;
  maps::SyntheticTerrainParams p;  // mars, 600 × 600 × 0.25 m, seed 1
  terrain::Dem dem = maps::generateTerrain(p);
  const std::string staging = dir_.stagingDir();
  const std::string path = (fs::path(staging) / "default-mars.tif").string();
  maps::writeGeoTiff(path, dem.z);
  const std::string moved = (fs::path(dir_.tmpDir()) / (store::DataDir::newId() + ".tif")).string();
  fs::rename(path, moved);
  store::DataDir::removeTree(staging);
  importDem({{moved, "default-mars.tif"}}, "Default: synthetic Mars, 150 m (seed 1)");
}

}  // namespace rover::api
