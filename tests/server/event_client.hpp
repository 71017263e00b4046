#pragma once
// A blocking WebSocket client of WS /api/events for the API tests (test_events_api.cpp,
// test_collab_api.cpp, test_study_api.cpp): it reads the stream's JSON messages one by one.
#include <string>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

namespace rover::test {

using nlohmann::json;

namespace beast = boost::beast;
namespace net = boost::asio;

// One subscriber: a blocking WebSocket client reading the stream's JSON messages.
struct EventClient {
  net::io_context ioc;
  beast::websocket::stream<beast::tcp_stream> ws{ioc};
  explicit EventClient(unsigned short port, const std::string& target) {
    beast::get_lowest_layer(ws).connect(net::ip::tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    ws.handshake("127.0.0.1", target);
  }
  // The next message, null once the server closed.
  json next() {
    beast::flat_buffer b;
    beast::error_code ec;
    ws.read(b, ec);
    if (ec) return nullptr;
    return json::parse(beast::buffers_to_string(b.data()), nullptr, false);
  }
  // The next message of `type` (events of other types skipped), null on close.
  json nextOf(const std::string& type) {
    for (int i = 0; i < 100000; ++i) {
      json m = next();
      if (m.is_null() || m.value("type", "") == type) return m;
    }
    return nullptr;
  }
  void send(const json& j) {
    ws.text(true);
    ws.write(net::buffer(j.dump()));
  }
};

}  // namespace rover::test
