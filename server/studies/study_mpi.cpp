#include "server/studies/study_mpi.hpp"

#include <cstdlib>
#include <cstring>
#include <stdexcept>

#ifdef ROVER_HAVE_MPI
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <iostream>
#include <mutex>
#include <thread>

#include "core/common/parallel.hpp"
#endif

namespace rover::studies {

namespace {

int envInt(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : 0;
}

}  // namespace

int mpiLaunchSize() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (int n = envInt(name); n > 0) return n;
  // srun without a PMI variable of its own still says how many tasks it started.
  if (std::getenv("PMIX_RANK") || std::getenv("PMI_RANK")) return std::max(1, envInt("SLURM_NTASKS"));
  return 0;
}

int mpiLocalSize() {
  const int n = envInt("OMPI_COMM_WORLD_LOCAL_SIZE");
  return n > 0 ? n : 1;
}

#ifndef ROVER_HAVE_MPI

bool mpiBuilt() { return false; }

int runStudyMpi(const std::function<nlohmann::json()>&, const std::string&, const RunOptions&, const ProgressFn&,
                RunReport&, bool&) {
  throw std::runtime_error("this roverplan was built without MPI");
}

#else

bool mpiBuilt() { return true; }

namespace {

enum Tag : int { kRequest = 1, kWork = 2, kError = 3, kSpec = 4 };

// Rows as bytes: little-endian fixed-width fields, doubles bit for bit, so a row that crosses
// ranks is the row that was computed.
class Writer {
 public:
  template <class T>
  void put(T v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof v);
  }
  void str(const std::string& s) {
    put<std::uint64_t>(s.size());
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  void doubles(const std::vector<double>& v) {
    put<std::uint64_t>(v.size());
    for (double d : v) put(d);
  }
  std::vector<char> bytes;
};

class Reader {
 public:
  explicit Reader(const std::vector<char>& b) : b_(b) {}
  template <class T>
  T get() {
    if (pos_ + sizeof(T) > b_.size()) throw std::runtime_error("mpi: truncated message");
    T v;
    std::memcpy(&v, b_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  std::string str() {
    const auto n = get<std::uint64_t>();
    if (pos_ + n > b_.size()) throw std::runtime_error("mpi: truncated message");
    std::string s(b_.data() + pos_, n);
    pos_ += n;
    return s;
  }
  std::vector<double> doubles() {
    std::vector<double> v(get<std::uint64_t>());
    for (double& d : v) d = get<double>();
    return v;
  }
  bool done() const { return pos_ >= b_.size(); }

 private:
  const std::vector<char>& b_;
  std::size_t pos_ = 0;
};

std::vector<char> encode(const std::vector<RunRow>& rows) {
  Writer w;
  for (const auto& r : rows) {
    w.put(r.runIndex);
    w.put(r.configId);
    w.put(r.replicate);
    w.put(r.seed);
    w.str(r.status);
    w.put<std::uint64_t>(r.metrics.size());
    for (const auto& [k, v] : r.metrics) {
      w.str(k);
      w.put(v);
    }
    w.put<std::uint64_t>(r.curves.size());
    for (const auto& c : r.curves) {
      w.str(c.key);
      w.doubles(c.x);
      w.doubles(c.y);
    }
    w.put(r.wallSeconds);
    w.put(r.cpuSeconds);
    w.str(r.host);
    w.put(r.rank);
  }
  return w.bytes;
}

std::vector<RunRow> decode(const std::vector<char>& bytes) {
  std::vector<RunRow> rows;
  Reader rd(bytes);
  while (!rd.done()) {
    RunRow r;
    r.runIndex = rd.get<std::int64_t>();
    r.configId = rd.get<int>();
    r.replicate = rd.get<std::int64_t>();
    r.seed = rd.get<std::uint64_t>();
    r.status = rd.str();
    for (auto n = rd.get<std::uint64_t>(); n > 0; --n) {
      std::string k = rd.str();
      r.metrics.push_back({std::move(k), rd.get<double>()});
    }
    for (auto n = rd.get<std::uint64_t>(); n > 0; --n) {
      Curve c;
      c.key = rd.str();
      c.x = rd.doubles();
      c.y = rd.doubles();
      r.curves.push_back(std::move(c));
    }
    r.wallSeconds = rd.get<double>();
    r.cpuSeconds = rd.get<double>();
    r.host = rd.str();
    r.rank = rd.get<int>();
    rows.push_back(std::move(r));
  }
  return rows;
}

std::vector<char> recvBytes(const MPI_Status& status) {
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  std::vector<char> b(static_cast<std::size_t>(count));
  MPI_Recv(b.data(), count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return b;
}

[[noreturn]] void abortJob(int rank, const std::string& what) {
  std::cerr << "roverplan study run: rank " << rank << ": " << what << "\n" << std::flush;
  MPI_Abort(MPI_COMM_WORLD, 2);
  std::exit(2);
}

// Rank 0: serves requests and commits while its own threads work through the same queue.
void root(const StudyRunner& runner, StudyDb& db, int ranks, const RunOptions& o, const ProgressFn& progress,
          RunReport& report, unsigned threads) {
  std::vector<std::size_t> todo = runner.pending(db);
  report.total = runner.spec().runCount();
  report.alreadyDone = report.total - todo.size();
  std::mutex mutex;  // queue and ready rows
  std::deque<std::size_t> queue(todo.begin(), todo.end());
  std::vector<RunRow> ready;
  bool localDone = false;
  std::exception_ptr localError;
  const std::size_t everywhere = static_cast<std::size_t>(ranks) * threads;
  auto chunk = [&]() {  // under the lock
    std::size_t n = std::clamp<std::size_t>(queue.size() / (4 * everywhere), 1, 256);
    std::vector<std::uint64_t> out;
    while (n-- > 0 && !queue.empty()) {
      out.push_back(queue.front());
      queue.pop_front();
    }
    return out;
  };
  std::thread local([&] {
    try {
      if (threads > 0)
        runner.work(threads, [&]() -> std::optional<std::size_t> {
              std::lock_guard lock(mutex);  // work() calls next() under its own lock only
              if (queue.empty()) return std::nullopt;
              const std::size_t i = queue.front();
              queue.pop_front();
              return i;
            },
            [&](RunRow&& row) {
              std::lock_guard lock(mutex);
              ready.push_back(std::move(row));
            },
            nullptr, 0);
    } catch (...) {
      localError = std::current_exception();
    }
    std::lock_guard lock(mutex);
    localDone = true;
  });

  int active = ranks - 1;
  auto lastCommit = std::chrono::steady_clock::now();
  auto commit = [&] {
    std::vector<RunRow> batch;
    {
      std::lock_guard lock(mutex);
      batch.swap(ready);
    }
    db.insert(batch);
    report.ran += batch.size();
    lastCommit = std::chrono::steady_clock::now();
    if (progress && !batch.empty()) progress(report.alreadyDone + report.ran, report.total);
  };
  for (;;) {
    bool finished;
    {
      std::lock_guard lock(mutex);
      finished = localDone;
    }
    if (finished && localError) abortJob(0, [&] {
        try {
          std::rethrow_exception(localError);
        } catch (const std::exception& e) {
          return std::string(e.what());
        }
      }());
    if (finished && active == 0) break;
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
    if (flag) {
      std::vector<char> bytes = recvBytes(status);
      if (status.MPI_TAG == kError) abortJob(status.MPI_SOURCE, std::string(bytes.begin(), bytes.end()));
      std::vector<RunRow> rows = decode(bytes);
      std::vector<std::uint64_t> next;
      {
        std::lock_guard lock(mutex);
        for (auto& r : rows) ready.push_back(std::move(r));
        next = chunk();
      }
      MPI_Send(next.data(), static_cast<int>(next.size() * sizeof(std::uint64_t)), MPI_BYTE, status.MPI_SOURCE, kWork,
               MPI_COMM_WORLD);
      if (next.empty()) --active;
    } else {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    std::size_t waiting;
    {
      std::lock_guard lock(mutex);
      waiting = ready.size();
    }
    if (waiting >= o.commitRuns ||
        (waiting > 0 && std::chrono::steady_clock::now() - lastCommit > std::chrono::duration<double>(o.commitSeconds)))
      commit();
  }
  local.join();
  commit();
}

// Other ranks: ask, run the chunk on this rank's threads, return its rows with the next request.
void worker(const StudyRunner& runner, int rank, unsigned threads) {
  std::vector<RunRow> rows;
  std::mutex mutex;
  for (;;) {
    std::vector<char> bytes = encode(rows);
    rows.clear();
    MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, 0, kRequest, MPI_COMM_WORLD);
    MPI_Status status;
    MPI_Probe(0, kWork, MPI_COMM_WORLD, &status);
    std::vector<char> reply = recvBytes(status);
    std::vector<std::uint64_t> chunk(reply.size() / sizeof(std::uint64_t));
    std::memcpy(chunk.data(), reply.data(), chunk.size() * sizeof(std::uint64_t));
    if (chunk.empty()) return;
    std::size_t next = 0;
    runner.work(std::max(1u, threads), [&]() -> std::optional<std::size_t> {
          if (next >= chunk.size()) return std::nullopt;
          return chunk[next++];
        },
        [&](RunRow&& row) {
          std::lock_guard lock(mutex);
          rows.push_back(std::move(row));
        },
        nullptr, rank);
  }
}

}  // namespace

int runStudyMpi(const std::function<nlohmann::json()>& specOnRoot, const std::string& dbPath, const RunOptions& o,
                const ProgressFn& progress, RunReport& report, bool& isRoot) {
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  isRoot = rank == 0;
  const auto t0 = std::chrono::steady_clock::now();
  unsigned threads = o.threads > 0 ? o.threads : std::max(1u, hardwareThreads() / static_cast<unsigned>(mpiLocalSize()));

  // The spec: read on rank 0, the same text everywhere.
  std::string text;
  std::exception_ptr specError;
  if (rank == 0) {
    try {
      text = specOnRoot().dump();
      parseStudySpec(nlohmann::json::parse(text));
    } catch (...) {
      specError = std::current_exception();
      text.clear();
    }
  }
  unsigned long long length = text.size();
  MPI_Bcast(&length, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  if (length == 0) {
    MPI_Finalize();
    if (specError) std::rethrow_exception(specError);
    return 2;
  }
  text.resize(length);
  MPI_Bcast(text.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD);

  try {
    StudyRunner runner(parseStudySpec(nlohmann::json::parse(text)));
    if (rank == 0) {
      StudyDb db = StudyDb::open(dbPath);
      db.attach(runner.spec());
      // Rank 0's main thread serves and commits; with one thread per rank it works on one thread
      // fewer than the others only when there are several (it keeps one for serving).
      root(runner, db, ranks, o, progress, report, threads);
      report.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    } else {
      worker(runner, rank, threads);
    }
  } catch (const std::exception& e) {
    if (rank == 0) abortJob(rank, e.what());
    std::string what = e.what();
    MPI_Send(what.data(), static_cast<int>(what.size()), MPI_BYTE, 0, kError, MPI_COMM_WORLD);
    // Rank 0 aborts the job when it reads this.
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  MPI_Finalize();
  return 0;
}

#endif

}  // namespace rover::studies
