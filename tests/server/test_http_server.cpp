// rover::http::HttpServer over loopback: routing, errors, limits, uploads, static files, auth,
// CORS, WebSockets (pull loop, wake-ups, slow clients), timeouts and shutdown. Every client
// operation runs under a watchdog, so a hung server fails the test instead of hanging it.
#include <doctest/doctest.h>

#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "server/http/http_server.hpp"
#include "server/http/router.hpp"
#include "tests/wait_until.hpp"

namespace {

namespace beast = boost::beast;
namespace bhttp = boost::beast::http;
namespace websocket = boost::beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;
using rover::http::ApiError;
using rover::http::HttpServer;
using rover::http::Request;
using rover::http::Response;
using rover::http::RouteOptions;
using rover::http::Router;
using rover::http::ServerConfig;
using rover::http::WsConnection;
using rover::http::WsFrame;
using rover::http::WsSource;

// Shuts the socket down if the guarded client operations take longer than `limit`: blocked
// synchronous reads then fail instead of hanging the suite.
class Watchdog {
 public:
  Watchdog(int fd, std::chrono::milliseconds limit)
      : thread_([this, fd, limit] {
          std::unique_lock lock(mutex_);
          if (!cv_.wait_for(lock, limit, [this] { return done_; })) {
            fired_ = true;
            ::shutdown(fd, SHUT_RDWR);
          }
        }) {}
  ~Watchdog() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  bool fired() {
    std::lock_guard lock(mutex_);
    return fired_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  bool fired_ = false;
  std::thread thread_;  // last: starts once the rest is constructed
};

struct TempDir {
  fs::path path;
  TempDir() {
    static std::atomic<int> counter{0};
    path = fs::temp_directory_path() /
           ("rover-http-test-" + std::to_string(::getpid()) + "-" + std::to_string(++counter));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::size_t count() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(path), {}));
  }
};

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A server on 127.0.0.1, ephemeral port, stopped by the destructor.
struct TestServer {
  Router router;
  ServerConfig config;
  std::unique_ptr<HttpServer> server;

  TestServer() {
    config.host = "127.0.0.1";
    config.port = 0;
    config.threads = 2;
    config.logRequests = false;
  }
  ~TestServer() { stop(); }
  void start() {
    server = std::make_unique<HttpServer>(config, router);
    server->start();
  }
  void stop() {
    if (server) server->stop();
  }
  unsigned short port() const { return server->port(); }
};

struct Reply {
  int status = 0;
  std::string body;
  std::map<std::string, std::string> headers;  // lower-case names
  bool ok = false;                             // a response was read
  json js() const { return json::parse(body); }
  bool has(const std::string& name) const { return headers.count(name) > 0; }
  std::string header(const std::string& name) const {
    auto it = headers.find(name);
    return it == headers.end() ? "" : it->second;
  }
};

