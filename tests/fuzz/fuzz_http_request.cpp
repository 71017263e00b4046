// libFuzzer: bytes -> the request parsing of HttpSession, step for step: the header parser as
// configureHeaderParser() sets it up, checkFraming(), parseTarget() and checkBodyLength() on the
// header, then the body through a string parser with the body limit, a chunked body fed at most
// maxHeaderBytes per put() (the session's bound on chunk header lines and trailers). Nothing may
// throw past the try/catch the session has, crash, or read out of bounds.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

#include <boost/beast/http.hpp>

#include "server/http/http_server.hpp"
#include "server/http/request_framing.hpp"

namespace bhttp = boost::beast::http;
namespace net = boost::asio;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const rover::http::ServerConfig config;  // the defaults the server runs with
  const char* p = reinterpret_cast<const char*>(data);
  std::size_t left = size;
  // Pipelined requests on one connection, as the session loops (bounded by the input).
  for (int request = 0; request < 8 && left > 0; ++request) {
    try {
      bhttp::request_parser<bhttp::empty_body> header;
      rover::http::configureHeaderParser(header, config.maxHeaderBytes);
      boost::beast::error_code ec;
      const std::size_t used = header.put(net::buffer(p, left), ec);
      p += used;
      left -= used;
      if (ec || !header.is_header_done()) return 0;
      if (rover::http::checkFraming(header.get())) return 0;  // answered 400, connection closed
      std::string path;
      std::map<std::string, std::string> query;
      const auto target = header.get().target();
      if (!rover::http::parseTarget({target.data(), target.size()}, path, query)) return 0;

      if (rover::http::checkBodyLength(header.content_length(), config.maxBodyBytes))
        return 0;  // answered 413, connection closed
      bhttp::request_parser<bhttp::string_body> body(std::move(header));
      body.body_limit(config.maxBodyBytes);
      body.eager(true);
      while (!body.is_done()) {
        std::size_t n = left;
        if (body.chunked() && n > config.maxHeaderBytes) n = config.maxHeaderBytes;
        const std::size_t got = body.put(net::buffer(p, n), ec);
        p += got;
        left -= got;
        if (ec == bhttp::error::need_more) {
          if (got > 0 && left > 0) continue;
          return 0;  // the session would read more (or refuse an oversized element with 431)
        }
        if (ec) return 0;
        if (got == 0) return 0;
      }
      if (!body.get().keep_alive()) return 0;
    } catch (const std::exception&) {
      return 0;  // the session catches this too (400 and close)
    }
  }
  return 0;
}
