#include "server/jail/worker_output.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/common/error.hpp"
#include "maps/gdal_env.hpp"
#include "maps/georef.hpp"

namespace rover::jail {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::uintmax_t kMaxJsonBytes = 16u << 20;  // row widths of a 50 k-row map fit many times
constexpr std::size_t kMaxWktBytes = 64u << 10;
constexpr std::size_t kMaxTextBytes = 1024;

[[noreturn]] void bad(const std::string& why) { throw std::runtime_error("import worker output: " + why); }

void writeFile(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.filename().string());
}

json readJson(const fs::path& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) bad(path.filename().string() + " is missing");
  if (size > kMaxJsonBytes) bad(path.filename().string() + " is too large");
  std::ifstream in(path, std::ios::binary);
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) bad(path.filename().string() + " is not a JSON object");
  return j;
}

std::string text(const json& j, const char* key, std::size_t max = kMaxTextBytes) {
  auto it = j.find(key);
  if (it == j.end() || !it->is_string()) bad(std::string(key) + " is not a string");
  std::string s = it->get<std::string>();
  if (s.size() > max) bad(std::string(key) + " is too long");
  return s;
}

double number(const json& j, const char* key) {
  auto it = j.find(key);
  if (it == j.end() || !it->is_number()) bad(std::string(key) + " is not a number");
  const double v = it->get<double>();
  if (!std::isfinite(v)) bad(std::string(key) + " is not finite");
  return v;
}

json window(const std::optional<std::array<double, 4>>& w) { return w ? json(*w) : json(nullptr); }

std::optional<std::array<double, 4>> windowFrom(const json& j, const char* key) {
  auto it = j.find(key);
  if (it == j.end() || it->is_null()) return std::nullopt;
  if (!it->is_array() || it->size() != 4) bad(std::string(key) + " is not four numbers");
  std::array<double, 4> w{};
  for (std::size_t i = 0; i < 4; ++i) {
    if (!(*it)[i].is_number()) bad(std::string(key) + " is not four numbers");
    w[i] = (*it)[i].get<double>();
  }
  return w;
}

// A chunk's NaN count, lowest and highest finite values (+inf / -inf when none) and whether it
// holds an infinity, four cells at a time (GCC/Clang vector extensions: SSE2 on x86-64, NEON on
// aarch64), no branch per cell: half the CPU of the branchy loop per cell (0.25 vs 0.5 s on
// 300 M cells), on the import's path to the first tiles (issue 24). A NaN keeps the lanes' lowest
// and highest; a real infinity shows as a lowest of -inf or a highest of +inf.
struct ChunkFigures {
  std::size_t nan = 0;
  float lo = INFINITY, hi = -INFINITY;
  bool infinite = false;
};

ChunkFigures figuresOf(const float* v, std::size_t n) {
  typedef float F4 __attribute__((vector_size(16)));
  typedef std::int32_t I4 __attribute__((vector_size(16)));
  const F4 inf = {INFINITY, INFINITY, INFINITY, INFINITY};
  F4 lo = inf, hi = -inf;
  I4 nan = {};
  std::size_t k = 0;
  ChunkFigures f;
  for (; k + 4 <= n; k += 4) {
    F4 x;
    std::memcpy(&x, v + k, sizeof x);
    const I4 isNan = x != x;  // -1 where NaN
    nan -= isNan;
    lo = isNan ? lo : (x < lo ? x : lo);
    hi = isNan ? hi : (x > hi ? x : hi);
    if (((k >> 2) & 0xFFFFF) == 0xFFFFF) {  // a lane's count stays far below 2^31
      for (int l = 0; l < 4; ++l) f.nan += static_cast<std::size_t>(nan[l]);
      nan = I4{};
    }
  }
  for (; k < n; ++k) {
    const float x = v[k];
    if (x != x) {
      ++f.nan;
      continue;
    }
    f.lo = std::min(f.lo, x);
    f.hi = std::max(f.hi, x);
  }
  for (int l = 0; l < 4; ++l) {
    f.nan += static_cast<std::size_t>(nan[l]);
    f.lo = std::min(f.lo, lo[l]);
    f.hi = std::max(f.hi, hi[l]);
  }
  f.infinite = f.lo == -INFINITY || f.hi == INFINITY;
  return f;
}

}  // namespace

void writeImportRequest(const std::string& outDir, const ImportRequest& r) {
  const json j{{"kind", r.kind},
               {"sources", r.sources},
               {"cell", r.load.cellSize},
               {"crop", window(r.load.crop)},
               {"crop_px", window(r.load.cropPixels)},
               {"vertical_scale", r.load.verticalScale},
               {"vertical_offset", r.load.verticalOffset},
               {"max_cells", r.load.maxCells},
               {"resampling", r.load.resampling},
               {"allow_hdf5", r.allowHdf5}};
  writeFile(fs::path(outDir) / "request.json", j.dump());
}