Reply toReply(const bhttp::response<bhttp::string_body>& res) {
  Reply r;
  r.ok = true;
  r.status = static_cast<int>(res.result_int());
  r.body = res.body();
  for (const auto& f : res) {
    std::string name(f.name_string());
    for (auto& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    r.headers[name] = std::string(f.value());
  }
  return r;
}

// A keep-alive client: one connection, many requests.
struct Client {
  net::io_context ioc;
  tcp::socket socket{ioc};
  beast::flat_buffer buffer;

  explicit Client(unsigned short port) {
    socket.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  }

  Reply send(bhttp::request<bhttp::string_body> req, std::chrono::milliseconds limit = rover::test::kHangDeadline) {
    Watchdog dog(socket.native_handle(), limit);
    req.version(11);
    req.set(bhttp::field::host, "127.0.0.1");
    if (!req.has_content_length() && !req.chunked()) req.prepare_payload();
    beast::error_code ec;
    bhttp::write(socket, req, ec);  // a failed write still lets us read an early error response
    return read(req.method() == bhttp::verb::head);
  }

  Reply read(bool head = false) {
    bhttp::response_parser<bhttp::string_body> parser;
    parser.body_limit(64u << 20);
    parser.skip(head);
    beast::error_code ec;
    bhttp::read(socket, buffer, parser, ec);
    if (ec) return {};
    return toReply(parser.get());
  }

  // Raw bytes, then whatever comes back until the server closes (for malformed requests).
  std::string raw(const std::string& bytes, std::chrono::milliseconds limit = rover::test::kHangDeadline) {
    Watchdog dog(socket.native_handle(), limit);
    beast::error_code ec;
    net::write(socket, net::buffer(bytes), ec);
    std::string out;
    char chunk[4096];
    for (;;) {
      std::size_t n = socket.read_some(net::buffer(chunk), ec);
      if (ec) break;
      out.append(chunk, n);
    }
    return out;
  }
};

bhttp::request<bhttp::string_body> makeRequest(bhttp::verb method, const std::string& target,
                                               std::string body = "") {
  bhttp::request<bhttp::string_body> req{method, target, 11};
  req.body() = std::move(body);
  return req;
}

Reply call(unsigned short port, bhttp::verb method, const std::string& target,
           std::string body = "", std::vector<std::pair<std::string, std::string>> headers = {}) {
  Client c(port);
  auto req = makeRequest(method, target, std::move(body));
  for (const auto& [k, v] : headers) req.set(k, v);
  return c.send(std::move(req));
}

int statusOf(const std::string& raw) {
  // "HTTP/1.1 400 Bad Request\r\n..."
  if (raw.size() < 12 || raw.compare(0, 5, "HTTP/") != 0) return 0;
  return std::stoi(raw.substr(9, 3));
}

Response echoParams(const Request& req) {
  json p = json::object();
  for (const auto& [k, v] : req.params) p[k] = v;
  return Response::json(200, {{"params", p}, {"query", req.query}, {"path", req.path}});
}

// ---- WebSocket helpers

// Frames handed out in order; empty -> nullopt until more are pushed (then wake()).
class QueueSource : public WsSource {
 public:
  explicit QueueSource(std::chrono::milliseconds interval = 1ms) : interval_(interval) {}
  void push(WsFrame f) {
    std::lock_guard lock(mutex_);
    frames_.push_back(std::move(f));
  }
  std::optional<WsFrame> next() override {
    std::lock_guard lock(mutex_);
    ++calls_;
    if (frames_.empty()) return std::nullopt;
    WsFrame f = std::move(frames_.front());
    frames_.pop_front();
    handed_.push_back(f.data);
    return f;
  }
  // The frames handed to the session, in the order it took them.
  std::vector<std::string> handed() {
    std::lock_guard lock(mutex_);
    return handed_;
  }
  std::chrono::milliseconds minInterval() const override { return interval_; }
  int calls() {
    std::lock_guard lock(mutex_);
    return calls_;
  }

 private:
  std::mutex mutex_;
  std::deque<WsFrame> frames_;
  std::chrono::milliseconds interval_;
  int calls_ = 0;
  std::vector<std::string> handed_;
};

// prefix + i (spelled out: GCC 12 -O3 warns falsely on `"literal" + std::to_string(i)`).
std::string numbered(const std::string& prefix, int i) {
  std::string s = prefix;
  s += std::to_string(i);
  return s;
}

// A WebSocket upgrade request as plain HTTP, to see a refusal's status and body (Beast 1.74's
// synchronous handshake does not return the response when it fails).
Reply upgradeRequest(unsigned short port, const std::string& target) {
  return call(port, bhttp::verb::get, target, "",
              {{"Connection", "Upgrade"},
               {"Upgrade", "websocket"},
               {"Sec-WebSocket-Version", "13"},
               {"Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="}});
}

WsFrame text(std::string s, bool last = false) {
  return WsFrame{false, std::move(s), last};
}

struct WsClient {
  net::io_context ioc;
  websocket::stream<tcp::socket> ws{ioc};
  websocket::response_type response;

  // Handshake; false (and `response` holds the HTTP answer) when the server refused.
  bool connect(unsigned short port, const std::string& target, const std::string& bearer = "",
               int receiveBuffer = 0) {
    if (receiveBuffer > 0) {
      ws.next_layer().open(tcp::v4());
      ws.next_layer().set_option(net::socket_base::receive_buffer_size(receiveBuffer));
    }
    ws.next_layer().connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    if (!bearer.empty())
      ws.set_option(websocket::stream_base::decorator([bearer](websocket::request_type& req) {
        req.set(bhttp::field::authorization, "Bearer " + bearer);
      }));
    Watchdog dog(ws.next_layer().native_handle(), rover::test::kHangDeadline);
    beast::error_code ec;
    ws.handshake(response, "127.0.0.1", target, ec);
    return !ec;
  }

  struct Message {
    bool binary = false;
    std::string data;
  };
  bool hitDeadline = false;  // the last readAll ended at its deadline, not at the server's close
  // Reads messages until the server closes (or the deadline); `closeCode` is set on a close.
  std::vector<Message> readAll(std::chrono::milliseconds limit, int* closeCode = nullptr,
                               std::size_t maxMessages = 1000) {
    Watchdog dog(ws.next_layer().native_handle(), limit);
    std::vector<Message> out;
    while (out.size() < maxMessages) {
      beast::flat_buffer buf;
      beast::error_code ec;
      ws.read(buf, ec);
      if (ec) {
        if (ec == websocket::error::closed && closeCode) *closeCode = ws.reason().code;
        break;
      }
      out.push_back({ws.got_binary(), beast::buffers_to_string(buf.data())});
    }
    hitDeadline = dog.fired();
    return out;
  }
};

}  // namespace

// ------------------------------------------------------------------------------------- routing

TEST_CASE("http: routes with captures, query decoding, 404 and 405 as JSON errors") {
  TestServer s;
  s.router.add("GET", "/api/items/{id}", echoParams);
  s.router.add("POST", "/api/items", echoParams);
  s.start();

  Reply r = call(s.port(), bhttp::verb::get, "/api/items/a%20b?x=1&name=rover+one&e=%2F");
  REQUIRE(r.ok);
  CHECK(r.status == 200);
  CHECK(r.header("content-type") == "application/json");
  CHECK(r.js()["params"]["id"] == "a b");
  CHECK(r.js()["query"]["x"] == "1");
  CHECK(r.js()["query"]["name"] == "rover one");
  CHECK(r.js()["query"]["e"] == "/");

  r = call(s.port(), bhttp::verb::delete_, "/api/items/7");
  CHECK(r.status == 405);
  CHECK(r.header("allow") == "GET");
  CHECK(r.js()["error"]["code"] == "method_not_allowed");
  CHECK(r.js()["error"]["message"].is_string());
  CHECK(r.js()["error"]["field"] == "method");

  r = call(s.port(), bhttp::verb::get, "/api/nothing/here");
  CHECK(r.status == 404);
  CHECK(r.js()["error"]["code"] == "not_found");
  CHECK(r.js()["error"]["field"] == "path");

  r = call(s.port(), bhttp::verb::get, "/no-web-root");  // no webRoot configured
  CHECK(r.status == 404);
  CHECK(r.js()["error"]["code"] == "not_found");
}

