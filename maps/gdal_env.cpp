#include "maps/gdal_env.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_multiproc.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <regex>

#include "maps/gdal_sandbox.hpp"

namespace rover::maps {

namespace fs = std::filesystem;

namespace sandbox {

thread_local UploadSandbox::State* tlsSandbox = nullptr;

bool underDir(const std::string& p, const std::string& dir) {
  if (dir.empty() || p.size() < dir.size() || p.compare(0, dir.size(), dir) != 0) return false;
  return p.size() == dir.size() || p[dir.size()] == '/' || dir == "/";
}

// Absolute, symlinks and ".." resolved as far as the path exists; "" when it cannot be resolved.
std::string canonicalLocal(const std::string& p) {
  std::error_code ec;
  fs::path abs = fs::absolute(p, ec);
  if (ec) return "";
  fs::path c = fs::weakly_canonical(abs, ec);
  if (ec) return "";
  std::string s = c.string();
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

std::string baseName(const std::string& p) {
  std::string s = p;
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  auto slash = s.rfind('/');
  return slash == std::string::npos ? s : s.substr(slash + 1);
}

namespace {

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

std::string lexicalNormal(const std::string& p) {
  std::string s = fs::path(p).lexically_normal().string();
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

bool hasDotDot(const std::string& p) {
  for (const auto& part : fs::path(p))
    if (part == "..") return true;
  return false;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// /vsizip/ARCHIVE/member (and /vsitar/, /vsigzip/): the archive and the member. The archive ends
// at the first component with the archive's extension, as GDAL splits it; braces ({…}) are not
// accepted. Returns false when the path has no such form.
bool splitArchive(const std::string& path, std::string& archive, std::string& member) {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> kinds{
      {"/vsizip/", {".zip"}}, {"/vsitar/", {".tar", ".tgz", ".tar.gz"}}, {"/vsigzip/", {}}};
  for (const auto& [prefix, exts] : kinds) {
    if (!startsWith(path, prefix.c_str())) continue;
    const std::string rest = path.substr(prefix.size());
    if (rest.empty() || rest[0] == '{') return false;
    if (exts.empty()) {  // /vsigzip/FILE: one compressed file
      archive = rest;
      member.clear();
      return true;
    }
    for (std::size_t i = 1; i <= rest.size(); ++i) {
      if (i < rest.size() && rest[i] != '/') continue;
      const std::string head = lower(rest.substr(0, i));
      for (const auto& e : exts)
        if (head.size() > e.size() && head.compare(head.size() - e.size(), e.size(), e) == 0) {
          archive = rest.substr(0, i);
          member = rest.substr(i);
          return true;
        }
    }
    return false;
  }
  return false;
}

bool containsPath(const UploadSandbox::State& s, const std::string& path, int depth = 0) {
  if (depth > 4) return false;
  std::string archive, member;
  if (startsWith(path, "/vsizip/") || startsWith(path, "/vsitar/") || startsWith(path, "/vsigzip/")) {
    if (!splitArchive(path, archive, member) || hasDotDot(member)) return false;
    return containsPath(s, archive, depth + 1);
  }
  if (startsWith(path, "/vsimem/")) return s.memory && !hasDotDot(path) && underDir(lexicalNormal(path), s.root);
  if (startsWith(path, "/vsi")) return false;
  return !s.memory && underDir(canonicalLocal(path), s.root);
}

}  // namespace

void noteRefusedFile(UploadSandbox::State& s, const char* path) {
  if (std::getenv("ROVER_SANDBOX_DEBUG")) std::fprintf(stderr, "sandbox refused: '%s'\n", path ? path : "(null)");
  std::string name = baseName(path ? path : "");
  if (name.empty()) name = "?";
  // GDAL probes case variants (passwd, PASSWD): name each file once.
  if (std::none_of(s.refusedFiles.begin(), s.refusedFiles.end(),
                   [&](const std::string& f) { return lower(f) == lower(name); }))
    s.refusedFiles.push_back(name);
}

}  // namespace sandbox

// The sandbox's path rules are used unqualified below.
using namespace sandbox;

namespace {

std::atomic<bool> ranOutOfMemory{false};

void captureError(CPLErr cls, CPLErrorNum num, const char* msg) {
  if (cls < CE_Failure) return;  // warnings and debug output are not reasons
  if (num == CPLE_OutOfMemory) ranOutOfMemory = true;
  if (auto* log = static_cast<GdalErrorLog*>(CPLGetErrorHandlerUserData())) log->add(msg ? msg : "");
}

}  // namespace

void ensureGdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    CPLSetErrorHandler(CPLQuietErrorHandler);
    // Figures GDAL reads from /proc and /sys once, before any sandbox is live.
    GDALGetCacheMax64();
    // GDAL's block cache defaults to 5 % of the machine's memory (1.2 GB of 23 GB), a hidden share
    // of every import's and tile's peak: 256 MiB unless GDAL_CACHEMAX says otherwise (README).
    if (!CPLGetConfigOption("GDAL_CACHEMAX", nullptr)) GDALSetCacheMax64(256ll << 20);
    CPLGetNumCPUs();
    const char* f = CPLFindFile("gdal", "gdalvrt.xsd");
    sandbox::installGdalGuards(f ? sandbox::canonicalLocal(fs::path(f).parent_path().string()) : std::string());
  });
}

std::string gdalVersion() {
  return std::string("GDAL ") + GDALVersionInfo("RELEASE_NAME");
}

const std::vector<std::string>& uploadDrivers() {
  static const std::vector<std::string> drivers{
      "GTiff", "PDS", "PDS4", "ISIS3", "ISIS2", "VICAR", "netCDF", "ENVI", "EHdr", "AAIGrid",
      "XYZ", "USGSDEM", "SRTMHGT", "DTED", "HFA", "GS7BG", "GSBG", "GSAG", "PNG"};
  return drivers;
}

std::string formatInWords(const std::string& driver) {
  static const std::map<std::string, std::string> words{
      {"GTiff", "GeoTIFF"}, {"PDS", "PDS3 image"}, {"PDS4", "PDS4 product"}, {"ISIS3", "ISIS3 cube"},
      {"ISIS2", "ISIS2 cube"}, {"VICAR", "VICAR image"}, {"netCDF", "netCDF file"},
      {"ENVI", "ENVI raster"}, {"EHdr", "ESRI .hdr raster"}, {"AAIGrid", "ASCII grid"},
      {"XYZ", "XYZ grid"}, {"USGSDEM", "USGS DEM"}, {"SRTMHGT", "SRTM .hgt tile"},
      {"DTED", "DTED tile"}, {"HFA", "Erdas Imagine image"}, {"GS7BG", "Surfer binary grid"},
      {"GSBG", "Surfer binary grid"}, {"GSAG", "Surfer ASCII grid"}, {"PNG", "PNG image"},
      {"VRT", "GDAL virtual raster (VRT)"}};
  if (auto it = words.find(driver); it != words.end()) return it->second;
  ensureGdal();
  GDALDriverH d = GDALGetDriverByName(driver.c_str());
  return d ? std::string(GDALGetDriverLongName(d)) + " (" + driver + ")" : driver;
}

std::string uploadFormatsInWords() {
  return "GeoTIFF, PDS3 (.IMG with its .LBL), PDS4, ISIS2/3 cubes, VICAR, netCDF, ENVI, "
         "ESRI .hdr, ASCII grid, XYZ, USGS DEM, SRTM .hgt, DTED, Erdas Imagine, Surfer grids, PNG — "
         "also inside a .zip or .tar";
}

ThreadConfig::ThreadConfig(const char* key, const char* value) : key_(key) {
  if (const char* was = CPLGetThreadLocalConfigOption(key, nullptr)) {
    had_ = true;
    was_ = was;
  }
  CPLSetThreadLocalConfigOption(key, value);
}

ThreadConfig::~ThreadConfig() { CPLSetThreadLocalConfigOption(key_.c_str(), had_ ? was_.c_str() : nullptr); }

UploadSandbox::UploadSandbox(const std::string& root, bool allowHdf5) : state_(std::make_unique<State>()) {
  ensureGdal();
  state_->allowHdf5 = allowHdf5;
  state_->memory = startsWith(root, "/vsimem/");
  state_->root = state_->memory ? lexicalNormal(root) : canonicalLocal(root);
  if (state_->root.empty() || state_->root == "/" || state_->root == "/vsimem")
    throw std::invalid_argument("UploadSandbox: the root must be a folder");
  if (tlsSandbox) throw std::logic_error("UploadSandbox: scopes do not nest");
  tlsSandbox = state_.get();
}

UploadSandbox::~UploadSandbox() { tlsSandbox = nullptr; }

const std::string& UploadSandbox::root() const { return state_->root; }
bool UploadSandbox::allowsHdf5() const { return state_->allowHdf5; }
bool UploadSandbox::live() const { return tlsSandbox == state_.get(); }
bool UploadSandbox::contains(const std::string& path) const { return containsPath(*state_, path); }
const std::vector<std::string>& UploadSandbox::refusedFiles() const { return state_->refusedFiles; }
const std::vector<std::string>& UploadSandbox::refusedDrivers() const { return state_->refusedDrivers; }

std::string UploadSandbox::uploadName(const std::string& path) const {
  std::string p = path, archive, member;
  for (const char* prefix : {"/vsizip/", "/vsitar/", "/vsigzip/"})
    if (startsWith(p, prefix)) {
      p = p.substr(std::strlen(prefix));
      break;
    }
  std::string c = state_->memory ? lexicalNormal(p) : p;
  if (!state_->memory && !startsWith(c, "/vsi")) {
    // Compare the archive's folder canonically, keep the member part as given.
    std::string head = c, tail;
    while (!head.empty() && canonicalLocal(head).empty()) {
      auto slash = head.rfind('/');
      if (slash == std::string::npos) break;
      tail = head.substr(slash) + tail;
      head = head.substr(0, slash);
    }
    c = canonicalLocal(head) + tail;
  }
  if (underDir(c, state_->root) && c.size() > state_->root.size() + 1) return c.substr(state_->root.size() + 1);
  return baseName(path);
}

void DatasetCloser::operator()(void* ds) const {
  if (ds) GDALClose(ds);
}

std::string firstBytes(const std::string& path, std::size_t n) {
  VSILFILE* f = VSIFOpenL(path.c_str(), "rb");
  if (!f) return "";
  std::string b(n, '\0');
  b.resize(VSIFReadL(b.data(), 1, n, f));
  VSIFCloseL(f);
  return b;
}

std::vector<std::uint8_t> takeMemFile(const std::string& path) {
  vsi_l_offset length = 0;
  GByte* buffer = VSIGetMemFileBuffer(path.c_str(), &length, FALSE);
  std::vector<std::uint8_t> bytes;
  if (buffer != nullptr) bytes.assign(buffer, buffer + length);
  VSIUnlink(path.c_str());
  return bytes;
}

namespace {

std::string quoted(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size() && i < 3; ++i) s += (i ? ", '" : "'") + names[i] + "'";
  if (names.size() > 3) s += " and " + std::to_string(names.size() - 3) + " more";
  return s;
}

}  // namespace

