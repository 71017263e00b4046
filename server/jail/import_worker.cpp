#include "server/jail/import_worker.hpp"

#include <cpl_error.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <malloc.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <new>

#include "core/common/error.hpp"
#include "maps/gdal_env.hpp"
#include "server/http/http_types.hpp"
#include "server/jail/worker_output.hpp"

namespace rover::jail {

namespace fs = std::filesystem;
using http::ApiError;

namespace {

constexpr std::size_t kMaxArchiveMembers = 100;  // files a zip or tar upload may hold

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// The file GDAL should open among the ones given (all under the live sandbox): a PDS3 label
// first, then any raster, sidecars last (a PDS4 .xml label). A file refused for what it is or
// where it reads (a VRT, a label pointing outside the upload) refuses the whole upload.
std::string pickRaster(const std::vector<std::string>& candidates, const maps::UploadSandbox& sandbox) {
  auto opens = [&](const std::string& c) {
    std::string refusal;
    maps::Dataset ds = maps::openUpload(c, sandbox, refusal);
    if (!refusal.empty()) throw ApiError(400, "refused_file", refusal, "file");
    return ds && GDALGetRasterCount(ds.get()) > 0;
  };
  auto ext = [](const std::string& c) { return lower(fs::path(c).extension().string()); };
  for (const auto& c : candidates)
    if (ext(c) == ".lbl" && opens(c)) return c;
  for (const auto& c : candidates) {
    const std::string e = ext(c);
    if (e == ".hdr" || e == ".xml" || e == ".aux" || e == ".txt" || e == ".prj" || e == ".lbl") continue;
    if (opens(c)) return c;
  }
  for (const auto& c : candidates)  // PDS4 (.xml labels) and anything else GDAL opens
    if (opens(c)) return c;
  return "";
}

// "/vsizip/" or "/vsitar/" for an archive upload, "" otherwise.
std::string archivePrefix(const std::string& fname) {
  const std::string n = lower(fname);
  auto ends = [&](const std::string& e) { return n.size() > e.size() && n.compare(n.size() - e.size(), e.size(), e) == 0; };
  if (ends(".zip")) return "/vsizip/";
  if (ends(".tar") || ends(".tgz") || ends(".tar.gz")) return "/vsitar/";
  return "";
}

std::vector<std::string> archiveMembers(const std::string& prefix, const std::string& archivePath,
                                        const std::string& shownName) {
  std::vector<std::string> out;
  const std::string root = prefix + archivePath;
  char** list = VSIReadDirRecursive(root.c_str());
  for (char** p = list; p && *p; ++p) {
    std::string member = root + "/" + *p;
    VSIStatBufL st;
    if (VSIStatL(member.c_str(), &st) == 0 && !VSI_ISDIR(st.st_mode)) out.push_back(member);
  }
  CSLDestroy(list);
  if (out.size() > kMaxArchiveMembers)
    throw ApiError(400, "invalid_dem", shownName + ": the archive holds " + std::to_string(out.size()) +
                   " files, more than the " + std::to_string(kMaxArchiveMembers) + " an upload may hold", "file");
  if (out.empty()) throw ApiError(400, "invalid_dem", shownName + ": not a readable archive, or an empty one", "file");
  std::sort(out.begin(), out.end());
  return out;
}

// A map upload: the raster among the files (also inside zips and tars), read with the options.
maps::LoadedDem readDemUpload(const std::string& in, const ImportRequest& req, const maps::UploadSandbox& sandbox,
                              std::string& rasterName) {
  std::vector<std::string> candidates;
  for (const auto& fname : req.sources) {
    const std::string target = (fs::path(in) / fname).string();
    const std::string prefix = archivePrefix(fname);
    if (prefix.empty()) {
      candidates.push_back(target);
      continue;
    }
    auto members = archiveMembers(prefix, target, fname);
    candidates.insert(candidates.end(), members.begin(), members.end());
  }
  const std::string raster = pickRaster(candidates, sandbox);
  if (raster.empty()) {
    // One file we cannot read: say why in words (a lone PDS3 .IMG, a damaged GeoTIFF).
    if (candidates.size() == 1) {
      maps::LoadOptions probe;
      probe.upload = &sandbox;
      try {
        maps::loadDem(candidates[0], probe);
      } catch (const Error& e) {
        throw ApiError(400, "invalid_dem", e.what(), e.field().rfind("geotransform", 0) == 0 ? e.field() : "file");
      }
    }
    throw ApiError(400, "invalid_dem",
                   "no raster roverplan reads in the upload (" + std::to_string(candidates.size()) +
                       " file(s); accepted: " + maps::uploadFormatsInWords() + ")",
                   "file");
  }
  maps::LoadOptions o = req.load;
  o.upload = &sandbox;
  maps::LoadedDem d;
  try {
    d = maps::loadDem(raster, o);
  } catch (const Error& e) {
    const bool tooLarge = e.field() == "max_cells";
    throw ApiError(400, tooLarge ? "too_large" : "invalid_dem", e.what(), tooLarge ? "file" : e.field());
  }
  rasterName = sandbox.uploadName(raster);
  return d;
}

// A PDM raster: the one file, warped onto the map's window.
maps::LoadedDem readPdmRaster(const std::string& in, const ImportRequest& req, const maps::UploadSandbox& sandbox,
                              std::string& rasterName) {
  if (req.sources.size() != 1) throw ApiError(400, "invalid_pdm", "a PDM raster is one file", "file");
  const std::string staged = (fs::path(in) / req.sources[0]).string();
  maps::LoadOptions o = req.load;
  o.upload = &sandbox;
  try {
    maps::LoadedDem d = maps::loadDem(staged, o);
    rasterName = req.sources[0];
    return d;
  } catch (const Error& e) {
    std::string msg = e.what();
    if (msg.rfind(req.sources[0], 0) == 0) msg = "PDM raster" + msg.substr(req.sources[0].size());
    throw ApiError(400, "invalid_pdm", msg, e.field().rfind("geotransform", 0) == 0 ? e.field() : "file");
  }
}

bool outOfMemory() { return CPLGetLastErrorNo() == CPLE_OutOfMemory || maps::gdalRanOutOfMemory(); }

WorkerError memoryError(const ImportRequest& req) {
  return {413, "too_large",
          std::string(req.kind == "pdm" ? "the PDM raster" : "the file") +
              " needs more memory to read than an import may use; upload a smaller or cropped raster",
          "file"};
}

}  // namespace

int importWorkerMain(const std::vector<std::string>& args) {
  if (args.size() == 1 && args[0] == "--probe") return 0;
  if (args.size() != 2) {
    std::cerr << "usage: roverplan import-worker IN OUT (run by the server, not by hand)\n";
    return 2;
  }
  // A few malloc arenas, not 8 a core: each reserves 64 MiB of the address space RLIMIT_AS bounds.
  mallopt(M_ARENA_MAX, 2);
  const std::string in = args[0], out = args[1];
  ImportRequest req;
  try {
    req = readImportRequest(out);
  } catch (const std::exception& e) {
    std::cerr << "import-worker: " << e.what() << "\n";
    return 2;
  }
  try {
    std::string rasterName;
    maps::LoadedDem d;
    {
      // Everything GDAL reads from here on must be one of the uploaded files (issue 14), in the
      // jail too: the sandbox also holds the driver allow-list.
      maps::UploadSandbox sandbox(in, req.allowHdf5);
      d = req.kind == "pdm" ? readPdmRaster(in, req, sandbox, rasterName) : readDemUpload(in, req, sandbox, rasterName);
    }
    writeWorkerResult(out, d, rasterName);
    return 0;
  } catch (const std::bad_alloc&) {
    writeWorkerError(out, memoryError(req));
  } catch (const ApiError& e) {
    if (outOfMemory()) writeWorkerError(out, memoryError(req));
    else writeWorkerError(out, {e.status(), e.code(), e.what(), e.field()});
  } catch (const std::exception& e) {
    // Not the client's fault that we know of: the server logs it and answers 400 without it.
    std::cerr << "import-worker: " << e.what() << "\n";
    return 3;
  }
  return 1;
}

}  // namespace rover::jail