TEST_CASE("http: keep-alive serves several requests on one connection, bodies reach handlers") {
  TestServer s;
  s.router.add("POST", "/api/echo", [](const Request& req) {
    return Response::json(200, {{"body", req.body},
                                {"size", req.bodySize},
                                {"ct", req.header("content-type")},
                                {"remote", !req.remote.empty()}});
  });
  s.start();
  Client c(s.port());
  for (int i = 0; i < 3; ++i) {
    auto req = makeRequest(bhttp::verb::post, "/api/echo", "{\"i\":" + std::to_string(i) + "}");
    req.set(bhttp::field::content_type, "application/json");
    Reply r = c.send(std::move(req));
    REQUIRE(r.ok);
    CHECK(r.status == 200);
    CHECK(r.js()["body"] == "{\"i\":" + std::to_string(i) + "}");
    CHECK(r.js()["ct"] == "application/json");
    CHECK(r.js()["remote"] == true);
  }
}

TEST_CASE("http: ApiError becomes its status with the JSON error shape") {
  TestServer s;
  s.router.add("POST", "/api/check", [](const Request&) -> Response {
    throw ApiError(422, "invalid_value", "alpha must be positive", "alpha");
  });
  s.router.add("GET", "/api/missing", [](const Request&) -> Response {
    throw ApiError(404, "not_found", "no such mission");
  });
  s.start();
  Reply r = call(s.port(), bhttp::verb::post, "/api/check", "{}");
  CHECK(r.status == 422);
  CHECK(r.js() == json{{"error",
                        {{"code", "invalid_value"},
                         {"message", "alpha must be positive"},
                         {"field", "alpha"}}}});
  r = call(s.port(), bhttp::verb::get, "/api/missing");
  CHECK(r.status == 404);
  CHECK(r.js()["error"]["code"] == "not_found");
  CHECK(r.js()["error"].contains("field"));  // always the three keys
}

TEST_CASE("http: a throwing handler gives 500 and the server keeps serving") {
  TestServer s;
  s.config.logRequests = true;  // exercise the log line once
  s.router.add("GET", "/api/boom",
               [](const Request&) -> Response { throw std::runtime_error("kaboom"); });
  s.router.add("GET", "/api/int", [](const Request&) -> Response { throw 42; });
  s.router.add("GET", "/api/ok", [](const Request&) { return Response::json(200, {{"ok", 1}}); });
  s.start();
  Client c(s.port());
  Reply r = c.send(makeRequest(bhttp::verb::get, "/api/boom"));
  CHECK(r.status == 500);
  CHECK(r.js()["error"]["code"] == "internal");
  // The exception's text is logged, not shown (it may hold server paths).
  CHECK(r.js()["error"]["message"] == "internal error");
  r = c.send(makeRequest(bhttp::verb::get, "/api/int"));
  CHECK(r.status == 500);
  r = c.send(makeRequest(bhttp::verb::get, "/api/ok"));  // same connection still works
  CHECK(r.status == 200);
  CHECK(call(s.port(), bhttp::verb::get, "/api/ok").status == 200);
}

TEST_CASE("http: a handler's file response is sent from disk, a vanished file is a 404") {
  TempDir dir;
  writeFile(dir.path / "result.bin", std::string(100000, 'z'));
  TestServer s;
  s.router.add("GET", "/api/file", [&](const Request&) {
    Response r;
    r.file = (dir.path / "result.bin").string();
    r.contentType = "application/octet-stream";
    return r;
  });
  s.router.add("GET", "/api/gone", [&](const Request&) {
    Response r;
    r.file = (dir.path / "gone.bin").string();
    return r;
  });
  s.start();
  Reply r = call(s.port(), bhttp::verb::get, "/api/file");
  CHECK(r.status == 200);
  CHECK(r.header("content-length") == "100000");
  CHECK(r.body == std::string(100000, 'z'));
  r = call(s.port(), bhttp::verb::get, "/api/gone");
  CHECK(r.status == 404);
  CHECK(r.js()["error"]["code"] == "not_found");
}

// --------------------------------------------------------------------------- bodies and limits

TEST_CASE("http: a streamed upload reaches the handler as a file with the exact bytes") {
  TempDir uploads;
  std::string payload(5u << 20, '\0');
  std::mt19937 rng(42);
  for (auto& c : payload) c = static_cast<char>(rng() & 0xff);

  TestServer s;
  s.config.uploadDir = uploads.path.string();
  s.config.maxUploadBytes = 8u << 20;
  s.config.maxBodyBytes = 1024;  // streamed routes are not bound by the in-memory limit
  std::mutex m;
  std::string seenFile;
  bool sameBytes = false;
  std::uint64_t seenSize = 0;
  RouteOptions o;
  o.streamBody = true;
  s.router.add(
      "POST", "/api/upload",
      [&](const Request& req) {
        std::lock_guard lock(m);
        seenFile = req.bodyFile;
        seenSize = req.bodySize;
        sameBytes = readFile(req.bodyFile) == payload;
        return Response::json(200, {{"size", req.bodySize}});
      },
      o);
  s.start();

  Reply r = call(s.port(), bhttp::verb::post, "/api/upload", payload,
                 {{"Content-Type", "application/octet-stream"}});
  REQUIRE(r.ok);
  CHECK(r.status == 200);
  CHECK(r.js()["size"] == payload.size());
  std::lock_guard lock(m);
  CHECK(sameBytes);
  CHECK(seenSize == payload.size());
  CHECK(fs::path(seenFile).parent_path() == uploads.path);
  CHECK_FALSE(fs::exists(seenFile));  // deleted after the handler returned
  CHECK(uploads.count() == 0);
}

