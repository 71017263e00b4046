#pragma once
// A small synchronous HTTP and WebSocket client for loopback tests (Boost.Beast).
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace rover::test {

namespace beast = boost::beast;
namespace net = boost::asio;
using tcp = net::ip::tcp;

struct HttpResult {
  int status = 0;
  std::string body;
  std::map<std::string, std::string> headers;
  nlohmann::json json() const { return nlohmann::json::parse(body, nullptr, false); }
};

inline HttpResult request(unsigned short port, const std::string& method, const std::string& target,
                          const std::string& body = "", const std::string& contentType = "",
                          const std::map<std::string, std::string>& headers = {}) {
  net::io_context ioc;
  beast::tcp_stream stream(ioc);
  stream.expires_after(std::chrono::seconds(60));
  stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  beast::http::request<beast::http::string_body> req{beast::http::string_to_verb(method), target, 11};
  req.set(beast::http::field::host, "127.0.0.1");
  for (const auto& [k, v] : headers) req.set(k, v);
  if (!contentType.empty()) req.set(beast::http::field::content_type, contentType);
  req.body() = body;
  req.prepare_payload();
  beast::http::write(stream, req);
  beast::flat_buffer buffer;
  beast::http::response_parser<beast::http::string_body> parser;
  parser.body_limit(1ull << 30);
  beast::http::read(stream, buffer, parser);
  auto& res = parser.get();
  HttpResult out;
  out.status = static_cast<int>(res.result_int());
  out.body = res.body();
  for (const auto& f : res) out.headers[std::string(f.name_string())] = std::string(f.value());
  beast::error_code ec;
  stream.socket().shutdown(tcp::socket::shutdown_both, ec);
  return out;
}

struct WsFrameSeen {
  bool binary;
  std::string data;
};

// Connects to a WebSocket route and reads frames until the server closes (or the deadline).
inline std::vector<WsFrameSeen> readAllFrames(unsigned short port, const std::string& target,
                                              std::chrono::seconds deadline = std::chrono::seconds(30),
                                              std::size_t stopAfter = SIZE_MAX) {
  net::io_context ioc;
  beast::websocket::stream<beast::tcp_stream> ws(ioc);
  beast::get_lowest_layer(ws).expires_after(deadline);
  beast::get_lowest_layer(ws).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  ws.read_message_max(256ull << 20);
  ws.handshake("127.0.0.1", target);
  std::vector<WsFrameSeen> frames;
  while (frames.size() < stopAfter) {
    beast::flat_buffer b;
    beast::error_code ec;
    ws.read(b, ec);
    if (ec) break;
    frames.push_back({ws.got_binary(), beast::buffers_to_string(b.data())});
  }
  return frames;
}

}  // namespace rover::test
