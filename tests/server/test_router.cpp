// rover::http Router, Request/Response helpers and static-file resolution: pure functions, no
// sockets (the server itself is in test_http_server.cpp).
#include <doctest/doctest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <string>

#include "server/http/router.hpp"
#include "server/http/static_files.hpp"

using rover::http::Request;
using rover::http::Response;
using rover::http::Router;
using rover::http::StaticFiles;
namespace fs = std::filesystem;

namespace {

Response ok(const Request&) {
  return Response::json(200, {{"ok", true}});
}

Router sampleRouter() {
  Router r;
  r.add("GET", "/api/maps", ok);
  r.add("POST", "/api/maps", ok);
  r.add("GET", "/api/maps/{id}", ok);
  r.add("GET", "/api/maps/default", ok);
  r.add("DELETE", "/api/maps/{id}", ok);
  r.add("GET", "/api/maps/{id}/layers/{layer}", ok);
  r.addWebSocket("/api/missions/{id}/events", [](const Request&, auto) { return nullptr; });
  return r;
}

struct TempDir {
  fs::path path;
  TempDir() {
    static int counter = 0;
    path = fs::temp_directory_path() /
           ("rover-router-test-" + std::to_string(::getpid()) + "-" + std::to_string(++counter));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

}  // namespace

TEST_CASE("router: captures match whole non-empty segments") {
  const Router r = sampleRouter();
  auto m = r.match("GET", "/api/maps/abc/layers/slope");
  REQUIRE(m.route);
  CHECK(m.route->pattern == "/api/maps/{id}/layers/{layer}");
  CHECK(m.params.at("id") == "abc");
  CHECK(m.params.at("layer") == "slope");

  m = r.match("GET", "/api/maps/x1");
  REQUIRE(m.route);
  CHECK(m.params.at("id") == "x1");

  CHECK_FALSE(r.match("GET", "/api/maps/").route);     // empty capture
  CHECK_FALSE(r.match("GET", "/api/maps/a/b").route);  // one segment per capture
  CHECK_FALSE(r.match("GET", "/api/mapsx").route);     // whole segments only
  CHECK_FALSE(r.match("GET", "/api/maps/a/layers").route);
  CHECK_FALSE(r.match("GET", "/nothing").pathKnown);
}

TEST_CASE("router: the most literal pattern wins, whatever the order") {
  const Router r = sampleRouter();
  auto m = r.match("GET", "/api/maps/default");
  REQUIRE(m.route);
  CHECK(m.route->pattern == "/api/maps/default");
  CHECK(m.params.empty());
}

TEST_CASE("router: a path known for another method is reported for a 405") {
  const Router r = sampleRouter();
  auto m = r.match("PUT", "/api/maps/abc");
  CHECK_FALSE(m.route);
  CHECK(m.pathKnown);
  CHECK(r.allowedMethods("/api/maps/abc") == std::vector<std::string>{"DELETE", "GET"});
  CHECK(r.allowedMethods("/api/maps") == std::vector<std::string>{"GET", "POST"});
  CHECK(r.allowedMethods("/nope").empty());

  m = r.match("DELETE", "/api/maps/abc");
  REQUIRE(m.route);
  CHECK(m.route->method == "DELETE");
}

TEST_CASE("router: WS routes match only a GET with an upgrade") {
  const Router r = sampleRouter();
  auto m = r.match("GET", "/api/missions/m1/events", true);
  REQUIRE(m.route);
  CHECK(m.route->method == "WS");
  CHECK(m.params.at("id") == "m1");

  m = r.match("GET", "/api/missions/m1/events", false);
  CHECK_FALSE(m.route);
  CHECK(m.pathKnown);
  CHECK(r.allowedMethods("/api/missions/m1/events") == std::vector<std::string>{"GET"});

  CHECK_FALSE(r.match("POST", "/api/missions/m1/events", true).route);
  // An upgrade request to a plain GET route falls back to it.
  m = r.match("GET", "/api/maps", true);
  REQUIRE(m.route);
  CHECK(m.route->method == "GET");
}

TEST_CASE("router: routes keep their options and handlers") {
  Router r;
  rover::http::RouteOptions o;
  o.streamBody = true;
  o.requireAuth = false;
  o.summary = "upload";
  r.add("POST", "/api/upload", ok, o);
  REQUIRE(r.routes().size() == 1);
  const auto m = r.match("POST", "/api/upload");
  REQUIRE(m.route);
  CHECK(m.route->options.streamBody);
  CHECK_FALSE(m.route->options.requireAuth);
  CHECK(m.route->handler(Request{}).status == 200);
}

TEST_CASE("router: JSON responses and the error shape") {
  const Response j = Response::json(201, {{"id", "m1"}});
  CHECK(j.status == 201);
  CHECK(j.contentType == "application/json");
  CHECK(nlohmann::json::parse(j.body) == nlohmann::json{{"id", "m1"}});

  const Response e = Response::error(422, "invalid_value", "alpha must be positive", "alpha");
  CHECK(e.status == 422);
  const auto body = nlohmann::json::parse(e.body);
  CHECK(body["error"]["code"] == "invalid_value");
  CHECK(body["error"]["message"] == "alpha must be positive");
  CHECK(body["error"]["field"] == "alpha");

  const auto noField = nlohmann::json::parse(Response::error(404, "not_found", "no map").body);
  CHECK(noField["error"]["field"] == "");  // always the three keys; "" when no one field is at fault
  CHECK(noField["error"]["code"] == "not_found");
}

TEST_CASE("router: Request::header takes lower-case names, empty when absent") {
  Request req;
  req.headers["content-type"] = "application/json";
  CHECK(req.header("content-type") == "application/json");
  CHECK(req.header("authorization").empty());
}

TEST_CASE("static: resolution stays inside the web root") {
  TempDir dir;
  const fs::path root = dir.path / "web";
  writeFile(root / "index.html", "<html></html>");
  writeFile(root / "js" / "app.js", "x");
  writeFile(root / "docs" / "index.html", "docs");
  writeFile(dir.path / "secret.txt", "secret");
  fs::create_symlink(dir.path / "secret.txt", root / "leak.txt");
  writeFile(dir.path / "web2" / "x.txt", "sibling");

  const StaticFiles s(root.string());
  REQUIRE(s.enabled());
  const fs::path canonRoot = fs::canonical(root);
  CHECK(s.resolve("/") == canonRoot / "index.html");
  CHECK(s.resolve("/js/app.js") == canonRoot / "js" / "app.js");
  CHECK(s.resolve("/docs") == canonRoot / "docs" / "index.html");
  CHECK(s.resolve("/docs/") == canonRoot / "docs" / "index.html");
  CHECK_FALSE(s.resolve("/missing.js"));
  CHECK_FALSE(s.resolve("/../secret.txt"));
  CHECK_FALSE(s.resolve("/js/../../secret.txt"));
  CHECK_FALSE(s.resolve("/../web2/x.txt"));
  CHECK_FALSE(s.resolve("/leak.txt"));  // symlink pointing outside
  CHECK_FALSE(s.resolve(std::string("/index.html\0x", 13)));

  const Response r = s.serve("/");
  CHECK(r.status == 200);
  CHECK(r.contentType.rfind("text/html", 0) == 0);
  bool noCache = false;
  for (const auto& [k, v] : r.headers) noCache |= k == "Cache-Control" && v == "no-cache";
  CHECK(noCache);
  CHECK(s.serve("/leak.txt").status == 404);

  CHECK_FALSE(StaticFiles("").enabled());
  CHECK_FALSE(StaticFiles("").resolve("/"));
}

TEST_CASE("static: content types by extension") {
  CHECK(StaticFiles::contentType("a/index.html") == "text/html; charset=utf-8");
  CHECK(StaticFiles::contentType("app.js") == "text/javascript; charset=utf-8");
  CHECK(StaticFiles::contentType("mod.mjs") == "text/javascript; charset=utf-8");
  CHECK(StaticFiles::contentType("s.CSS") == "text/css; charset=utf-8");
  CHECK(StaticFiles::contentType("d.json") == "application/json");
  CHECK(StaticFiles::contentType("i.png") == "image/png");
  CHECK(StaticFiles::contentType("i.svg") == "image/svg+xml");
  CHECK(StaticFiles::contentType("m.wasm") == "application/wasm");
  CHECK(StaticFiles::contentType("favicon.ico") == "image/x-icon");
  CHECK(StaticFiles::contentType("r.txt") == "text/plain; charset=utf-8");
  CHECK(StaticFiles::contentType("app.js.map") == "application/json");
  CHECK(StaticFiles::contentType("blob") == "application/octet-stream");
}
