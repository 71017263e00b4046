// Fan-out benchmark (issue 14, issue 22 item 2). Three figures, printed, never asserted:
//   frames  PORT MISSION_ID CLIENTS SERVER_PID
//       N Beast clients read one mission stream to its end: frames and bytes delivered per second,
//       the server's peak memory (/proc/PID/status).
//   health  PORT MISSION_ID IDLE READERS SECONDS SERVER_PID
//       IDLE sockets upgrade to the mission's stream and never read a byte, READERS read and discard
//       everything (one epoll thread); meanwhile /api/health is asked on a fresh connection every
//       50 ms for SECONDS: p50/p99/max latency, how many upgrades were answered 101 or 503, how many
//       readers the server dropped, bytes the readers got, the server's RSS.
//   study   PORT STUDY_ID READERS SECONDS
//       runs/s of a running study over SECONDS with no stream reader, then with READERS reading its
//       stream, then with none again (the study's own rate drifts: compare the middle with both ends).
// Raw sockets, not Beast streams, for the load: thousands of clients must cost the client little.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "../server/test_client.hpp"

namespace {

using Clock = std::chrono::steady_clock;

long procKib(int pid, const std::string& key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key + ":", 0) == 0) return std::stol(line.substr(key.size() + 1));
  return -1;
}

