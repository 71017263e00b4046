// Same-origin by default (issue 22, item 6): the Host allow-list against DNS rebinding, the Origin
// check on state changes and WebSocket upgrades, --cors as the one way to allow a foreign page; and
// the JSON edge's last loose ends (item 10): duplicate keys, one name rule, canonical run indices
// (the studies' part is in test_study_api.cpp, with its study server).
// Over loopback only, every loop bounded.
#include <doctest/doctest.h>

#include <sys/socket.h>
#include <sys/time.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>

#include "api_server.hpp"
#include "server/http/request_origin.hpp"

using namespace rover;
using rover::test::ApiServer;
using rover::test::ApiServerOptions;
using rover::test::checkError;
using rover::test::request;
using rover::test::TempDir;
using Json = nlohmann::json;

namespace {

namespace net = boost::asio;
using tcp = net::ip::tcp;

// Sends `raw` as is and returns what the server answers: everything until it closes, or only the
// response head when it switches protocols (a WebSocket stays open). A receive timeout bounds every
// read, so a hung server fails the test instead of hanging it.
std::string rawExchange(unsigned short port, const std::string& raw) {
  net::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  const timeval limit{20, 0};
  ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  net::write(socket, net::buffer(raw));
  std::string out;
  char buf[4096];
  for (int i = 0; i < 10000; ++i) {
    boost::system::error_code ec;
    const std::size_t n = socket.read_some(net::buffer(buf), ec);
    out.append(buf, n);
    if (ec || (out.rfind("HTTP/1.1 101", 0) == 0 && out.find("\r\n\r\n") != std::string::npos)) break;
  }
  return out;
}

int statusOf(const std::string& raw) {
  return raw.size() >= 12 && raw.compare(0, 5, "HTTP/") == 0 ? std::stoi(raw.substr(9, 3)) : 0;
}

std::string wsUpgrade(const std::string& path, const std::string& host, const std::string& origin) {
  return "GET " + path + " HTTP/1.1\r\nHost: " + host +
         "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n" +
         (origin.empty() ? "" : "Origin: " + origin + "\r\n") + "Connection: close\r\n\r\n";
}

Json coverageMission(const std::string& map) {
  return {{"map", map}, {"planner", "coverage"}, {"rovers", {{{"x", 20.5}, {"y", 20.5}, {"heading", 0}}}},
          {"params", {{"coverage", 0.01}}}};
}

std::size_t mapCount(ApiServer& s) { return s.get("/api/maps").json().size(); }

}  // namespace

TEST_CASE("origin policy: Host names parse strictly, loopback and configured names are ours") {
  using http::hostAllowed;
  using http::hostName;
  CHECK(hostName("Example.ORG:8080") == "example.org");
  CHECK(hostName("[::1]:80") == "::1");
  CHECK(hostName("localhost.") == "localhost");
  CHECK_FALSE(hostName("").has_value());
  CHECK_FALSE(hostName("a b").has_value());
  CHECK_FALSE(hostName("user@127.0.0.1").has_value());
  CHECK_FALSE(hostName("127.0.0.1:80x").has_value());
  CHECK_FALSE(hostName("127.0.0.1, evil.example").has_value());  // two Host headers, joined
  CHECK_FALSE(hostName("[::1").has_value());

  const http::OriginPolicy none;
  CHECK(hostAllowed(none, "localhost:8080"));
  CHECK(hostAllowed(none, "127.0.0.1"));
  CHECK(hostAllowed(none, "127.8.9.10:1"));
  CHECK(hostAllowed(none, "[::1]:8080"));
  CHECK_FALSE(hostAllowed(none, "evil.example:8080"));
  CHECK_FALSE(hostAllowed(none, "127.0.0.1.evil.example"));
  CHECK_FALSE(hostAllowed(none, "localhost.evil.example"));
  CHECK_FALSE(hostAllowed(none, "10.0.0.5"));
  const http::OriginPolicy named{{"rover.lab", "10.0.0.5"}, ""};
  CHECK(hostAllowed(named, "ROVER.lab:8080"));
  CHECK(hostAllowed(named, "10.0.0.5:8080"));
  CHECK_FALSE(hostAllowed(named, "rover.lab.evil.example"));
  CHECK(hostAllowed(http::OriginPolicy{{"*"}, ""}, "anything.example"));
}

