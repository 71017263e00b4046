#pragma once
// The stages of a map import, timed for the server's log (issue 24: upload -> first tiles, memory
// per stage): wall seconds, CPU seconds (every thread of the server and the reaped import worker, user +
// system) and its
// resident peak (VmHWM) after each stage. One line per import on stderr, e.g.
//   import 7000x7000: worker 4.1 s (cpu 0.0 s, peak 220 MiB), classes 0.5 s (...), ...
// The peak is the process's: with other requests running it is an upper bound on the import's.
#include <chrono>
#include <string>
#include <vector>

namespace rover::api {

class ImportStages {
 public:
  ImportStages();
  void done(const char* stage);  // closes the stage begun at the previous done() (or construction)
  void note(std::string text);    // said after the stages (what ran alongside them)
  std::string line() const;      // "worker 4.1 s (cpu 0.0 s, peak 220 MiB), ..., total 9.8 s"

 private:
  struct Stage {
    std::string name;
    double wall, cpu, peakMiB;
  };
  std::chrono::steady_clock::time_point start_, last_;
  double lastCpu_ = 0;
  std::vector<Stage> stages_;
  std::string notes_;
};

}  // namespace rover::api
