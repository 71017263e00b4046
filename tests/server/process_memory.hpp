#pragma once
// What the memory tests of the server read about this process (test_mission_peaks.cpp,
// test_memory_returned.cpp): whether it runs under the sanitizers (their shadow memory makes RSS
// figures meaningless, so those tests skip), and fields of /proc/self/status.
#include <cstdint>
#include <fstream>
#include <string>

namespace rover::test {

#ifdef ROVER_SANITIZED
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

// A field of /proc/self/status in bytes ("VmRSS", "VmHWM"); 0 if absent.
inline std::uint64_t statusBytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + ":", 0) == 0) return std::stoull(line.substr(key.size() + 1)) * 1024;
  return 0;
}

}  // namespace rover::test
