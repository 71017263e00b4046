// The slow-request lane (server/http/work_pool.hpp): fair turns between clients (issue 22).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/http/work_pool.hpp"
#include "tests/wait_until.hpp"

using namespace rover;
using namespace std::chrono_literals;

TEST_CASE("work pool: a client with one job is served before another client's 50 queued jobs finish") {
  test::Gate release;  // before the pool: the held job may wait on it until the pool is gone
  http::WorkPool pool(1, 68);  // one client may hold 51 of the 68 places
  std::mutex m;
  std::vector<std::string> order;
  auto record = [&](std::string what) {
    std::lock_guard lock(m);
    order.push_back(std::move(what));
  };
  // A's first job holds the only thread until every job is queued, so the order is the pool's.
  REQUIRE(pool.trySubmit([&] {
    release.wait();
    record("A");
  }, "10.0.0.1"));
  test::waitUntil([&] { return pool.busy() == 1; }, "A's first job to take the thread");
  for (int i = 0; i < 50; ++i) REQUIRE(pool.trySubmit([&] { record("A"); }, "10.0.0.1"));
  REQUIRE(pool.trySubmit([&] { record("B"); }, "10.0.0.2"));
  CHECK(pool.queued() == 51);
  // A may queue one more, then its share is full while the queue still has room for others.
  CHECK(pool.maxQueuedPerClient() == 51);
  CHECK(pool.trySubmit([&] { record("A"); }, "10.0.0.1"));
  CHECK_FALSE(pool.trySubmit([&] { record("A"); }, "10.0.0.1"));
  CHECK(pool.queued() == 52);
  release.open();
  test::waitUntil(
      [&] {
        std::lock_guard lock(m);
        return order.size() == 53;
      },
      "all 53 jobs to run");
  std::lock_guard lock(m);
  // FIFO would put B after A's 50; in turns it comes right after A's running job and one more.
  const auto b = std::find(order.begin(), order.end(), "B") - order.begin();
  CHECK(b <= 2);
  CHECK(std::count(order.begin(), order.end(), "A") == 52);
}

TEST_CASE("work pool: clients take turns one job each, in the order they arrived") {
  test::Gate release;
  http::WorkPool pool(1, 16);
  std::mutex m;
  std::string order;
  REQUIRE(pool.trySubmit([&] { release.wait(); }, "gate"));
  test::waitUntil([&] { return pool.busy() == 1; }, "the gate job to take the thread");
  auto job = [&](char c) {
    return [&, c] {
      std::lock_guard lock(m);
      order += c;
    };
  };
  for (int i = 0; i < 3; ++i) REQUIRE(pool.trySubmit(job('a'), "a"));
  for (int i = 0; i < 2; ++i) REQUIRE(pool.trySubmit(job('b'), "b"));
  REQUIRE(pool.trySubmit(job('c'), "c"));
  release.open();
  test::waitUntil(
      [&] {
        std::lock_guard lock(m);
        return order.size() == 6;
      },
      "the six jobs to run");
  std::lock_guard lock(m);
  CHECK(order == "abcaba");
}
