#include "maps/gdal_sandbox.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_http.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <cpl_vsi_virtual.h>
#include <gdal.h>
#include <gdal_priv.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <unordered_map>

namespace rover::maps::sandbox {

namespace {

std::string gdalDataDir;  // read-only allowance for GDAL's own support files; set once

// What a wrapped GDAL file system may reach while a sandbox is live on the thread. Only these are
// wrapped: /vsimem/ is cast to its own class inside GDAL, and the archive and sub-file handlers
// (/vsizip/, /vsitar/, /vsisubfile/, …) reach bytes only through the local one, which checks.
enum class Reach {
  LocalFiles,  // the default (POSIX) file system: inside the root, or GDAL's own data files to read
  Never,       // /vsistdin/: nothing while sandboxed
  Network,     // /vsicurl/, /vsis3/, …: nothing, ever (network access is off for the process)
};

// Forwards to GDAL's own handler what the live sandbox (if any) allows; the rest fails as if the
// file did not exist, and is noted so the upload error can name it.
class GuardedFilesystem final : public VSIFilesystemHandler {
 public:
  GuardedFilesystem(VSIFilesystemHandler* inner, Reach reach) : inner_(inner), reach_(reach) {}

  VSIVirtualHandle* Open(const char* path, const char* access, bool setError,
                         CSLConstList options) override {
    const bool readOnly = access && !std::strpbrk(access, "wa+");
    if (!allowed(path, readOnly)) {
      if (setError) VSIError(VSIE_FileError, "access refused");
      errno = EACCES;
      return nullptr;
    }
    return inner_->Open(path, access, setError, options);
  }
  int Stat(const char* path, VSIStatBufL* st, int flags) override {
    if (!allowed(path, true)) {
      errno = ENOENT;
      return -1;
    }
    return inner_->Stat(path, st, flags);
  }
  int Unlink(const char* path) override { return allowed(path, false) ? inner_->Unlink(path) : refuse(); }
  int Mkdir(const char* path, long mode) override { return allowed(path, false) ? inner_->Mkdir(path, mode) : refuse(); }
  int Rmdir(const char* path) override { return allowed(path, false) ? inner_->Rmdir(path) : refuse(); }
  int RmdirRecursive(const char* path) override {
    return allowed(path, false) ? inner_->RmdirRecursive(path) : refuse();
  }
  int Rename(const char* from, const char* to) override {
    return allowed(from, false) && allowed(to, false) ? inner_->Rename(from, to) : refuse();
  }
  char** ReadDirEx(const char* path, int maxFiles) override {
    return allowed(path, true) ? inner_->ReadDirEx(path, maxFiles) : nullptr;
  }
  char** ReadDir(const char* path) override { return ReadDirEx(path, 0); }
  char** SiblingFiles(const char* path) override { return allowed(path, true) ? inner_->SiblingFiles(path) : nullptr; }
  VSIDIR* OpenDir(const char* path, int depth, const char* const* options) override {
    return allowed(path, true) ? inner_->OpenDir(path, depth, options) : nullptr;
  }
  char** GetFileMetadata(const char* path, const char* domain, CSLConstList options) override {
    return allowed(path, true) ? inner_->GetFileMetadata(path, domain, options) : nullptr;
  }
  bool SetFileMetadata(const char* path, CSLConstList md, const char* domain, CSLConstList options) override {
    return allowed(path, false) && inner_->SetFileMetadata(path, md, domain, options);
  }
  int IsCaseSensitive(const char* path) override { return inner_->IsCaseSensitive(path); }
  GIntBig GetDiskFreeSpace(const char* path) override { return inner_->GetDiskFreeSpace(path); }
  int SupportsSparseFiles(const char* path) override { return inner_->SupportsSparseFiles(path); }
  bool IsLocal(const char* path) override { return reach_ != Reach::Network && inner_->IsLocal(path); }
  bool SupportsSequentialWrite(const char* path, bool tmp) override {
    return inner_->SupportsSequentialWrite(path, tmp);
  }
  bool SupportsRandomWrite(const char* path, bool tmp) override { return inner_->SupportsRandomWrite(path, tmp); }
  const char* GetOptions() override { return inner_->GetOptions(); }

 private:
  static int refuse() {
    errno = EACCES;
    return -1;
  }
  bool allowed(const char* path, bool readOnly) const {
    if (reach_ == Reach::Network) {
      if (tlsSandbox) noteRefusedFile(*tlsSandbox, path);
      return false;
    }
    UploadSandbox::State* s = tlsSandbox;
    if (!s) return true;
    if (!path || !*path) return false;  // GDAL probes "" (a warped VRT's name): nothing to note
    bool ok = false;
    if (reach_ == Reach::LocalFiles) {
      const std::string c = canonicalLocal(path ? path : "");
      ok = !c.empty() && ((!s->memory && underDir(c, s->root)) || (readOnly && underDir(c, gdalDataDir)));
    }
    if (!ok) noteRefusedFile(*s, path);
    return ok;
  }

