#pragma once
// How many WebSocket subscribers the server keeps (issue 22 item 2): at most `perStream` on one
// stream (one upgrade path, e.g. /api/missions/ID/stream) and `global` in all. An upgrade beyond
// either is refused before anything is subscribed (503 with Retry-After), so a crowd of sockets
// costs the server a short HTTP answer each, never a session, a source or a snapshot.
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

namespace rover::http {

class WsAdmission : public std::enable_shared_from_this<WsAdmission> {
 public:
  // A place held until the returned handle is released (the session holds it for its lifetime);
  // null when refused, with the reason in `refusal`.
  std::shared_ptr<void> admit(const std::string& stream, std::size_t perStream, std::size_t global,
                              std::string& refusal);
  std::size_t total() const;

 private:
  void release(const std::string& stream);
  mutable std::mutex mutex_;
  std::size_t total_ = 0;
  std::unordered_map<std::string, std::size_t> perStream_;
};

}  // namespace rover::http
