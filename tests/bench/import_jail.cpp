// Benchmark (issue 22): what the import jail costs. The same upload read R times in this process
// (the old path: maps::loadDem under an UploadSandbox, as the server did before) and R times by a
// jailed worker (runJailed + readWorkerResult, as the server does now), alternated; prints the
// wall times, the ratio, this process's peak RSS over its baseline for each path, and the workers'
// peak RSS.
//   bench_import_jail FILE [FILE…] [--repeat R]     (the files of one upload, e.g. a .LBL and .IMG)
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "maps/dem_io.hpp"
#include "maps/gdal_env.hpp"
#include "server/jail/import_jail.hpp"
#include "server/jail/import_worker.hpp"
#include "server/jail/worker_output.hpp"

using namespace rover;
namespace fs = std::filesystem;

namespace {

// VmHWM (peak resident set) of this process, in MiB.
double peakRssMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

void resetPeakRss() { std::ofstream("/proc/self/clear_refs") << "5"; }

double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "import-worker")
    return jail::importWorkerMain(std::vector<std::string>(argv + 2, argv + argc));
  std::vector<std::string> files;
  int repeat = 5;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    else files.push_back(argv[i]);
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: bench_import_jail FILE [FILE...] [--repeat R]\n");
    return 2;
  }
  const fs::path work = fs::temp_directory_path() / ("roverplan-bench-jail-" + std::to_string(::getpid()));
  const fs::path in = work / "in", out = work / "out";
  fs::create_directories(in);
  std::vector<std::string> names;
  for (const auto& f : files) {
    fs::copy_file(f, in / fs::path(f).filename(), fs::copy_options::overwrite_existing);
    names.push_back(fs::path(f).filename().string());
  }
  // The raster GDAL opens: a PDS3 label first, else the first file.
  std::string raster = names[0];
  for (const auto& n : names)
    if (fs::path(n).extension() == ".LBL" || fs::path(n).extension() == ".lbl") raster = n;
  maps::ensureGdal();
  std::printf("upload: %s; isolation: %s\n", raster.c_str(), jail::isolationInWords(jail::isolation()).c_str());

  jail::JailConfig config;
  config.limits.memoryBytes = 4ull << 30;
  double inProcess = 0, jailed = 0, rssIn = 0, rssJail = 0;
  int rows = 0, cols = 0;
  for (int k = 0; k < repeat; ++k) {
    {
      resetPeakRss();
      const double base = peakRssMiB();
      const auto t0 = std::chrono::steady_clock::now();
      maps::UploadSandbox sandbox(in.string());
      maps::LoadOptions o;
      o.upload = &sandbox;
      o.maxCells = 50'000'000;
      const maps::LoadedDem d = maps::loadDem((in / raster).string(), o);
      inProcess += seconds(t0);
      rssIn = std::max(rssIn, peakRssMiB() - base);
      rows = d.dem.geometry().rows;
      cols = d.dem.geometry().cols;
    }
    {
      resetPeakRss();
      const double base = peakRssMiB();
      const auto t0 = std::chrono::steady_clock::now();
      fs::remove_all(out);
      fs::create_directories(out);
      jail::ImportRequest req;
      req.sources = names;
      req.load.maxCells = 50'000'000;
      jail::writeImportRequest(out.string(), req);
      const jail::JailRun run = jail::runJailed(config, in.string(), out.string());
      if (run.end != jail::JailRun::End::Exited || run.exitStatus != 0) {
        std::fprintf(stderr, "the worker failed (end %d, status %d, signal %d)\n", static_cast<int>(run.end),
                     run.exitStatus, run.signal);
        return 1;
      }
      const jail::WorkerResult r = jail::readWorkerResult(out.string(), 50'000'000);
      jailed += seconds(t0);
      rssJail = std::max(rssJail, peakRssMiB() - base);
    }
  }
  struct rusage children {};
  getrusage(RUSAGE_CHILDREN, &children);
  std::printf("grid              %d x %d cells (%.1f MiB of float32)\n", rows, cols, rows * 4.0 * cols / 1048576);
  std::printf("%-28s %10s %22s\n", "path (mean of runs)", "wall ms", "this process +MiB RSS");
  std::printf("%-28s %10.1f %22.1f\n", "in-process (before)", 1000 * inProcess / repeat, rssIn);
  std::printf("%-28s %10.1f %22.1f\n", "jailed worker (after)", 1000 * jailed / repeat, rssJail);
  std::printf("ratio jailed / in-process  x%.2f over %d alternated runs\n", jailed / inProcess, repeat);
  std::printf("worker peak RSS            %.1f MiB\n", children.ru_maxrss / 1024.0);
  fs::remove_all(work);
  return 0;
}