TEST_CASE("http: a streamed upload the handler keeps is left where it moved it") {
  TempDir uploads;
  TestServer s;
  s.config.uploadDir = (uploads.path / "tmp").string();  // created on demand
  RouteOptions o;
  o.streamBody = true;
  s.router.add(
      "POST", "/api/keep",
      [&](const Request& req) {
        fs::rename(req.bodyFile, uploads.path / "kept.bin");
        return Response::json(201, {{"ok", true}});
      },
      o);
  s.start();
  Reply r = call(s.port(), bhttp::verb::post, "/api/keep", "hello");
  CHECK(r.status == 201);
  CHECK(readFile(uploads.path / "kept.bin") == "hello");
}

TEST_CASE("http: bodies over the limits are refused with 413") {
  TempDir uploads;
  TestServer s;
  s.config.uploadDir = uploads.path.string();
  s.config.maxUploadBytes = 1u << 20;
  s.config.maxBodyBytes = 1024;
  RouteOptions o;
  o.streamBody = true;
  std::atomic<int> calls{0};
  auto handler = [&](const Request&) {
    ++calls;
    return Response::json(200, {});
  };
  s.router.add("POST", "/api/upload", handler, o);
  s.router.add("POST", "/api/json", handler);
  s.start();

  SUBCASE("streamed, Content-Length over the limit") {
    Reply r = call(s.port(), bhttp::verb::post, "/api/upload", std::string(3u << 20, 'u'));
    REQUIRE(r.ok);
    CHECK(r.status == 413);
    CHECK(r.js()["error"]["code"] == "payload_too_large");
  }
  SUBCASE("streamed, chunked over the limit") {
    Client c(s.port());
    auto req = makeRequest(bhttp::verb::post, "/api/upload", std::string(3u << 20, 'u'));
    req.chunked(true);
    Reply r = c.send(std::move(req));
    REQUIRE(r.ok);
    CHECK(r.status == 413);
  }
  SUBCASE("in memory") {
    Reply r = call(s.port(), bhttp::verb::post, "/api/json", std::string(4096, 'j'));
    REQUIRE(r.ok);
    CHECK(r.status == 413);
    CHECK(r.js()["error"]["code"] == "payload_too_large");
  }
  CHECK(calls == 0);
  CHECK(uploads.count() == 0);
  CHECK(call(s.port(), bhttp::verb::post, "/api/json", "{}").status == 200);
}

TEST_CASE("http: an oversized header gets 431 and malformed requests get 400") {
  TestServer s;
  s.config.maxHeaderBytes = 2048;
  s.router.add("GET", "/api/ok", [](const Request&) { return Response::json(200, {}); });
  s.start();

  Client big(s.port());
  auto req = makeRequest(bhttp::verb::get, "/api/ok");
  req.set("X-Big", std::string(8000, 'h'));
  Reply r = big.send(std::move(req));
  REQUIRE(r.ok);
  CHECK((r.status == 431 || r.status == 400));

  Client garbage(s.port());
  CHECK(statusOf(garbage.raw("THIS IS NOT HTTP\r\n\r\n")) == 400);

  Client badEscape(s.port());
  CHECK(statusOf(badEscape.raw(
            "GET /api/ok%zz HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")) == 400);

  Client nul(s.port());
  CHECK(statusOf(nul.raw("GET /api/ok%00 HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")) ==
        400);

  CHECK(call(s.port(), bhttp::verb::get, "/api/ok").status == 200);
}

TEST_CASE("http: the read timeout closes an idle half-sent request, a longer one keeps it open") {
  // The same half-sent header on two servers that differ only in their read timeout. The event
  // waited for is the short one's close; at that moment the long one's connection must still be
  // open and answer once the header is finished: the close came from the timeout, not from the
  // half-sent request itself. (The watchdog's bound only catches a hang.)
  const std::string head = "GET /api/ok HTTP/1.1\r\nHost: localhost\r\n";
  auto ok = [](const Request&) { return Response::json(200, {}); };
  TestServer patient;
  patient.config.readTimeout = std::chrono::seconds(3600);
  patient.router.add("GET", "/api/ok", ok);
  patient.start();
  TestServer strict;
  strict.config.readTimeout = std::chrono::seconds(1);
  strict.router.add("GET", "/api/ok", ok);
  strict.start();
  Client kept(patient.port());
  net::write(kept.socket, net::buffer(head));  // first: it has waited longer than the other
  Client cut(strict.port());
  {
    Watchdog dog(cut.socket.native_handle(), rover::test::kHangDeadline);
    net::write(cut.socket, net::buffer(head));
    char buf[256];
    beast::error_code ec;
    std::size_t total = 0;
    while (!ec) total += cut.socket.read_some(net::buffer(buf), ec);
    CHECK_FALSE(dog.fired());  // the server closed, not the watchdog
    CHECK(ec == net::error::eof);
    CHECK(total == 0);  // quietly: no response to a request that never finished
  }
  // Nothing from the patient server yet: no bytes, no end of stream.
  kept.socket.non_blocking(true);
  char probe;
  beast::error_code ec;
  kept.socket.read_some(net::buffer(&probe, 1), ec);
  CHECK(ec == net::error::would_block);
  kept.socket.non_blocking(false);
  Watchdog dog(kept.socket.native_handle(), rover::test::kHangDeadline);
  net::write(kept.socket, net::buffer(std::string("\r\n")));
  CHECK(kept.read().status == 200);
}

// ------------------------------------------------------------------------------ static files