ImportRequest readImportRequest(const std::string& outDir) {
  const json j = readJson(fs::path(outDir) / "request.json");
  ImportRequest r;
  r.kind = text(j, "kind");
  if (r.kind != "dem" && r.kind != "pdm") bad("kind must be dem or pdm");
  if (!j.contains("sources") || !j["sources"].is_array()) bad("sources is not a list");
  for (const auto& s : j["sources"]) {
    if (!s.is_string()) bad("sources holds a non-string");
    r.sources.push_back(s.get<std::string>());
  }
  r.load.cellSize = number(j, "cell");
  r.load.crop = windowFrom(j, "crop");
  r.load.cropPixels = windowFrom(j, "crop_px");
  r.load.verticalScale = number(j, "vertical_scale");
  r.load.verticalOffset = number(j, "vertical_offset");
  r.load.maxCells = static_cast<std::int64_t>(number(j, "max_cells"));
  r.load.resampling = text(j, "resampling");
  r.allowHdf5 = j.value("allow_hdf5", false);
  return r;
}

void writeWorkerError(const std::string& outDir, const WorkerError& e) {
  const json j{{"status", e.status}, {"code", e.code}, {"message", e.message}, {"field", e.field}};
  // Written beside, then renamed: the server never reads half an error.
  writeFile(fs::path(outDir) / "error.json.tmp", j.dump());
  fs::rename(fs::path(outDir) / "error.json.tmp", fs::path(outDir) / "error.json");
}

