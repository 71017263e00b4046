// rover::http::dispatch without a socket: a Beast request in, the server's answer out (auth,
// routing, the error table answering what handlers throw), and the error table's statuses.
#include <doctest/doctest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string>

#include <boost/beast/http.hpp>
#include <nlohmann/json.hpp>

#include "core/common/error.hpp"
#include "server/api/error_table.hpp"
#include "server/errors/domain_error.hpp"
#include "server/http/dispatch.hpp"
#include "server/store/data_dir.hpp"

namespace {

namespace bhttp = boost::beast::http;
namespace fs = std::filesystem;
using nlohmann::json;
using rover::DomainError;
using rover::Refusal;
using rover::http::Request;
using rover::http::Response;
using rover::http::Router;
using rover::http::ServerConfig;
using rover::http::ServerState;
using rover::http::WorkPool;

// A server's state without its listener: the router and config dispatch reads.
struct Server {
  explicit Server(const ServerConfig& config = {}) : config(config) {}
  ServerState& state() {
    if (!state_) state_ = std::make_unique<ServerState>(config, router, pool);
    return *state_;
  }
  ServerConfig config;
  Router router;
  WorkPool pool{1, 1};

 private:
  std::unique_ptr<ServerState> state_;
};

bhttp::request<bhttp::string_body> request(bhttp::verb method, const std::string& target, std::string body = "") {
  bhttp::request<bhttp::string_body> r{method, target, 11};
  r.set(bhttp::field::host, "localhost:8080");
  r.body() = std::move(body);
  r.prepare_payload();
  return r;
}

std::string header(const Response& r, const std::string& name) {
  for (const auto& [n, v] : r.headers)
    if (n == name) return v;
  return "";
}

json error(const Response& r) {
  return json::parse(r.body).at("error");
}

}  // namespace

TEST_CASE("dispatch: without the bearer token an API route is refused 401 and the handler never runs") {
  Server s;
  s.config.token = "s3cret";
  bool ran = false;
  s.router.add("GET", "/api/things", [&](const Request&) {
    ran = true;
    return Response::json(200, {{"ok", true}});
  });
  Response r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/things"));
  CHECK(r.status == 401);
  CHECK(error(r)["code"] == "unauthorized");
  CHECK(error(r)["field"] == "authorization");
  CHECK(header(r, "WWW-Authenticate") == "Bearer");
  CHECK_FALSE(ran);

  auto authorized = request(bhttp::verb::get, "/api/things");
  authorized.set(bhttp::field::authorization, "Bearer s3cret");
  r = rover::http::dispatch(s.state(), authorized);
  CHECK(r.status == 200);
  CHECK(ran);
}

TEST_CASE("dispatch: no route is 404 naming the path, another method's route 405 with Allow, a foreign Host 421") {
  Server s;
  s.router.add("GET", "/api/things/{id}", [](const Request& req) { return Response::json(200, {{"id", req.params.at("id")}}); });
  Response r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/nothing"));
  CHECK(r.status == 404);
  CHECK(error(r)["code"] == "not_found");
  CHECK(error(r)["field"] == "path");
  CHECK(error(r)["message"] == "no route for GET /api/nothing");

  r = rover::http::dispatch(s.state(), request(bhttp::verb::delete_, "/api/things/7"));
  CHECK(r.status == 405);
  CHECK(header(r, "Allow") == "GET");

  r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/things/7"));
  CHECK(r.status == 200);
  CHECK(json::parse(r.body)["id"] == "7");

  auto rebound = request(bhttp::verb::get, "/api/things/7");
  rebound.set(bhttp::field::host, "evil.example:8080");
  r = rover::http::dispatch(s.state(), rebound);
  CHECK(r.status == 421);
  CHECK(error(r)["code"] == "misdirected_request");
}

TEST_CASE("dispatch: what a handler throws is answered through the error table") {
  Server s;
  s.router.add("POST", "/api/queue", [](const Request&) -> Response {
    throw DomainError(Refusal::QueueFull, "the queue is full").retryAfter(std::chrono::seconds(10));
  });
  s.router.add("POST", "/api/disk", [](const Request&) -> Response { throw rover::store::StorageFull("the result"); });
  s.router.add("POST", "/api/big", [](const Request&) -> Response {
    throw rover::store::OverBudget(Refusal::TooLarge, "more than a map's whole disk budget", "body", false);
  });
  s.router.add("POST", "/api/core", [](const Request&) -> Response {
    throw rover::Error(rover::ErrorCode::InvalidInput, "", "the grid is too small");
  });
  s.router.add("POST", "/api/json", [](const Request& req) -> Response {
    return Response::json(200, {{"n", json::parse(req.body).at("n").get<int>()}});
  });
  s.router.add("POST", "/api/edge", [](const Request&) -> Response {
    throw rover::http::ApiError(422, "invalid_value", "alpha must be positive", "alpha");
  });
  s.router.add("POST", "/api/bug", [](const Request&) -> Response { throw std::runtime_error("/srv/secret/path"); });

  Response r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/queue"));
  CHECK(r.status == 429);
  CHECK(error(r)["code"] == "queue_full");
  CHECK(error(r)["message"] == "the queue is full");
  CHECK(header(r, "Retry-After") == "10");

  r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/disk"));
  CHECK(r.status == 507);
  CHECK(error(r)["code"] == "insufficient_storage");
  CHECK(header(r, "Retry-After").empty());

  r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/big"));
  CHECK(r.status == 413);
  CHECK(error(r)["code"] == "too_large");
  CHECK(error(r)["field"] == "body");

  r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/core"));
  CHECK(r.status == 400);
  CHECK(error(r)["code"] == "invalid_input");
  CHECK(error(r)["field"] == "body");  // an error naming no field is about the body

  r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/json", R"({"n": "seven"})"));
  CHECK(r.status == 400);
  CHECK(error(r)["code"] == "bad_json");

  r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/edge"));
  CHECK(r.status == 422);
  CHECK(error(r)["field"] == "alpha");

  r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/bug"));
  CHECK(r.status == 500);
  CHECK(error(r)["code"] == "internal");
  CHECK(r.body.find("secret") == std::string::npos);  // the detail goes to the log only
}