TEST_CASE("origin policy: a page's Origin is ours when it names this Host, or is the CORS origin") {
  using http::foreignOrigin;
  const http::OriginPolicy p{{}, "http://localhost:5173"};
  CHECK_FALSE(foreignOrigin(p, "http://127.0.0.1:8080", "", "127.0.0.1:8080"));
  CHECK_FALSE(foreignOrigin(p, "http://LOCALHOST:8080", "same-origin", "localhost:8080"));
  CHECK_FALSE(foreignOrigin(p, "http://localhost:5173", "cross-site", "127.0.0.1:8080"));
  CHECK_FALSE(foreignOrigin(p, "", "", "127.0.0.1:8080"));      // curl, scripts, the CLI
  CHECK_FALSE(foreignOrigin(p, "", "none", "127.0.0.1:8080"));  // typed into the address bar
  CHECK(foreignOrigin(p, "http://evil.example", "", "127.0.0.1:8080"));
  CHECK(foreignOrigin(p, "http://127.0.0.1:9999", "", "127.0.0.1:8080"));  // another port
  CHECK(foreignOrigin(p, "null", "", "127.0.0.1:8080"));                  // sandboxed frame
  CHECK(foreignOrigin(p, "", "cross-site", "127.0.0.1:8080"));
  CHECK(foreignOrigin(p, "", "same-site", "127.0.0.1:8080"));
}

TEST_CASE("same origin: without a token, a foreign page can neither upload, launch nor listen") {
  TempDir d;
  ApiServer s(d.str("data"));
  const std::string map = s.defaultMap();
  const std::size_t maps = mapCount(s);
  const std::map<std::string, std::string> evil{{"Origin", "http://evil.example"}};

  // A DEM as a text/plain or multipart body (CORS "simple" requests: no preflight).
  checkError(request(s.port(), "POST", "/api/maps?name=x&filename=x.asc", "ncols 2\nnrows 2\n", "text/plain", evil),
             403, "foreign_origin", "origin");
  checkError(request(s.port(), "POST", "/api/maps", "--b\r\n\r\n--b--\r\n", "multipart/form-data; boundary=b", evil),
             403, "foreign_origin", "origin");
  CHECK(mapCount(s) == maps);
  // A mission as a form post, a deletion, a zone list.
  checkError(request(s.port(), "POST", "/api/missions", coverageMission(map).dump(),
                     "application/x-www-form-urlencoded", evil),
             403, "foreign_origin", "origin");
  checkError(request(s.port(), "DELETE", "/api/maps/" + map, "", "", evil), 403, "foreign_origin", "origin");
  checkError(request(s.port(), "PUT", "/api/maps/" + map + "/zones", "[]", "text/plain", evil), 403,
             "foreign_origin", "origin");
  CHECK(mapCount(s) == maps);
  // No Origin but a browser's cross-site fetch metadata; and the opaque "null" origin.
  checkError(request(s.port(), "POST", "/api/missions", coverageMission(map).dump(), "text/plain",
                     {{"Sec-Fetch-Site", "cross-site"}}),
             403, "foreign_origin", "origin");
  checkError(request(s.port(), "POST", "/api/missions", coverageMission(map).dump(), "text/plain", {{"Origin", "null"}}),
             403, "foreign_origin", "origin");
  CHECK(s.get("/api/missions").json().empty());

  // A live stream from a foreign page: refused before the upgrade; ours is accepted.
  const Json launched = s.postJson("/api/missions", coverageMission(map)).json();
  REQUIRE(launched.contains("id"));
  const std::string stream = "/api/missions/" + launched["id"].get<std::string>() + "/stream";
  const std::string host = "127.0.0.1:" + std::to_string(s.port());
  const std::string refused = rawExchange(s.port(), wsUpgrade(stream, host, "http://evil.example"));
  CHECK(statusOf(refused) == 403);
  CHECK(refused.find("foreign_origin") != std::string::npos);
  CHECK(statusOf(rawExchange(s.port(), wsUpgrade(stream, host, "http://" + host))) == 101);
  CHECK(statusOf(rawExchange(s.port(), wsUpgrade(stream, host, ""))) == 101);

  // The server's own page (Origin = scheme://Host) and reads from anywhere still work.
  const auto own = request(s.port(), "POST", "/api/missions", coverageMission(map).dump(), "application/json",
                           {{"Host", host}, {"Origin", "http://" + host}, {"Sec-Fetch-Site", "same-origin"}});
  CHECK(own.status == 202);
  CHECK(request(s.port(), "GET", "/api/maps", "", "", evil).status == 200);
}

