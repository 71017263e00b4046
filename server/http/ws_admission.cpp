#include "server/http/ws_admission.hpp"

namespace rover::http {

std::shared_ptr<void> WsAdmission::admit(const std::string& stream, std::size_t perStream,
                                         std::size_t global, std::string& refusal) {
  {
    std::lock_guard lock(mutex_);
    if (total_ >= global) {
      refusal = "the server has " + std::to_string(total_) + " live streams open, its limit: retry later";
      return nullptr;
    }
    std::size_t& n = perStream_[stream];
    if (n >= perStream) {
      refusal = "this stream has " + std::to_string(n) + " subscribers, its limit: retry later";
      return nullptr;
    }
    ++n;
    ++total_;
  }
  // The handle keeps the registry alive: a session may outlive the server's state by a moment.
  return std::shared_ptr<void>(static_cast<void*>(this),
                               [self = shared_from_this(), stream](void*) { self->release(stream); });
}

void WsAdmission::release(const std::string& stream) {
  std::lock_guard lock(mutex_);
  --total_;
  auto it = perStream_.find(stream);
  if (it != perStream_.end() && --it->second == 0) perStream_.erase(it);
}

std::size_t WsAdmission::total() const {
  std::lock_guard lock(mutex_);
  return total_;
}

}  // namespace rover::http