TEST_CASE("dispatch: a blocking route's quick answer is taken when it has one, its handler runs otherwise") {
  Server s;
  int handled = 0;
  rover::http::RouteOptions slow;
  slow.blocking = true;
  slow.quick = [](const Request& req) -> std::optional<Response> {
    const std::string& what = req.params.at("what");
    if (what == "made") return Response::json(200, {{"from", "quick"}});
    if (what == "gone") throw rover::http::ApiError(404, "not_found", "no such thing", "what");
    if (what == "bug") throw std::runtime_error("/srv/secret/path");
    return std::nullopt;  // not at hand
  };
  s.router.add("GET", "/api/thing/{what}", [&](const Request&) {
    ++handled;
    return Response::json(200, {{"from", "handler"}});
  }, slow);
  // The same quick function on a route that is not blocking is never asked: the handler is as cheap.
  rover::http::RouteOptions cheap = slow;
  cheap.blocking = false;
  s.router.add("GET", "/api/cheap/{what}", [&](const Request&) {
    ++handled;
    return Response::json(200, {{"from", "handler"}});
  }, cheap);

  Response r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/thing/made"));
  CHECK(json::parse(r.body)["from"] == "quick");
  CHECK(handled == 0);
  r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/thing/unmade"));
  CHECK(json::parse(r.body)["from"] == "handler");
  CHECK(handled == 1);
  r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/thing/gone"));
  CHECK(r.status == 404);
  CHECK(error(r)["field"] == "what");
  r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/thing/bug"));
  CHECK(r.status == 500);
  CHECK(r.body.find("secret") == std::string::npos);
  CHECK(handled == 1);  // an answer thrown by the quick function is the answer
  r = rover::http::dispatch(s.state(), request(bhttp::verb::get, "/api/cheap/made"));
  CHECK(json::parse(r.body)["from"] == "handler");
  CHECK(handled == 2);
}

TEST_CASE("dispatch: a streamed-body route reads its body from a file that is gone afterwards") {
  Server s;
  s.config.uploadDir = (fs::temp_directory_path() / ("dispatch-test-" + std::to_string(::getpid()))).string();
  std::string seen;
  rover::http::RouteOptions streamed;
  streamed.streamBody = true;
  s.router.add("POST", "/api/upload", [&](const Request& req) {
    std::ifstream in(req.bodyFile, std::ios::binary);
    seen = std::string(std::istreambuf_iterator<char>(in), {});
    return Response::json(201, {{"bytes", req.bodySize}});
  }, streamed);
  Response r = rover::http::dispatch(s.state(), request(bhttp::verb::post, "/api/upload", "BYTES"));
  CHECK(r.status == 201);
  CHECK(seen == "BYTES");
  CHECK(fs::is_empty(s.config.uploadDir));
  fs::remove_all(s.config.uploadDir);
}

TEST_CASE("error table: every domain refusal keeps the status and code name the API answers") {
  struct Row {
    Refusal code;
    const char* name;
    int status;
  };
  const Row rows[] = {
      {Refusal::BadJson, "bad_json", 400},
      {Refusal::UnknownField, "unknown_field", 400},
      {Refusal::InvalidField, "invalid_field", 400},
      {Refusal::TooManyRuns, "too_many_runs", 400},
      {Refusal::MissionTooLarge, "mission_too_large", 413},
      {Refusal::TooLarge, "too_large", 413},
      {Refusal::QueueFull, "queue_full", 429},
      {Refusal::MemoryBusy, "memory_busy", 429},
      {Refusal::TooManyStudies, "too_many_studies", 429},
      {Refusal::Unavailable, "unavailable", 503},
      {Refusal::InsufficientStorage, "insufficient_storage", 507},
      {Refusal::DiskBudgetFull, "disk_budget_full", 507},
  };
  for (const Row& row : rows) {
    CAPTURE(row.name);
    CHECK(std::string(rover::refusalName(row.code)) == row.name);
    CHECK(rover::api::httpStatus(row.code) == row.status);
  }
}
