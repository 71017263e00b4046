#include "server/http/response_message.hpp"

#include <utility>

namespace rover::http {

namespace beast = boost::beast;
namespace bhttp = boost::beast::http;

bool bodyless(int status) {
  return status < 200 || status == 204 || status == 304;
}

ResponseMessage responseMessage(Response res, const ResponseFraming& framing, const ServerConfig& config) {
  if (bodyless(res.status)) {
    res.body.clear();
    res.file.clear();
  }
  auto decorate = [&](auto& msg) {
    msg.result(static_cast<unsigned>(res.status));
    msg.version(framing.version);
    msg.set(bhttp::field::server, "roverplan");
    if (!res.contentType.empty() && !bodyless(res.status))
      msg.set(bhttp::field::content_type, res.contentType);
    for (const auto& [name, value] : res.headers) msg.insert(name, value);
    if (!config.corsOrigin.empty()) {
      msg.set(bhttp::field::access_control_allow_origin, config.corsOrigin);
      msg.set(bhttp::field::vary, "Origin");
      // Without this a cross-origin client cannot read how listings are paged.
      msg.set(bhttp::field::access_control_expose_headers,
              "X-Total-Count, Link, Retry-After, Content-Disposition");
    }
    msg.keep_alive(framing.keepAlive);
  };

  if (!res.file.empty()) {
    bhttp::file_body::value_type body;
    beast::error_code ec;
    body.open(res.file.c_str(), beast::file_mode::scan, ec);
    if (ec) {
      res = Response::error(404, "not_found", "file not found", "path");
    } else {
      const std::uint64_t size = body.size();
      if (framing.head) {
        auto msg = std::make_shared<bhttp::response<bhttp::empty_body>>();
        decorate(*msg);
        msg->content_length(size);
        return {std::move(msg), res.status, 0};
      }
      auto msg = std::make_shared<bhttp::response<bhttp::file_body>>();
      decorate(*msg);
      msg->body() = std::move(body);
      msg->prepare_payload();
      return {std::move(msg), res.status, size};
    }
  }
  auto msg = std::make_shared<bhttp::response<bhttp::string_body>>();
  decorate(*msg);
  const std::uint64_t size = res.body.size();
  if (framing.head) {
    if (!bodyless(res.status)) msg->content_length(size);
    return {std::move(msg), res.status, 0};
  }
  msg->body() = std::move(res.body);
  if (!bodyless(res.status)) msg->prepare_payload();
  return {std::move(msg), res.status, size};
}

}  // namespace rover::http