TEST_CASE("static: index.html, content types, HEAD, and no token needed") {
  TempDir dir;
  writeFile(dir.path / "web" / "index.html", "<!doctype html><title>rover</title>");
  writeFile(dir.path / "web" / "js" / "app.js", "console.log(1);");
  writeFile(dir.path / "web" / "style.css", "body{}");
  TestServer s;
  s.config.webRoot = (dir.path / "web").string();
  s.config.token = "s3cret";
  s.start();

  Reply r = call(s.port(), bhttp::verb::get, "/");
  REQUIRE(r.ok);
  CHECK(r.status == 200);
  CHECK(r.header("content-type").rfind("text/html", 0) == 0);
  CHECK(r.header("cache-control") == "no-cache");
  CHECK(r.body == "<!doctype html><title>rover</title>");

  r = call(s.port(), bhttp::verb::get, "/js/app.js");
  CHECK(r.status == 200);
  CHECK(r.header("content-type").rfind("text/javascript", 0) == 0);
  CHECK_FALSE(r.has("cache-control"));
  CHECK(r.body == "console.log(1);");

  r = call(s.port(), bhttp::verb::head, "/style.css");
  CHECK(r.status == 200);
  CHECK(r.header("content-length") == "6");
  CHECK(r.body.empty());

  r = call(s.port(), bhttp::verb::get, "/missing.js");
  CHECK(r.status == 404);
  CHECK(r.js()["error"]["code"] == "not_found");

  r = call(s.port(), bhttp::verb::get, "/api/anything");  // /api is never static, needs the token
  CHECK(r.status == 401);
}

TEST_CASE("static: path traversal never leaves the web root") {
  TempDir dir;
  writeFile(dir.path / "web" / "index.html", "index");
  writeFile(dir.path / "secret.txt", "TOP-SECRET");
  writeFile(dir.path / "web2" / "sibling.txt", "TOP-SECRET");
  TestServer s;
  s.config.webRoot = (dir.path / "web").string();
  s.start();
  const std::vector<std::string> targets = {
      "/../secret.txt",
      "/%2e%2e/secret.txt",
      "/%2E%2E%2Fsecret.txt",
      "/..%2fsecret.txt",
      "/js/../../secret.txt",
      "/../web2/sibling.txt",
      "/../../../../../../etc/passwd",
      "/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
      "/secret.txt%00.html",
  };
  for (const auto& t : targets) {
    CAPTURE(t);
    Client c(s.port());
    const std::string raw = c.raw("GET " + t + " HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n");
    const int status = statusOf(raw);
    CHECK((status == 400 || status == 404));
    CHECK(raw.find("TOP-SECRET") == std::string::npos);
    CHECK(raw.find("root:") == std::string::npos);
  }
}

TEST_CASE("static: a symlink inside the web root pointing outside gives 404") {
  TempDir dir;
  writeFile(dir.path / "web" / "index.html", "index");
  writeFile(dir.path / "outside" / "secret.txt", "TOP-SECRET");
  fs::create_symlink(dir.path / "outside" / "secret.txt", dir.path / "web" / "leak.txt");
  fs::create_directory_symlink(dir.path / "outside", dir.path / "web" / "leakdir");
  writeFile(dir.path / "web" / "real.txt", "fine");
  fs::create_symlink(dir.path / "web" / "real.txt", dir.path / "web" / "alias.txt");
  TestServer s;
  s.config.webRoot = (dir.path / "web").string();
  s.start();
  for (const std::string t : {"/leak.txt", "/leakdir/secret.txt"}) {
    CAPTURE(t);
    Reply r = call(s.port(), bhttp::verb::get, t);
    CHECK(r.status == 404);
    CHECK(r.body.find("TOP-SECRET") == std::string::npos);
  }
  Reply r = call(s.port(), bhttp::verb::get, "/alias.txt");  // inside the root: fine
  CHECK(r.status == 200);
  CHECK(r.body == "fine");
}

// ------------------------------------------------------------------------------ auth and CORS

TEST_CASE("http: bearer token on /api, open health route, constant answers") {
  TestServer s;
  s.config.token = "s3cret-token";
  s.router.add("GET", "/api/x", [](const Request&) { return Response::json(200, {{"x", 1}}); });
  RouteOptions open;
  open.requireAuth = false;
  s.router.add(
      "GET", "/api/health", [](const Request&) { return Response::json(200, {}); }, open);
  s.start();

  Reply r = call(s.port(), bhttp::verb::get, "/api/x");
  CHECK(r.status == 401);
  CHECK(r.header("www-authenticate") == "Bearer");
  CHECK(r.js()["error"]["code"] == "unauthorized");
  CHECK(
      call(s.port(), bhttp::verb::get, "/api/x", "", {{"Authorization", "Bearer wrong"}}).status ==
      401);
  CHECK(call(s.port(), bhttp::verb::get, "/api/x", "", {{"Authorization", "Bearer s3cret-tok"}})
            .status == 401);
  CHECK(
      call(s.port(), bhttp::verb::get, "/api/x", "", {{"Authorization", "s3cret-token"}}).status ==
      401);
  CHECK(call(s.port(), bhttp::verb::get, "/api/x?token=s3cret-token").status == 401);  // WS only
  r = call(s.port(), bhttp::verb::get, "/api/x", "", {{"Authorization", "Bearer s3cret-token"}});
  CHECK(r.status == 200);
  CHECK(r.js()["x"] == 1);
  CHECK(call(s.port(), bhttp::verb::get, "/api/health").status == 200);
  CHECK(call(s.port(), bhttp::verb::get, "/api/unknown").status == 401);  // no probing
}

