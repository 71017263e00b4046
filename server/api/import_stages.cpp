#include "server/api/import_stages.hpp"

#include <sys/resource.h>

#include <cstdio>
#include <fstream>

namespace rover::api {

namespace {

// This process and its reaped children (the import worker, once it has ended).
double cpuSeconds() {
  auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + t.tv_usec / 1e6; };
  double total = 0;
  for (int who : {RUSAGE_SELF, RUSAGE_CHILDREN}) {
    rusage u{};
    ::getrusage(who, &u);
    total += s(u.ru_utime) + s(u.ru_stime);
  }
  return total;
}

double peakMiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

}  // namespace

ImportStages::ImportStages() : start_(std::chrono::steady_clock::now()), last_(start_), lastCpu_(cpuSeconds()) {}

void ImportStages::done(const char* stage) {
  const auto now = std::chrono::steady_clock::now();
  const double cpu = cpuSeconds();
  stages_.push_back({stage, std::chrono::duration<double>(now - last_).count(), cpu - lastCpu_, peakMiB()});
  last_ = now;
  lastCpu_ = cpu;
}

void ImportStages::note(std::string text) { notes_ += (notes_.empty() ? "" : "; ") + std::move(text); }

std::string ImportStages::line() const {
  std::string out;
  char buf[160];
  for (const Stage& s : stages_) {
    std::snprintf(buf, sizeof buf, "%s %.2f s (cpu %.2f s, peak %.0f MiB), ", s.name.c_str(), s.wall, s.cpu, s.peakMiB);
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "total %.2f s", std::chrono::duration<double>(last_ - start_).count());
  return out + buf + (notes_.empty() ? "" : " (" + notes_ + ")");
}

}  // namespace rover::api
