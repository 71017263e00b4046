#pragma once
// The jail an untrusted file is parsed in (issue 22). GDAL reads dozens of formats in C and C++;
// one bad file in one of them may crash, hang or exhaust the process that reads it. So the server
// never reads a client's raster itself: it starts `roverplan import-worker IN OUT` (this same
// executable) in a process it can lose, and reads back only what the worker wrote into OUT, as
// plain numbers it checks (server/jail/worker_output.hpp).
//
// The worker runs under the strongest isolation this machine allows, probed once per process:
//   bubblewrap  `bwrap --unshare-all`: new user, mount, PID, IPC, UTS and network namespaces (no
//               network at all, only loopback); a root with /usr and the dynamic loader's cache
//               read-only, IN read-only at /in, OUT read-write at /out and nothing else of the host
//               (no data dir, no /home, no /tmp); no new privileges; killed with the server.
//   namespaces  without bwrap (or where it cannot run): fork, then unshare a new user + network
//               namespace (no network) before exec; files are confined only by GDAL's own guards
//               (maps::UploadSandbox), so netCDF-4/HDF5 stays refused (libhdf5 opens files itself).
//   rlimits     where no namespace can be made: limits and the deadline only, netCDF-4 refused.
// Whatever the isolation, the worker gets rlimits (RLIMIT_AS memory, RLIMIT_CPU, RLIMIT_FSIZE,
// no core files) and a wall-clock deadline after which it is killed (SIGKILL). `serve` says at start
// which isolation is active.
#include <cstdint>
#include <string>
#include <vector>

namespace rover::jail {

// AddressSanitizer reserves terabytes of shadow address space at start, so a sanitizer build's
// worker cannot run under RLIMIT_AS at all: there the memory limit is not set (CPU, file size and the
// deadline still are). Release builds, the ones `serve` runs, always set it.
// ROVER_SANITIZED is defined by CMake for the sanitizer and fuzz builds.
#ifdef ROVER_SANITIZED
inline constexpr bool kAddressSpaceLimited = false;
#else
inline constexpr bool kAddressSpaceLimited = true;
#endif

enum class Isolation { Bubblewrap, Namespaces, Rlimits };

// The isolation workers get in this process: probed on first use (a `bwrap ... true`, then an
// unshare in a forked child), then fixed.
Isolation isolation();
// "bubblewrap (…)" — one line for the server log.
std::string isolationInWords(Isolation i);

struct JailLimits {
  std::uint64_t memoryBytes = 2ull << 30;  // RLIMIT_AS: address space, so a memory bomb fails to allocate
  unsigned cpuSeconds = 600;               // RLIMIT_CPU, all threads together (SIGXCPU, then SIGKILL)
  std::uint64_t fileBytes = 1ull << 30;    // RLIMIT_FSIZE: the largest file it may write (SIGXFSZ)
  double deadlineSeconds = 300;            // wall clock, then SIGKILL
};

struct JailConfig {
  // The worker's command before its IN and OUT arguments; empty = this executable's
  // `import-worker`. Tests put a program here that crashes or hangs like a broken GDAL would.
  std::vector<std::string> worker;
  JailLimits limits;
};

// How a worker ended.
struct JailRun {
  enum class End { Exited, Signalled, DeadlinePassed, NotStarted };
  End end = End::NotStarted;
  int exitStatus = 0;   // Exited
  int signal = 0;       // Signalled: the signal that ended the worker (SIGSEGV, SIGKILL, SIGXCPU, …)
  std::string detail;   // NotStarted: why, for the server log
};

// Runs the worker on IN (the client's files, read-only) and OUT (an empty folder it writes to);
// returns when it ends or its deadline has passed (it is then killed and reaped). Thread-safe.
JailRun runJailed(const JailConfig& config, const std::string& inDir, const std::string& outDir);

// This executable's own path (/proc/self/exe), "" when unknown.
std::string selfExecutable();

}  // namespace rover::jail
