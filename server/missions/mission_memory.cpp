#include "server/missions/mission_memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace rover::missions {

std::uint64_t defaultMissionMemoryBudget() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return 4ull << 30;
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(pageSize) / 2;
}

std::string formatBytes(std::uint64_t bytes) {
  char buf[32];
  if (bytes >= (10ull << 40))
    std::snprintf(buf, sizeof buf, "%.0f TiB", static_cast<double>(bytes) / (1ull << 40));
  else if (bytes >= (10ull << 30))
    std::snprintf(buf, sizeof buf, "%.0f GiB", static_cast<double>(bytes) / (1ull << 30));
  else if (bytes >= (1ull << 30))
    std::snprintf(buf, sizeof buf, "%.1f GiB", static_cast<double>(bytes) / (1ull << 30));
  else
    std::snprintf(buf, sizeof buf, "%.0f MiB", std::max(1.0, static_cast<double>(bytes) / (1ull << 20)));
  return buf;
}

}  // namespace rover::missions