TEST_CASE("http: CORS headers only with corsOrigin, OPTIONS preflight gives 204") {
  SUBCASE("off by default") {
    TestServer s;
    s.router.add("GET", "/api/x", [](const Request&) { return Response::json(200, {}); });
    s.start();
    Reply r = call(s.port(), bhttp::verb::get, "/api/x", "", {{"Origin", "http://evil.test"}});
    CHECK(r.status == 200);
    CHECK_FALSE(r.has("access-control-allow-origin"));
    CHECK(call(s.port(), bhttp::verb::options, "/api/x").status == 405);
  }
  SUBCASE("on") {
    TestServer s;
    s.config.corsOrigin = "http://localhost:5173";
    s.config.token = "t";
    s.router.add("GET", "/api/x", [](const Request&) { return Response::json(200, {}); });
    s.start();
    Reply r = call(s.port(), bhttp::verb::options, "/api/x", "",
                   {{"Origin", "http://localhost:5173"},
                    {"Access-Control-Request-Method", "GET"},
                    {"Access-Control-Request-Headers", "authorization"}});
    CHECK(r.status == 204);
    CHECK(r.header("access-control-allow-origin") == "http://localhost:5173");
    CHECK(r.header("access-control-allow-methods") == "GET, POST, PUT, PATCH, DELETE, OPTIONS");
    CHECK(r.header("access-control-allow-headers") == "Authorization, Content-Type");
    CHECK(r.body.empty());
    r = call(s.port(), bhttp::verb::get, "/api/x", "", {{"Authorization", "Bearer t"}});
    CHECK(r.status == 200);
    CHECK(r.header("access-control-allow-origin") == "http://localhost:5173");
    CHECK(r.header("vary") == "Origin");
    CHECK(r.header("access-control-expose-headers") ==
          "X-Total-Count, Link, Retry-After, Content-Disposition");
    r = call(s.port(), bhttp::verb::get, "/api/x");  // errors carry it too
    CHECK(r.status == 401);
    CHECK(r.header("access-control-allow-origin") == "http://localhost:5173");
  }
}

// ------------------------------------------------------------------------------- lifecycle

TEST_CASE("http: start throws when the port is in use, stop is idempotent") {
  TestServer a;
  a.start();
  Router router;
  ServerConfig cfg;
  cfg.host = "127.0.0.1";
  cfg.port = a.port();
  cfg.logRequests = false;
  HttpServer b(cfg, router);
  CHECK_THROWS_AS(b.start(), std::runtime_error);
  try {
    b.start();
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find(std::to_string(a.port())) != std::string::npos);
  }
  CHECK(a.port() != 0);
  a.stop();
  a.stop();
  b.stop();
}

TEST_CASE("http: stop closes idle keep-alive connections and open websockets promptly") {
  auto source = std::make_shared<QueueSource>();
  TestServer s;
  s.router.add("GET", "/api/ok", [](const Request&) { return Response::json(200, {}); });
  s.router.addWebSocket("/api/ws", [&](const Request&, std::shared_ptr<WsConnection>) {
    return std::static_pointer_cast<WsSource>(source);
  });
  s.start();
  Client idle(s.port());
  CHECK(idle.send(makeRequest(bhttp::verb::get, "/api/ok")).status == 200);
  WsClient ws;
  REQUIRE(ws.connect(s.port(), "/api/ws"));
  s.stop();  // returns (a hang fails the test run): sessions are closed, not waited for
  // Both clients see the server's close (the watchdog's bound only catches a hang).
  CHECK(ws.readAll(rover::test::kHangDeadline).empty());
  CHECK_FALSE(ws.hitDeadline);
  Watchdog dog(idle.socket.native_handle(), rover::test::kHangDeadline);
  CHECK_FALSE(idle.read().ok);
  CHECK_FALSE(dog.fired());
}

// ------------------------------------------------------------------------------- websockets

TEST_CASE("websocket: text and binary frames arrive in order, then a normal close") {
  TestServer s;
  std::string seenId;
  std::shared_ptr<QueueSource> source;
  s.router.addWebSocket("/api/missions/{id}/events",
                        [&](const Request& req, std::shared_ptr<WsConnection>) {
                          seenId = req.params.at("id");
                          auto src = std::make_shared<QueueSource>(5ms);
                          source = src;
                          src->push(text("one"));
                          src->push(text("two"));
                          src->push(text("three"));
                          src->push(WsFrame{true, std::string("\x00\x01\x02\xff", 4), false});
                          src->push(text("{\"type\":\"done\"}", true));
                          return src;
                        });
  s.start();
  WsClient c;
  REQUIRE(c.connect(s.port(), "/api/missions/m42/events"));
  int code = 0;
  auto msgs = c.readAll(rover::test::kHangDeadline, &code);
  CHECK(seenId == "m42");
  REQUIRE(msgs.size() == 5);
  CHECK(msgs[0].data == "one");
  CHECK(msgs[1].data == "two");
  CHECK(msgs[2].data == "three");
  CHECK_FALSE(msgs[2].binary);
  CHECK(msgs[3].binary);
  CHECK(msgs[3].data == std::string("\x00\x01\x02\xff", 4));
  CHECK(msgs[4].data == "{\"type\":\"done\"}");
  CHECK(code == static_cast<int>(websocket::close_code::normal));
  // One frame per ask, taken in the order they were pushed.
  CHECK(source->calls() == 5);
  CHECK(source->handed() == std::vector<std::string>{"one", "two", "three", std::string("\x00\x01\x02\xff", 4),
                                                     "{\"type\":\"done\"}"});
}