TEST_CASE("same origin: --cors ORIGIN is the one foreign page allowed to change state") {
  TempDir d;
  ApiServerOptions o;
  o.http.corsOrigin = "http://localhost:5173";
  ApiServer s(d.str("data"), o);
  const std::string map = s.defaultMap();
  const auto r = request(s.port(), "POST", "/api/missions", coverageMission(map).dump(), "application/json",
                         {{"Origin", "http://localhost:5173"}});
  CHECK(r.status == 202);
  CHECK(r.headers.at("Access-Control-Allow-Origin") == "http://localhost:5173");
  checkError(request(s.port(), "POST", "/api/missions", coverageMission(map).dump(), "application/json",
                     {{"Origin", "http://localhost:5174"}}),
             403, "foreign_origin", "origin");
  const std::string host = "127.0.0.1:" + std::to_string(s.port());
  const std::string stream = "/api/missions/" + r.json()["id"].get<std::string>() + "/stream";
  CHECK(statusOf(rawExchange(s.port(), wsUpgrade(stream, host, "http://localhost:5173"))) == 101);
}

TEST_CASE("host allow-list: a rebound name gets 421, a missing Host 400, configured names are answered") {
  TempDir d;
  ApiServerOptions o;
  o.http.publicNames = {"rover.lab"};
  ApiServer s(d.str("data"), o);
  const std::string map = s.defaultMap();
  // DNS rebinding: the page's own origin, but a Host that is not ours.
  const std::string rebound = "evil.example:" + std::to_string(s.port());
  checkError(request(s.port(), "GET", "/api/health", "", "", {{"Host", rebound}}), 421, "misdirected_request", "host");
  checkError(request(s.port(), "POST", "/api/missions", coverageMission(map).dump(), "application/json",
                     {{"Host", rebound}, {"Origin", "http://" + rebound}}),
             421, "misdirected_request", "host");
  CHECK(statusOf(rawExchange(s.port(), "GET / HTTP/1.1\r\nHost: " + rebound + "\r\nConnection: close\r\n\r\n")) == 421);
  CHECK(statusOf(rawExchange(s.port(), wsUpgrade("/api/missions/x/stream", rebound, ""))) == 421);
  CHECK(s.get("/api/missions").json().empty());
  // Loopback names and --public-name are ours; HTTP/1.1 needs a Host, HTTP/1.0 may omit it.
  CHECK(request(s.port(), "GET", "/api/health", "", "", {{"Host", "localhost:1"}}).status == 200);
  CHECK(request(s.port(), "GET", "/api/health", "", "", {{"Host", "rover.lab"}}).status == 200);
  CHECK(statusOf(rawExchange(s.port(), "GET /api/health HTTP/1.1\r\nConnection: close\r\n\r\n")) == 400);
  CHECK(statusOf(rawExchange(s.port(), "GET /api/health HTTP/1.0\r\n\r\n")) == 200);
}

TEST_CASE("json edge: a key named twice in one object is refused, naming the key") {
  TempDir d;
  ApiServer s(d.str("data"));
  const std::string map = s.defaultMap();
  const std::string twice = R"({"map":")" + map +
                            R"(","planner":"coverage","rovers":[{"x":20.5,"y":20.5,"heading":0}],)"
                            R"("params":{"coverage":0.01,"coverage":1}})";
  checkError(s.post("/api/missions", twice), 400, "bad_json", "coverage");
  checkError(s.post("/api/missions", R"({"map":"a","map":"b"})"), 400, "bad_json", "map");
  // The same key in two different objects is not a duplicate.
  const std::string apart = R"({"map":")" + map +
                            R"(","planner":"coverage","rovers":[{"x":20.5,"y":20.5,"heading":0},)"
                            R"({"x":22.5,"y":20.5,"heading":0}],"params":{"coverage":0.01}})";
  CHECK(s.post("/api/missions", apart).status == 202);
}
