// Fan-out benchmark (issue: server): N WebSocket clients on one mission stream; prints frames and
// bytes delivered per second over the whole run and the server's memory (from /proc/PID/status).
//   bench_ws_fanout PORT MISSION_ID CLIENTS SERVER_PID
#include <atomic>
#include <chrono>
#include <fstream>
#include <iostream>
#include <thread>
#include <vector>

#include "../server/test_client.hpp"

namespace {
long procKib(int pid, const std::string& key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key + ":", 0) == 0) return std::stol(line.substr(key.size() + 1));
  return -1;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: bench_ws_fanout PORT MISSION_ID CLIENTS SERVER_PID\n";
    return 2;
  }
  const auto port = static_cast<unsigned short>(std::stoi(argv[1]));
  const std::string target = std::string("/api/missions/") + argv[2] + "/stream";
  const int clients = std::stoi(argv[3]), pid = std::stoi(argv[4]);
  std::atomic<long> frames{0}, bytes{0}, done{0};
  std::atomic<long> peakRss{0};
  std::atomic<bool> sampling{true};
  std::thread sampler([&] {
    while (sampling) {
      peakRss = std::max(peakRss.load(), procKib(pid, "VmRSS"));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::thread> threads;
  for (int i = 0; i < clients; ++i)
    threads.emplace_back([&] {
      auto f = rover::test::readAllFrames(port, target, std::chrono::seconds(120));
      frames += static_cast<long>(f.size());
      for (const auto& x : f) bytes += static_cast<long>(x.data.size());
      if (!f.empty() && f.back().data.find("\"type\":\"done\"") != std::string::npos) ++done;
    });
  for (auto& t : threads) t.join();
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  sampling = false;
  sampler.join();
  std::cout << "clients                 " << clients << " (" << done << " saw the final done frame)\n"
            << "wall                    " << secs << " s\n"
            << "frames delivered        " << frames << "  (" << frames / secs << " frames/s in total, "
            << frames / secs / clients << " per client)\n"
            << "bytes delivered         " << bytes / 1048576.0 << " MiB  (" << bytes / secs / 1048576.0 << " MiB/s)\n"
            << "server RSS peak/now     " << peakRss / 1024.0 << " / " << procKib(pid, "VmRSS") / 1024.0 << " MiB"
            << " (VmHWM " << procKib(pid, "VmHWM") / 1024.0 << " MiB)\n";
  return done == clients ? 0 : 1;
}