TEST_CASE("websocket: the next frame waits for the source's interval, which wake() does not cut short") {
  // An interval of an hour: the second frame is ready, but the session, pausing after the first,
  // must not ask for it before the server stops (an event, not a measured gap).
  TestServer s;
  std::mutex m;
  std::shared_ptr<QueueSource> source;
  std::shared_ptr<WsConnection> connection;
  s.router.addWebSocket("/api/ws", [&](const Request&, std::shared_ptr<WsConnection> conn) {
    std::lock_guard lock(m);
    source = std::make_shared<QueueSource>(std::chrono::hours(1));
    source->push(text("one"));
    source->push(text("two", true));
    connection = conn;
    return source;
  });
  s.start();
  WsClient c;
  REQUIRE(c.connect(s.port(), "/api/ws"));
  const auto first = c.readAll(rover::test::kHangDeadline, nullptr, 1);
  REQUIRE(first.size() == 1);
  CHECK(first[0].data == "one");
  {
    std::lock_guard lock(m);
    connection->wake();  // the session is pausing, not parked: nothing to pull early
  }
  s.stop();
  CHECK(c.readAll(rover::test::kHangDeadline).empty());
  CHECK_FALSE(c.hitDeadline);
  std::lock_guard lock(m);
  CHECK(source->calls() == 1);
  CHECK(source->handed() == std::vector<std::string>{"one"});
}

TEST_CASE("websocket: a source with nothing to say waits for wake() from another thread") {
  TestServer s;
  std::mutex m;
  std::shared_ptr<QueueSource> source;
  std::shared_ptr<WsConnection> connection;
  s.router.addWebSocket("/api/ws", [&](const Request&, std::shared_ptr<WsConnection> conn) {
    std::lock_guard lock(m);
    source = std::make_shared<QueueSource>(1ms);
    connection = conn;
    return source;
  });
  s.start();
  WsClient c;
  REQUIRE(c.connect(s.port(), "/api/ws"));
  std::thread producer([&] {
    std::shared_ptr<QueueSource> src;
    std::shared_ptr<WsConnection> conn;
    {
      std::lock_guard lock(m);
      src = source;
      conn = connection;
    }
    // Each frame is pushed once the session has asked and found nothing (parked): its first ask,
    // then one ask for each frame and one more after it. The bound only catches a hang.
    for (int i = 0; i < 3; ++i) {
      rover::test::pollUntil([&] { return src->calls() >= 2 * i + 1; });
      src->push(text(numbered("tick", i), i == 2));
      for (int k = 0; k < 5; ++k) conn->wake();  // coalesced
    }
  });
  int code = 0;
  auto msgs = c.readAll(rover::test::kHangDeadline, &code);
  producer.join();
  REQUIRE(msgs.size() == 3);
  CHECK(msgs[0].data == "tick0");
  CHECK(msgs[2].data == "tick2");
  CHECK(code == static_cast<int>(websocket::close_code::normal));
  // Asked once at start and about once per wake-up, not once per wake() call.
  CHECK(source->calls() <= 8);

  s.stop();
  s.server.reset();
  connection->wake();  // the server is gone: a no-op, not a crash
}

TEST_CASE("websocket: two clients on one route get their own streams") {
  TestServer s;
  std::atomic<int> n{0};
  s.router.addWebSocket("/api/ws/{name}", [&](const Request& req, std::shared_ptr<WsConnection>) {
    ++n;
    auto src = std::make_shared<QueueSource>(1ms);
    for (int i = 0; i < 10; ++i) src->push(text(numbered(req.params.at("name"), i)));
    src->push(text("end", true));
    return src;
  });
  s.start();
  WsClient a, b;
  REQUIRE(a.connect(s.port(), "/api/ws/a"));
  REQUIRE(b.connect(s.port(), "/api/ws/b"));
  auto ma = a.readAll(rover::test::kHangDeadline);
  auto mb = b.readAll(rover::test::kHangDeadline);
  CHECK(n == 2);
  REQUIRE(ma.size() == 11);
  REQUIRE(mb.size() == 11);
  for (int i = 0; i < 10; ++i) {
    CHECK(ma[static_cast<std::size_t>(i)].data == numbered("a", i));
    CHECK(mb[static_cast<std::size_t>(i)].data == numbered("b", i));
  }
}

TEST_CASE("websocket: a handler's ApiError is answered as HTTP, before any upgrade") {
  TestServer s;
  s.router.addWebSocket(
      "/api/missions/{id}/events",
      [](const Request& req, std::shared_ptr<WsConnection>) -> std::shared_ptr<WsSource> {
        throw ApiError(404, "not_found", "no mission " + req.params.at("id"));
      });
  s.router.addWebSocket(
      "/api/broken",
      [](const Request&, std::shared_ptr<WsConnection>) -> std::shared_ptr<WsSource> {
        throw std::runtime_error("nope");
      });
  s.start();
  WsClient c;
  CHECK_FALSE(c.connect(s.port(), "/api/missions/zz/events"));
  Reply r = upgradeRequest(s.port(), "/api/missions/zz/events");
  CHECK(r.status == 404);
  CHECK(r.js()["error"]["message"] == "no mission zz");

  WsClient d;
  CHECK_FALSE(d.connect(s.port(), "/api/broken"));
  r = upgradeRequest(s.port(), "/api/broken");
  CHECK(r.status == 500);
  CHECK(r.js()["error"]["message"] == "nope");

  // A plain GET on a WebSocket-only path says so.
  CHECK(call(s.port(), bhttp::verb::get, "/api/missions/zz/events").status == 426);
}