std::optional<WorkerError> readWorkerError(const std::string& outDir) {
  const fs::path path = fs::path(outDir) / "error.json";
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  try {
    const json j = readJson(path);
    WorkerError e;
    e.status = static_cast<int>(number(j, "status"));
    if (e.status != 400 && e.status != 413) return std::nullopt;
    e.code = text(j, "code", 64);
    e.field = text(j, "field", 256);
    e.message = maps::withoutPaths(text(j, "message", 4096));
    auto plain = [](const std::string& s, const char* extra) {
      return std::all_of(s.begin(), s.end(), [&](unsigned char c) {
        return std::islower(c) || std::isdigit(c) || c == '_' || std::strchr(extra, c) != nullptr;
      });
    };
    if (e.code.empty() || !plain(e.code, "") || !plain(e.field, ".[]_ABCDEFGHIJKLMNOPQRSTUVWXYZ")) return std::nullopt;
    return e;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

void writeWorkerResult(const std::string& outDir, const maps::LoadedDem& d, const std::string& rasterName) {
  const GridGeometry& g = d.dem.geometry();
  const maps::DemInfo& i = d.info;
  json info{{"driver", i.driver},          {"source_cols", i.sourceCols}, {"source_rows", i.sourceRows},
            {"crs_name", i.crsName},       {"geographic", i.geographic},  {"georeferenced", i.georeferenced},
            {"scale", i.scale},            {"offset", i.offset},          {"resampling", i.resampling}};
  if (i.nodata && std::isfinite(*i.nodata)) info["nodata"] = *i.nodata;
  const json j{{"rows", g.rows},
               {"cols", g.cols},
               {"cell_width", g.cellWidth},
               {"cell_height", g.cellHeight},
               {"row_cell_width", d.dem.rowCellWidth},
               {"geo_valid", d.dem.z.geo.valid},
               {"geotransform", d.dem.z.geo.geotransform},
               {"crs_wkt", d.dem.z.geo.crsWkt},
               {"raster", rasterName},
               {"info", info}};
  {
    // Straight from the grid (a copy would double the worker's peak); x86-64 and aarch64 are
    // little-endian.
    std::ofstream grid(fs::path(outDir) / "grid.f32", std::ios::binary | std::ios::trunc);
    grid.write(reinterpret_cast<const char*>(d.dem.z.values.data()),
               static_cast<std::streamsize>(g.cellCount()) * static_cast<std::streamsize>(sizeof(float)));
    grid.close();
    if (!grid) throw std::runtime_error("cannot write grid.f32");
  }
  // The result last, by rename: its presence says the grid is complete.
  writeFile(fs::path(outDir) / "result.json.tmp", j.dump());
  fs::rename(fs::path(outDir) / "result.json.tmp", fs::path(outDir) / "result.json");
}

WorkerResult readWorkerHeader(const std::string& outDir, std::int64_t maxCells) {
  const json j = readJson(fs::path(outDir) / "result.json");
  WorkerResult r;
  const double rows = number(j, "rows"), cols = number(j, "cols");
  if (rows < 2 || cols < 2 || rows != std::floor(rows) || cols != std::floor(cols)) bad("the grid is not 2 x 2 cells or more");
  if (rows * cols > static_cast<double>(maxCells)) bad("the grid is over the cell budget");
  GridGeometry g{static_cast<int>(rows), static_cast<int>(cols), number(j, "cell_width"), number(j, "cell_height")};
  // Cell sizes in metres: the same checks as the core (checkGridGeometry) and the georeferencing.
  for (double c : {g.cellWidth, g.cellHeight})
    if (!(c > 0)) throw Error(ErrorCode::InvalidInput, "geotransform.pixel_width", "the map's cells have no size");
  terrain::Dem& dem = r.dem.dem;
  if (!j.contains("row_cell_width") || !j["row_cell_width"].is_array()) bad("row_cell_width is not a list");
  const json& widths = j["row_cell_width"];
  if (!widths.empty() && widths.size() != static_cast<std::size_t>(g.rows)) bad("row_cell_width is not one per row");
  for (const auto& w : widths) {
    if (!w.is_number() || !std::isfinite(w.get<double>()) || !(w.get<double>() > 0)) bad("a row cell width is not positive");
    dem.rowCellWidth.push_back(w.get<double>());
  }
  GeoReference geo;
  geo.valid = j.value("geo_valid", false);
  if (!j.contains("geotransform") || !j["geotransform"].is_array() || j["geotransform"].size() != 6)
    bad("geotransform is not six numbers");
  for (std::size_t k = 0; k < 6; ++k) {
    if (!j["geotransform"][k].is_number()) bad("geotransform is not six numbers");
    geo.geotransform[k] = j["geotransform"][k].get<double>();
  }
  geo.crsWkt = text(j, "crs_wkt", kMaxWktBytes);
  maps::checkGeoreference(geo, g.rows, g.cols);  // rover::Error naming geotransform.<part>
  r.rasterName = text(j, "raster");
  dem.z.geometry = g;  // no values yet: readWorkerGrid streams them
  dem.z.geo = geo;
  maps::DemInfo& info = r.dem.info;
  if (!j.contains("info") || !j["info"].is_object()) bad("info is not an object");
  const json& i = j["info"];
  info.driver = text(i, "driver", 64);
  info.sourceCols = static_cast<int>(number(i, "source_cols"));
  info.sourceRows = static_cast<int>(number(i, "source_rows"));
  info.crsName = text(i, "crs_name");
  info.geographic = i.value("geographic", false);
  info.georeferenced = i.value("georeferenced", false);
  info.scale = number(i, "scale");
  info.offset = number(i, "offset");
  info.resampling = text(i, "resampling", 64);
  if (i.contains("nodata")) info.nodata = number(i, "nodata");
  return r;
}

void readWorkerGrid(const std::string& outDir, const GridGeometry& g, maps::DemInfo& info, int rowsPerChunk,
                    const std::function<void(int, int, const float*)>& each) {
  const fs::path grid = fs::path(outDir) / "grid.f32";
  std::error_code ec;
  const auto size = fs::file_size(grid, ec);
  const std::uintmax_t expected = static_cast<std::uintmax_t>(g.cellCount()) * sizeof(float);
  if (ec || size != expected) bad("grid.f32 does not hold rows x cols float32 values");
  std::ifstream in(grid, std::ios::binary);
  rowsPerChunk = std::clamp(rowsPerChunk, 1, g.rows);
  std::vector<float> chunk(static_cast<std::size_t>(rowsPerChunk) * g.cols);
  // The figures the map's record shows, from the grid itself.
  double lo = INFINITY, hi = -INFINITY;
  std::int64_t nodata = 0;
  for (int r0 = 0; r0 < g.rows; r0 += rowsPerChunk) {
    const int n = std::min(rowsPerChunk, g.rows - r0);
    const std::size_t cells = static_cast<std::size_t>(n) * g.cols;
    in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(cells * sizeof(float)));
    if (!in) bad("grid.f32 does not read");
    const ChunkFigures f = figuresOf(chunk.data(), cells);
    if (f.infinite) throw Error(ErrorCode::InvalidInput, "file", "the raster holds infinite values");
    nodata += f.nan;
    lo = std::min(lo, static_cast<double>(f.lo));
    hi = std::max(hi, static_cast<double>(f.hi));
    each(r0, n, chunk.data());
  }
  if (nodata == g.cellCount()) throw Error(ErrorCode::InvalidInput, "file", "every cell is nodata");
  info.nodataCells = nodata;
  info.minHeight = lo;
  info.maxHeight = hi;
}

WorkerResult readWorkerResult(const std::string& outDir, std::int64_t maxCells) {
  WorkerResult r = readWorkerHeader(outDir, maxCells);
  Raster<float>& z = r.dem.dem.z;
  const GridGeometry g = z.geometry;
  const GeoReference geo = z.geo;
  // Up to 4 MiB a chunk: the one full-size copy is `z` itself.
  z = Raster<float>(g, 0.0f);
  z.geo = geo;
  readWorkerGrid(outDir, g, r.dem.info, std::max(1, (4 << 20) / (4 * g.cols)), [&](int r0, int n, const float* v) {
    std::copy(v, v + static_cast<std::size_t>(n) * g.cols, z.values.data() + static_cast<std::size_t>(r0) * g.cols);
  });
  return r;
}

}  // namespace rover::jail