Dataset openUpload(const std::string& path, const UploadSandbox& sandbox, std::string& refusal) {
  refusal.clear();
  if (!sandbox.live()) throw std::logic_error("openUpload: the sandbox is not live on this thread");
  if (!sandbox.contains(path)) {
    refusal = "'" + sandbox.uploadName(path) + "' is not a file of the upload";
    return nullptr;
  }
  std::vector<std::string> drivers = uploadDrivers();
  // netCDF-4 files are HDF5, whose datasets may be stored in (or link to) other files, which
  // libhdf5 opens itself: only classic netCDF ("CDF\1", "CDF\2", "CDF\5") is accepted, unless
  // the process cannot see other files (the import jail says so).
  if (!sandbox.allowsHdf5() && firstBytes(path, 3) != "CDF")
    drivers.erase(std::find(drivers.begin(), drivers.end(), "netCDF"));
  std::vector<const char*> allowed;
  for (const auto& d : drivers) allowed.push_back(d.c_str());
  allowed.push_back(nullptr);
  const std::size_t refusedBefore = sandbox.refusedFiles().size();
  const std::size_t driversBefore = sandbox.refusedDrivers().size();
  Dataset ds(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, allowed.data(), nullptr, nullptr));
  const std::string name = sandbox.uploadName(path);
  if (!ds) {
    if (sandbox.refusedFiles().size() > refusedBefore) {
      std::vector<std::string> outside(sandbox.refusedFiles().begin() + refusedBefore, sandbox.refusedFiles().end());
      refusal = name + " refers to " + quoted(outside) + ", which is not part of the upload (a dataset may "
                "only use files uploaded with it)";
    } else if (sandbox.refusedDrivers().size() > driversBefore) {
      refusal = name + " holds a " + formatInWords(sandbox.refusedDrivers()[driversBefore]) +
                " inside it, which uploads may not use";
    } else if (GDALDriverH d = GDALIdentifyDriverEx(path.c_str(), GDAL_OF_RASTER, nullptr, nullptr)) {
      const std::string driver = GDALGetDriverShortName(d);
      if (std::find(drivers.begin(), drivers.end(), driver) == drivers.end())
        refusal = driver == "netCDF"
                      ? name + " is a netCDF-4 (HDF5) file, which this server reads only where its import "
                               "jail (bubblewrap) runs; classic netCDF is read everywhere"
                      : name + " is a " + formatInWords(driver) + ", which uploads may not use (accepted: " +
                            uploadFormatsInWords() + ")";
    }
    return nullptr;
  }
  // Every file the dataset uses must be one of the upload's; an archive member counts as its archive.
  std::vector<std::string> outside;
  char** files = GDALGetFileList(ds.get());
  for (char** f = files; f && *f; ++f)
    if (!sandbox.contains(*f)) outside.push_back(sandbox.uploadName(*f));
  CSLDestroy(files);
  if (!outside.empty()) {
    refusal = name + " refers to " + quoted(outside) + ", which is not part of the upload";
    return nullptr;
  }
  return ds;
}

bool gdalRanOutOfMemory() { return ranOutOfMemory; }

GdalErrorLog::GdalErrorLog() { CPLPushErrorHandlerEx(captureError, this); }
GdalErrorLog::~GdalErrorLog() { CPLPopErrorHandler(); }

bool GdalErrorLog::mentions(const std::string& text) const {
  return std::any_of(messages_.begin(), messages_.end(),
                     [&](const std::string& m) { return m.find(text) != std::string::npos; });
}

std::string withoutPaths(const std::string& text) {
  static const std::regex absPath(R"((/[^\s'"(),;:\[\]{}<>]+)+)");
  std::string out;
  auto begin = std::sregex_iterator(text.begin(), text.end(), absPath);
  std::size_t last = 0;
  for (auto it = begin; it != std::sregex_iterator(); ++it) {
    out += text.substr(last, it->position() - last);
    out += baseName(it->str());
    last = it->position() + it->length();
  }
  return out + text.substr(last);
}

}  // namespace rover::maps
