// A loopback TCP listener for tests that must prove a connection was (or was not) made, e.g. that
// a refused /vsicurl/ upload never reached the network. Shared by test_maps and test_server.
#pragma once

#include <arpa/inet.h>
#include <doctest/doctest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

namespace rover::test {

struct Listener {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  int port = 0;
  Listener() {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
    REQUIRE(::listen(fd, 8) == 0);
    socklen_t len = sizeof a;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
    port = ntohs(a.sin_port);
  }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;
  ~Listener() { ::close(fd); }
  // Whether a connection is waiting within `ms` milliseconds.
  bool contacted(int ms) const {
    pollfd p{fd, POLLIN, 0};
    return ::poll(&p, 1, ms) > 0;
  }
  // Connections waiting to be accepted after `ms` milliseconds (each accepted and closed).
  int connections(int ms) const {
    int n = 0;
    pollfd p{fd, POLLIN, 0};
    while (::poll(&p, 1, n == 0 ? ms : 0) > 0) {
      int c = ::accept(fd, nullptr, nullptr);
      if (c < 0) break;
      ::close(c);
      ++n;
    }
    return n;
  }
};

}  // namespace rover::test