TEST_CASE("websocket: auth applies to upgrades, ?token= is accepted there") {
  TestServer s;
  s.config.token = "tok";
  s.router.addWebSocket("/api/ws", [](const Request&, std::shared_ptr<WsConnection>) {
    auto src = std::make_shared<QueueSource>();
    src->push(text("hi", true));
    return src;
  });
  s.start();
  WsClient none;
  CHECK_FALSE(none.connect(s.port(), "/api/ws"));
  CHECK(upgradeRequest(s.port(), "/api/ws").status == 401);
  WsClient wrong;
  CHECK_FALSE(wrong.connect(s.port(), "/api/ws?token=nope"));
  Reply r = upgradeRequest(s.port(), "/api/ws?token=nope");
  CHECK(r.status == 401);
  CHECK(r.header("www-authenticate") == "Bearer");
  WsClient query;
  REQUIRE(query.connect(s.port(), "/api/ws?token=tok"));
  CHECK(query.readAll(rover::test::kHangDeadline).size() == 1);
  WsClient header;
  REQUIRE(header.connect(s.port(), "/api/ws", "tok"));
  CHECK(header.readAll(rover::test::kHangDeadline).size() == 1);
}

// Says nothing; tells when the session lets go of it.
class GoneSource : public WsSource {
 public:
  explicit GoneSource(std::shared_ptr<std::promise<void>> gone) : gone_(std::move(gone)) {}
  ~GoneSource() override { gone_->set_value(); }
  std::optional<WsFrame> next() override { return std::nullopt; }

 private:
  std::shared_ptr<std::promise<void>> gone_;
};

TEST_CASE("websocket: beyond the per-stream or the global subscriber limit an upgrade gets 503 with Retry-After") {
  TestServer s;
  s.config.maxStreamSubscribers = 2;
  s.config.maxSubscribers = 3;
  std::atomic<int> handled{0};
  std::mutex m;
  std::vector<std::future<void>> gone;
  s.router.addWebSocket("/api/ws/{name}", [&](const Request&, std::shared_ptr<WsConnection>) {
    ++handled;
    auto promise = std::make_shared<std::promise<void>>();
    std::lock_guard lock(m);
    gone.push_back(promise->get_future());
    return std::static_pointer_cast<WsSource>(std::make_shared<GoneSource>(promise));
  });
  s.start();
  auto a = std::make_unique<WsClient>();
  WsClient b, c;
  REQUIRE(a->connect(s.port(), "/api/ws/x"));
  REQUIRE(b.connect(s.port(), "/api/ws/x"));
  Reply stream = upgradeRequest(s.port(), "/api/ws/x");  // a third on one stream
  CHECK(stream.status == 503);
  CHECK(stream.header("retry-after") == "5");
  CHECK(stream.js()["error"]["code"] == "too_many_subscribers");
  REQUIRE(c.connect(s.port(), "/api/ws/y"));  // another stream: room under the global limit
  Reply global = upgradeRequest(s.port(), "/api/ws/z");  // a fourth in all
  CHECK(global.status == 503);
  CHECK(global.header("retry-after") == "5");
  CHECK(global.js()["error"]["code"] == "too_many_subscribers");
  CHECK(handled == 3);  // the refused upgrades never reached the handler: nothing subscribed

  // A subscriber that leaves frees its place: once its session has let go of its source (the
  // event waited for; the bound only catches a hang), a new subscriber of that stream is let in.
  a->ws.close(websocket::close_code::normal);
  a.reset();
  std::future<void> first;
  {
    std::lock_guard lock(m);
    first = std::move(gone.front());
  }
  REQUIRE(first.wait_for(10s) == std::future_status::ready);
  WsClient d;
  CHECK(d.connect(s.port(), "/api/ws/x"));
  CHECK(handled == 4);
}

// Offers large frames forever, as fast as the session takes them.
class FloodSource : public WsSource {
 public:
  std::optional<WsFrame> next() override {
    ++calls;
    return WsFrame{true, std::string(2u << 20, 'f'), false};
  }
  std::chrono::milliseconds minInterval() const override { return 0ms; }
  std::atomic<int> calls{0};
};

TEST_CASE("websocket: a client that never reads does not stop another from getting frames") {
  TestServer s;
  auto flood = std::make_shared<FloodSource>();
  s.router.addWebSocket("/api/slow", [&](const Request&, std::shared_ptr<WsConnection>) {
    return std::static_pointer_cast<WsSource>(flood);
  });
  s.router.addWebSocket("/api/fast", [](const Request&, std::shared_ptr<WsConnection>) {
    auto src = std::make_shared<QueueSource>(1ms);
    for (int i = 0; i < 20; ++i) src->push(text(numbered("f", i)));
    src->push(text("end", true));
    return src;
  });
  s.router.add("GET", "/api/ok", [](const Request&) { return Response::json(200, {}); });
  s.start();

  WsClient slow;  // small receive buffer and never reads
  REQUIRE(slow.connect(s.port(), "/api/slow", "", 4096));
  // The slow session is writing (the event waited for); it stalls once the socket buffers fill.
  rover::test::waitUntil([&] { return flood->calls >= 1; }, "the slow session asks its source for a frame");

  WsClient fast;
  REQUIRE(fast.connect(s.port(), "/api/fast"));
  auto msgs = fast.readAll(rover::test::kHangDeadline);  // the bound only catches a hang
  CHECK_FALSE(fast.hitDeadline);
  CHECK(msgs.size() == 21);
  CHECK(call(s.port(), bhttp::verb::get, "/api/ok").status == 200);
  // Back-pressure: one write in flight and no queue, so while the fast client was served the
  // stuck session took no more 2 MiB frames than the socket buffers hold (a queue would take
  // hundreds).
  CHECK(flood->calls < 50);
  s.stop();  // must not hang on the stuck write
}