int connectLoopback(unsigned short port, int timeoutMs) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  timeval tv{timeoutMs / 1000, (timeoutMs % 1000) * 1000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

bool sendAll(int fd, const std::string& s) {
  for (std::size_t off = 0; off < s.size();) {
    const ssize_t n = ::send(fd, s.data() + off, s.size() - off, MSG_NOSIGNAL);
    if (n <= 0) return false;
    off += static_cast<std::size_t>(n);
  }
  return true;
}

// A WebSocket upgrade request sent on a fresh socket; the answer is left unread.
int openUpgrade(unsigned short port, const std::string& target) {
  const int fd = connectLoopback(port, 10000);
  if (fd < 0) return -1;
  const std::string req = "GET " + target +
                          " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                          "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
  if (!sendAll(fd, req)) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// The status of the upgrade's answer, peeked (the bytes stay unread); 0 when none arrived yet.
int peekStatus(int fd) {
  char b[13] = {};
  const ssize_t n = ::recv(fd, b, 12, MSG_PEEK | MSG_DONTWAIT);
  if (n < 12 || std::strncmp(b, "HTTP/1.1 ", 9) != 0) return 0;
  return std::atoi(b + 9);
}

// GET on a fresh connection, read to EOF; the body ("" on failure) and the wall time.
std::string httpGet(unsigned short port, const std::string& target, double* ms = nullptr) {
  const auto t0 = Clock::now();
  std::string out;
  const int fd = connectLoopback(port, 60000);
  if (fd >= 0) {
    if (sendAll(fd, "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")) {
      char buf[16384];
      for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) out.append(buf, static_cast<std::size_t>(n));
    }
    ::close(fd);
  }
  if (ms) *ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  const auto body = out.find("\r\n\r\n");
  return body == std::string::npos ? std::string() : out.substr(body + 4);
}

// Readers on one epoll thread: read and discard, note each upgrade's status and each close.
class Readers {
 public:
  Readers(unsigned short port, const std::string& target, int n) {
    ep_ = ::epoll_create1(0);
    for (int i = 0; i < n; ++i) {
      const int fd = openUpgrade(port, target);
      if (fd < 0) {
        ++failed_;
        continue;
      }
      ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
      epoll_event ev{};
      ev.events = EPOLLIN;
      ev.data.u32 = static_cast<std::uint32_t>(fds_.size());
      fds_.push_back(fd);
      status_.push_back(0);
      ::epoll_ctl(ep_, EPOLL_CTL_ADD, fd, &ev);
    }
    thread_ = std::thread([this] { loop(); });
  }
  ~Readers() {
    stop_ = true;
    thread_.join();
    for (int fd : fds_)
      if (fd >= 0) ::close(fd);
    ::close(ep_);
  }
  long bytes() const { return bytes_; }
  int closed() const { return closed_; }
  int failed() const { return failed_; }
  int withStatus(int s) const { return static_cast<int>(std::count(status_.begin(), status_.end(), s)); }

 private:
  void loop() {
    std::vector<epoll_event> events(256);
    std::vector<char> buf(1 << 16);
    while (!stop_) {
      const int n = ::epoll_wait(ep_, events.data(), static_cast<int>(events.size()), 50);
      for (int i = 0; i < n; ++i) {
        const std::uint32_t k = events[static_cast<std::size_t>(i)].data.u32;
        const int fd = fds_[k];
        if (fd < 0) continue;
        for (;;) {
          const ssize_t got = ::recv(fd, buf.data(), buf.size(), 0);
          if (got > 0) {
            if (status_[k] == 0 && got >= 12 && std::strncmp(buf.data(), "HTTP/1.1 ", 9) == 0)
              status_[k] = std::atoi(buf.data() + 9);
            bytes_ += got;
            continue;
          }
          if (got < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
          ::epoll_ctl(ep_, EPOLL_CTL_DEL, fd, nullptr);
          ::close(fd);
          fds_[k] = -1;
          ++closed_;
          break;
        }
      }
    }
  }
  int ep_ = -1;
  std::vector<int> fds_;
  std::vector<int> status_;  // written by the loop; read after it is joined or as an estimate
  std::atomic<long> bytes_{0};
  std::atomic<int> closed_{0};
  int failed_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

void raiseFdLimit() {
  rlimit rl{};
  ::getrlimit(RLIMIT_NOFILE, &rl);
  rl.rlim_cur = rl.rlim_max;
  ::setrlimit(RLIMIT_NOFILE, &rl);
}

int frames(unsigned short port, const std::string& missionId, int clients, int pid) {
  const std::string target = "/api/missions/" + missionId + "/stream";
  std::atomic<long> frameCount{0}, bytes{0}, done{0};
  std::atomic<long> peakRss{0};
  std::atomic<bool> sampling{true};
  std::thread sampler([&] {
    while (sampling) {
      peakRss = std::max(peakRss.load(), procKib(pid, "VmRSS"));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  auto t0 = Clock::now();
  std::vector<std::thread> threads;
  for (int i = 0; i < clients; ++i)
    threads.emplace_back([&] {
      auto f = rover::test::readAllFrames(port, target, std::chrono::seconds(120));
      frameCount += static_cast<long>(f.size());
      for (const auto& x : f) bytes += static_cast<long>(x.data.size());
      if (!f.empty() && f.back().data.find("\"type\":\"done\"") != std::string::npos) ++done;
    });
  for (auto& t : threads) t.join();
  double secs = std::chrono::duration<double>(Clock::now() - t0).count();
  sampling = false;
  sampler.join();
  std::cout << "clients                 " << clients << " (" << done << " saw the final done frame)\n"
            << "wall                    " << secs << " s\n"
            << "frames delivered        " << frameCount << "  (" << frameCount / secs << " frames/s in total, "
            << frameCount / secs / clients << " per client)\n"
            << "bytes delivered         " << bytes / 1048576.0 << " MiB  (" << bytes / secs / 1048576.0 << " MiB/s)\n"
            << "server RSS peak/now     " << peakRss / 1024.0 << " / " << procKib(pid, "VmRSS") / 1024.0 << " MiB"
            << " (VmHWM " << procKib(pid, "VmHWM") / 1024.0 << " MiB)\n";
  return done == clients ? 0 : 1;
}

int health(unsigned short port, const std::string& missionId, int idle, int readers, double seconds, int pid) {
  raiseFdLimit();
  const std::string target = "/api/missions/" + missionId + "/stream";
  const auto t0 = Clock::now();
  std::vector<int> idleFds;
  for (int i = 0; i < idle; ++i)
    if (const int fd = openUpgrade(port, target); fd >= 0) idleFds.push_back(fd);
  const double openIdle = std::chrono::duration<double>(Clock::now() - t0).count();
  Readers reading(port, target, readers);
  const double openAll = std::chrono::duration<double>(Clock::now() - t0).count();

  std::vector<double> lat;
  int failed = 0;
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  long rssPeak = 0;
  while (Clock::now() < end) {
    double ms = 0;
    const std::string body = httpGet(port, "/api/health", &ms);
    if (body.find("ok") == std::string::npos) ++failed;
    lat.push_back(ms);
    rssPeak = std::max(rssPeak, procKib(pid, "VmRSS"));
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  int idle101 = 0, idle503 = 0, idleNone = 0;
  for (int fd : idleFds) {
    const int s = peekStatus(fd);
    idle101 += s == 101;
    idle503 += s == 503;
    idleNone += s == 0;
  }
  std::cout << std::fixed << std::setprecision(1)
            << "sockets                 " << idleFds.size() << " never reading (opened in " << openIdle << " s), "
            << readers << " reading (all open after " << openAll << " s)\n"
            << "never-reading upgrades  " << idle101 << " x 101, " << idle503 << " x 503, " << idleNone
            << " unanswered\n"
            << "reading upgrades        " << reading.withStatus(101) << " x 101, " << reading.withStatus(503)
            << " x 503; " << reading.closed() << " closed by the server, " << reading.failed()
            << " could not connect; " << reading.bytes() / 1048576.0 << " MiB read\n"
            << "/api/health             " << lat.size() << " asks in " << seconds << " s: p50 "
            << percentile(lat, 0.5) << " ms, p99 " << percentile(lat, 0.99) << " ms, max "
            << (lat.empty() ? 0 : *std::max_element(lat.begin(), lat.end())) << " ms, " << failed << " failed\n"
            << "server RSS peak         " << rssPeak / 1024.0 << " MiB\n";
  for (int fd : idleFds) ::close(fd);
  return 0;
}

// runs_done of the study, from the listing (GET /api/studies/{id} computes the summary).
long runsDone(unsigned short port, const std::string& id) {
  const auto j = nlohmann::json::parse(httpGet(port, "/api/studies"), nullptr, false);
  if (!j.is_array()) return -1;
  for (const auto& s : j)
    if (s.value("id", "") == id) return s.value("runs_done", -1L);
  return -1;
}

int study(unsigned short port, const std::string& id, int readers, double seconds) {
  raiseFdLimit();
  const auto rate = [&] {
    const long a = runsDone(port, id);
    const auto t0 = Clock::now();
    std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
    const long b = runsDone(port, id);
    return static_cast<double>(b - a) / std::chrono::duration<double>(Clock::now() - t0).count();
  };
  const double before = rate();
  double with = 0;
  long got = 0;
  int ok = 0;
  {
    Readers reading(port, "/api/studies/" + id + "/stream", readers);
    with = rate();
    got = reading.bytes();
    ok = reading.withStatus(101);
  }
  const double after = rate();
  std::cout << std::fixed << std::setprecision(0) << "study runs/s            " << before << " with no reader, "
            << with << " with " << readers << " readers (" << ok << " upgraded, " << got / 1024 << " KiB read), "
            << after << " with none again: " << std::setprecision(1)
            << 100.0 * (with / ((before + after) / 2) - 1) << " % vs the mean of both ends\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  try {
    if (mode == "frames" && argc == 6)
      return frames(static_cast<unsigned short>(std::stoi(argv[2])), argv[3], std::stoi(argv[4]), std::stoi(argv[5]));
    if (mode == "health" && argc == 8)
      return health(static_cast<unsigned short>(std::stoi(argv[2])), argv[3], std::stoi(argv[4]), std::stoi(argv[5]),
                    std::stod(argv[6]), std::stoi(argv[7]));
    if (mode == "study" && argc == 6)
      return study(static_cast<unsigned short>(std::stoi(argv[2])), argv[3], std::stoi(argv[4]), std::stod(argv[5]));
  } catch (const std::exception& e) {
    std::cerr << "bench_ws_fanout: " << e.what() << "\n";
    return 1;
  }
  std::cerr << "usage: bench_ws_fanout frames PORT MISSION_ID CLIENTS SERVER_PID\n"
               "       bench_ws_fanout health PORT MISSION_ID IDLE READERS SECONDS SERVER_PID\n"
               "       bench_ws_fanout study PORT STUDY_ID READERS SECONDS\n";
  return 2;
}