  VSIFilesystemHandler* inner_;  // GDAL's, kept alive by kOriginals (never freed)
  Reach reach_;
};

// GDAL's handlers we wrapped: reachable for the life of the process.
std::vector<VSIFilesystemHandler*>* kOriginals = new std::vector<VSIFilesystemHandler*>();

void guardFilesystems() {
  static const std::vector<std::string> kNetwork{
      "/vsicurl/", "/vsicurl?", "/vsicurl_streaming/", "/vsis3/", "/vsis3_streaming/", "/vsigs/",
      "/vsigs_streaming/", "/vsiaz/", "/vsiaz_streaming/", "/vsiadls/", "/vsioss/",
      "/vsioss_streaming/", "/vsiswift/", "/vsiswift_streaming/", "/vsiwebhdfs/", "/vsihdfs/"};
  VSIFilesystemHandler* local = VSIFileManager::GetHandler("/");
  std::vector<std::string> prefixes;
  char** list = VSIFileManager::GetPrefixes();
  for (char** p = list; p && *p; ++p) prefixes.emplace_back(*p);
  CSLDestroy(list);
  prefixes.push_back("/vsicurl?");  // GetPrefixes leaves it out
  std::map<VSIFilesystemHandler*, GuardedFilesystem*> wrapped;  // one wrapper per handler
  for (const auto& prefix : prefixes) {
    VSIFilesystemHandler* h = VSIFileManager::GetHandler(prefix.c_str());
    if (!h || h == local) continue;
    Reach reach;
    if (std::find(kNetwork.begin(), kNetwork.end(), prefix) != kNetwork.end() || !h->IsLocal(prefix.c_str()))
      reach = Reach::Network;
    else if (prefix == "/vsistdin/")
      reach = Reach::Never;
    else
      continue;
    auto& w = wrapped[h];
    if (!w) {
      kOriginals->push_back(h);
      w = new GuardedFilesystem(h, reach);
    }
    VSIFileManager::InstallHandler(prefix, w);
  }
  kOriginals->push_back(local);
  VSIFileManager::InstallHandler("", new GuardedFilesystem(local, Reach::LocalFiles));
}

// GDAL's HTTP client (WMS, WCS, the HTTP driver, …) answers every request with an error.
CPLHTTPResult* refuseHttp(const char*, CSLConstList, GDALProgressFunc, void*, CPLHTTPFetchWriteFunc,
                          void*, void*) {
  auto* r = static_cast<CPLHTTPResult*>(CPLCalloc(1, sizeof(CPLHTTPResult)));
  r->nStatus = 1;
  r->pszErrBuf = CPLStrdup("network access is off in roverplan");
  return r;
}

struct OriginalOpen {
  GDALDataset* (*open)(GDALOpenInfo*) = nullptr;
  GDALDataset* (*openWithDriver)(GDALDriver*, GDALOpenInfo*) = nullptr;
};
// Filled once in ensureGdal, read-only afterwards.
std::unordered_map<GDALDriver*, OriginalOpen>* kOriginalOpen = new std::unordered_map<GDALDriver*, OriginalOpen>();

// Drivers that fetch from the network by themselves (some with their own HTTP code): refused in
// every open, not only an upload's.
bool networkDriver(const std::string& name) {
  static const std::vector<std::string> kNetworkDrivers{
      "WMS", "WMTS", "WCS", "HTTP", "DAAS", "EEDA", "EEDAI", "PLMOSAIC", "PLSCENES", "OGCAPI",
      "STACTA", "STACIT", "NGW", "WFS", "OAPIF", "CSW", "Elasticsearch", "CouchDB", "Carto",
      "AmigoCloud", "GNMServer", "TileDB"};
  return std::find(kNetworkDrivers.begin(), kNetworkDrivers.end(), name) != kNetworkDrivers.end();
}

// Stands in for the open function of every driver not allowed for uploads: refuses while a
// sandbox is live on the thread (so a dataset nested in an allowed one cannot use it either),
// and always for a network driver.
GDALDataset* gatedOpen(GDALDriver* driver, GDALOpenInfo* info) {
  if (networkDriver(driver->GetDescription())) return nullptr;
  if (UploadSandbox::State* s = tlsSandbox) {
    if (driver->pfnIdentify && driver->pfnIdentify(info) > 0) {
      std::string name = driver->GetDescription();
      if (std::find(s->refusedDrivers.begin(), s->refusedDrivers.end(), name) == s->refusedDrivers.end())
        s->refusedDrivers.push_back(name);
    }
    return nullptr;
  }
  const OriginalOpen& o = kOriginalOpen->at(driver);
  return o.open ? o.open(info) : o.openWithDriver(driver, info);
}

void gateDrivers() {
  const auto& allowed = uploadDrivers();
  GDALDriverManager* dm = GetGDALDriverManager();
  for (int i = 0; i < dm->GetDriverCount(); ++i) {
    GDALDriver* d = dm->GetDriver(i);
    if (std::find(allowed.begin(), allowed.end(), d->GetDescription()) != allowed.end()) continue;
    if (!d->pfnOpen && !d->pfnOpenWithDriverArg) continue;
    (*kOriginalOpen)[d] = {d->pfnOpen, d->pfnOpenWithDriverArg};
    d->pfnOpen = nullptr;
    d->pfnOpenWithDriverArg = gatedOpen;
  }
}

}  // namespace

void installGdalGuards(const std::string& dataDir) {
  gdalDataDir = dataDir;
  guardFilesystems();
  CPLHTTPSetFetchCallback(refuseHttp, nullptr);
  OSRSetPROJEnableNetwork(FALSE);
  gateDrivers();
}

}  // namespace rover::maps::sandbox
