#include "server/jail/import_jail.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <thread>

namespace rover::jail {

namespace fs = std::filesystem;

namespace {

// Where bubblewrap lives on Debian (package `bubblewrap`); "" when it is not installed.
std::string findBwrap() {
  for (const char* p : {"/usr/bin/bwrap", "/bin/bwrap", "/usr/local/bin/bwrap"})
    if (::access(p, X_OK) == 0) return p;
  return "";
}

// What the worker process does between fork and exec: only async-signal-safe calls (the server
// is multithreaded, so the child must not allocate or lock).
struct ChildSetup {
  JailLimits limits;
  int unshareFlags = 0;  // the namespaces isolation: CLONE_NEWUSER | CLONE_NEWNET, or CLONE_NEWNET
  int logFd = -1;        // stdout and stderr of the worker (a file in OUT), or -1 for /dev/null
  int devNull = -1;
  int maxFd = 1024;      // the close loop's bound when close_range is missing
};

[[noreturn]] void childMain(const ChildSetup& s, char* const* argv) {
  ::setpgid(0, 0);  // its own process group: the deadline kills the whole group
  ::dup2(s.devNull, 0);
  ::dup2(s.logFd >= 0 ? s.logFd : s.devNull, 1);
  ::dup2(s.logFd >= 0 ? s.logFd : s.devNull, 2);
  // Nothing of the server's reaches the worker: no socket, no database, no upload in flight.
#ifdef SYS_close_range
  if (::syscall(SYS_close_range, 3u, ~0u, 0u) != 0)
#endif
    for (int fd = 3; fd < s.maxFd; ++fd) ::close(fd);
  auto limit = [](int resource, rlim_t soft, rlim_t hard) {
    struct rlimit r {soft, hard};
    ::setrlimit(resource, &r);
  };
  if (kAddressSpaceLimited) limit(RLIMIT_AS, s.limits.memoryBytes, s.limits.memoryBytes);
  limit(RLIMIT_CPU, s.limits.cpuSeconds, s.limits.cpuSeconds + 5);  // SIGXCPU first, SIGKILL 5 s later
  limit(RLIMIT_FSIZE, s.limits.fileBytes, s.limits.fileBytes);
  limit(RLIMIT_CORE, 0, 0);  // a crash leaves no core file of a client's data behind
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // the worker dies with the server
  ::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0);
  if (s.unshareFlags && ::unshare(s.unshareFlags) != 0) ::_exit(126);  // never run with less than probed
  // The server blocks SIGINT/SIGTERM for its sigwait: the worker must take them normally.
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  ::execv(argv[0], argv);
  ::_exit(127);
}

// Forks `argv` with `setup`; -1 when fork fails.
pid_t spawn(const std::vector<std::string>& args, const ChildSetup& setup) {
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) childMain(setup, argv.data());
  return pid;
}

// Waits for `pid` until `deadlineSeconds` have passed; then kills its process group and it, and
// reaps it. Returns the wait status, or nullopt-like `timedOut` = true.
int waitWithDeadline(pid_t pid, double deadlineSeconds, bool& timedOut) {
  timedOut = false;
  int status = 0;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(deadlineSeconds);
  // A pidfd turns "the child ended" into a poll event: no polling loop (Linux 5.3).
  const int pidfd = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
  for (;;) {
    const pid_t w = ::waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) break;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timedOut = true;
      ::kill(-pid, SIGKILL);
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      break;
    }
    if (pidfd >= 0) {
      struct pollfd p {pidfd, POLLIN, 0};
      ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 60'000)));
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::min<long long>(left.count(), 10)));
    }
  }
  if (pidfd >= 0) ::close(pidfd);
  return status;
}

// bwrap's arguments for a worker: a root of its own with the system read-only, IN and OUT.
// `proc`: a /proc of the sandbox's own PID namespace. Inside a container (podman, docker) the
// kernel refuses a new proc mount under the runtime's masked /proc; the worker then goes without
// one (GDAL only reads its memory figures there).
std::vector<std::string> bwrapCommand(const std::string& bwrap, const std::vector<std::string>& worker,
                                      const std::string& in, const std::string& out, bool proc) {
  std::vector<std::string> a{bwrap, "--unshare-all", "--die-with-parent", "--new-session", "--ro-bind", "/usr", "/usr"};
  // Merged-/usr systems link /lib, /bin… into /usr; others get them bound read-only.
  for (const char* top : {"/lib", "/lib64", "/lib32", "/libx32", "/bin", "/sbin"}) {
    std::error_code ec;
    if (fs::is_symlink(top, ec)) {
      a.insert(a.end(), {"--symlink", fs::read_symlink(top, ec).string(), top});
    } else if (fs::is_directory(top, ec)) {
      a.insert(a.end(), {"--ro-bind", top, top});
    }
  }
  // The dynamic loader's cache (Debian's multiarch libraries are found through it), the
  // alternatives some libraries are linked through (libblas.so.3 -> /etc/alternatives/…), and the
  // worker binary itself when it is not under /usr (a build tree).
  a.insert(a.end(), {"--ro-bind-try", "/etc/ld.so.cache", "/etc/ld.so.cache", "--ro-bind-try", "/etc/alternatives",
                     "/etc/alternatives"});
  if (!worker.empty() && worker[0].rfind("/usr/", 0) != 0) a.insert(a.end(), {"--ro-bind", worker[0], worker[0]});
  if (proc) a.insert(a.end(), {"--proc", "/proc"});
  a.insert(a.end(), {"--dev", "/dev"});
  if (!in.empty()) a.insert(a.end(), {"--ro-bind", in, "/in"});
  if (!out.empty()) a.insert(a.end(), {"--bind", out, "/out", "--chdir", "/out"});
  a.insert(a.end(), {"--remount-ro", "/", "--clearenv", "--setenv", "PATH", "/usr/bin:/bin", "--setenv", "HOME", "/out",
                     "--setenv", "TMPDIR", "/out", "--"});
  a.insert(a.end(), worker.begin(), worker.end());
  if (!in.empty()) a.insert(a.end(), {"/in", "/out"});
  return a;
}

