// libFuzzer: bytes -> client WebSocket frames read by a server-role Beast stream configured by
// configureServerWebsocket() (what every WebsocketSession uses), over an in-memory stream. The
// server discards client messages, so what is fuzzed is the frame parsing under its limits:
// masking, fragmentation, control frames (ping/pong/close), UTF-8 checks, 64 KiB messages.
#include <cstddef>
#include <cstdint>
#include <string>

#include <boost/beast/_experimental/test/stream.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include "server/http/websocket_session.hpp"

namespace beast = boost::beast;
namespace websocket = boost::beast::websocket;
namespace net = boost::asio;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const rover::http::ServerConfig config;
  net::io_context ioc;
  beast::test::stream client(ioc), server(ioc);
  client.connect(server);
  websocket::stream<beast::test::stream&> ws(server);
  rover::http::configureServerWebsocket(ws, config);
  const std::string upgrade =
      "GET /api/missions/x/stream HTTP/1.1\r\nHost: localhost\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
  client.write_some(net::buffer(upgrade));
  beast::error_code ec;
  ws.accept(ec);
  if (ec) return 0;
  client.write_some(net::buffer(data, size));
  client.close();  // EOF after the fuzzed frames
  beast::flat_buffer buffer;
  // As WebsocketSession::readLoop: read in pieces and discard until the stream fails or closes,
  // counting the message's size; one over the limit is closed with 1009 as the session does.
  // Every piece or frame consumes input, so this ends (bounded again for safety).
  std::size_t message = 0;
  for (std::size_t i = 0; i <= size + 1 && !ec; ++i) {
    message += ws.read_some(buffer, 16 * 1024, ec);
    buffer.consume(buffer.size());
    if (ec) break;
    if (message > rover::http::kMaxClientMessageBytes) {
      ws.close(websocket::close_code::too_big, ec);
      break;
    }
    if (ws.is_message_done()) message = 0;
  }
  return 0;
}