std::vector<std::string> defaultWorker() { return {selfExecutable(), "import-worker"}; }

ChildSetup baseSetup(const JailLimits& limits) {
  ChildSetup s;
  s.limits = limits;
  struct rlimit r {};
  if (::getrlimit(RLIMIT_NOFILE, &r) == 0) s.maxFd = static_cast<int>(std::min<rlim_t>(r.rlim_cur, 1 << 16));
  return s;
}

struct Probe {
  Isolation isolation = Isolation::Rlimits;
  std::string bwrap;
  bool proc = true;  // bubblewrap: whether the sandbox gets its own /proc
  int unshareFlags = 0;
};

// Whether `args` runs to exit status 0 within a few seconds under `setup`.
bool runsCleanly(const std::vector<std::string>& args, ChildSetup setup) {
  setup.devNull = ::open("/dev/null", O_RDWR | O_CLOEXEC);
  const pid_t pid = spawn(args, setup);
  if (setup.devNull >= 0) ::close(setup.devNull);
  if (pid < 0) return false;
  bool timedOut = false;
  const int status = waitWithDeadline(pid, 20, timedOut);
  return !timedOut && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

const Probe& probe() {
  static Probe p;
  static std::once_flag once;
  std::call_once(once, [] {
    JailLimits l;
    ChildSetup s = baseSetup(l);
    std::vector<std::string> probeWorker = defaultWorker();
    probeWorker.push_back("--probe");
    if (const std::string b = findBwrap(); !b.empty() && !probeWorker[0].empty())
      for (bool proc : {true, false})
        if (runsCleanly(bwrapCommand(b, probeWorker, "", "", proc), s)) {
          p.isolation = Isolation::Bubblewrap;
          p.bwrap = b;
          p.proc = proc;
          return;
        }
    for (int flags : {CLONE_NEWUSER | CLONE_NEWNET, CLONE_NEWNET}) {
      ChildSetup u = s;
      u.unshareFlags = flags;
      if (runsCleanly({"/bin/true"}, u)) {
        p.isolation = Isolation::Namespaces;
        p.unshareFlags = flags;
        return;
      }
    }
  });
  return p;
}

}  // namespace

std::string selfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? "" : p.string();
}

Isolation isolation() { return probe().isolation; }

std::string isolationInWords(Isolation i) {
  switch (i) {
    case Isolation::Bubblewrap:
      return "bubblewrap (no network, sees only its upload; rlimits and a deadline)";
    case Isolation::Namespaces:
      return "namespaces without bubblewrap (no network; rlimits and a deadline; files confined by "
             "GDAL's guards only, so netCDF-4/HDF5 is refused)";
    case Isolation::Rlimits:
      break;
  }
  return "a separate process with rlimits and a deadline only (no namespace could be made here; "
         "netCDF-4/HDF5 is refused)";
}

JailRun runJailed(const JailConfig& config, const std::string& inDir, const std::string& outDir) {
  const Probe& p = probe();
  std::vector<std::string> worker = config.worker.empty() ? defaultWorker() : config.worker;
  JailRun run;
  if (worker.empty() || worker[0].empty()) {
    run.detail = "the worker executable is unknown";
    return run;
  }
  ChildSetup setup = baseSetup(config.limits);
  std::vector<std::string> args;
  if (p.isolation == Isolation::Bubblewrap) {
    args = bwrapCommand(p.bwrap, worker, inDir, outDir, p.proc);
  } else {
    args = worker;
    args.insert(args.end(), {inDir, outDir});
    setup.unshareFlags = p.unshareFlags;
  }
  setup.devNull = ::open("/dev/null", O_RDWR | O_CLOEXEC);
  setup.logFd = ::open((fs::path(outDir) / "worker.log").c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  const pid_t pid = spawn(args, setup);
  if (setup.devNull >= 0) ::close(setup.devNull);
  if (setup.logFd >= 0) ::close(setup.logFd);
  if (pid < 0) {
    run.detail = std::string("fork failed: ") + std::strerror(errno);
    return run;
  }
  bool timedOut = false;
  const int status = waitWithDeadline(pid, config.limits.deadlineSeconds, timedOut);
  if (timedOut) {
    run.end = JailRun::End::DeadlinePassed;
  } else if (WIFSIGNALED(status)) {
    run.end = JailRun::End::Signalled;
    run.signal = WTERMSIG(status);
  } else if (p.isolation == Isolation::Bubblewrap && WEXITSTATUS(status) > 128) {
    // bwrap reports a child ended by signal N as exit status 128 + N (the worker itself only
    // exits 0, 1 or 2).
    run.end = JailRun::End::Signalled;
    run.signal = WEXITSTATUS(status) - 128;
  } else {
    run.end = JailRun::End::Exited;
    run.exitStatus = WEXITSTATUS(status);
  }
  return run;
}

}  // namespace rover::jail
