// `sesi view --serve` (serve.hpp): HTTP/1.1 (RFC 9112) on 127.0.0.1, one thread.
#include "serve.hpp"

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <string_view>
#include <vector>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include "errors.hpp"

namespace sesi::view {

namespace {

/// How long poll() waits before asking stop() again, and how long a connection may stay silent
/// before it is closed.
constexpr int poll_ms = 200;
constexpr int request_ms = 30000;
constexpr std::size_t max_request = 16384;
constexpr std::size_t max_pending = 64;

/// Sends all of text; false when the client went away (MSG_NOSIGNAL: no SIGPIPE then).
bool send_all(int fd, std::string_view text, const std::function<bool()>& stop) {
  while (!text.empty()) {
    const ssize_t sent = ::send(fd, text.data(), text.size(), MSG_NOSIGNAL);
    if (sent < 0) {
      if (errno == EINTR && !stop()) continue;
      return false;
    }
    text.remove_prefix(static_cast<std::size_t>(sent));
  }
  return true;
}

void answer(int fd, int status, std::string_view reason, std::string_view type, std::string_view body, bool head,
            const std::function<bool()>& stop) {
  std::string header = "HTTP/1.1 " + std::to_string(status) + " " + std::string(reason) + "\r\n";
  header += "Content-Type: " + std::string(type) + "\r\n";
  header += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  header += "Cache-Control: no-store\r\nConnection: close\r\n\r\n";
  if (send_all(fd, header, stop) && !head) send_all(fd, body, stop);
}

/// Answers one request (its head in request) on fd.
void respond(int client, const std::string& request, const std::string& page, const ViewData& data, Precision resolved,
             const std::function<bool()>& stop) {
  // The request line: METHOD SP TARGET SP VERSION (RFC 9112, 3).
  const std::size_t end = request.find("\r\n");
  const std::string_view line = std::string_view(request).substr(0, end == std::string::npos ? 0 : end);
  const std::size_t s1 = line.find(' '), s2 = s1 == std::string_view::npos ? s1 : line.find(' ', s1 + 1);
  if (s2 == std::string_view::npos) {
    answer(client, 400, "Bad Request", "text/plain", "bad request\n", false, stop);
    return;
  }
  const std::string_view method = line.substr(0, s1);
  std::string_view target = line.substr(s1 + 1, s2 - s1 - 1);
  target = target.substr(0, target.find_first_of("?#"));  // the page's own query (frame=, ...)
  const bool head = method == "HEAD";
  if (method != "GET" && !head) {
    answer(client, 405, "Method Not Allowed", "text/plain", "only GET\n", false, stop);
  } else if (target == "/" || target == "/view.html") {
    answer(client, 200, "OK", "text/html; charset=utf-8", page, head, stop);
  } else if (target.starts_with("/frames/")) {
    const std::string_view digits = target.substr(8);
    std::size_t k = 0;
    const auto [next, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), k);
    if (digits.empty() || ec != std::errc() || next != digits.data() + digits.size() || k >= data.x.size()) {
      answer(client, 404, "Not Found", "text/plain", "no such frame\n", head, stop);
    } else {
      answer(client, 200, "OK", "text/plain; charset=us-ascii", frame_line(data, k, resolved), head, stop);
    }
  } else {
    answer(client, 404, "Not Found", "text/plain", "not found\n", head, stop);
  }
}

/// A connection whose request is still coming. Browsers open connections ahead of use and may
/// send nothing on them for a while, so several are watched at once and none holds up the others.
struct Pending {
  int fd;
  std::string request;
  std::chrono::steady_clock::time_point since;
};

}  // namespace

Server::Server(int port) {
  const auto fail = [&](const std::string& what) {
    const std::string reason = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    throw program::InputError(program::Origin{}, "--port",
                              "cannot " + what + " 127.0.0.1:" + std::to_string(port) + ": " + reason);
  };
  if (port < 0 || port > 65535) {
    throw program::InputError(program::Origin{}, "--port", "expected a port 0 to 65535, got " + std::to_string(port));
  }
  fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) fail("open a socket for");
  const int yes = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);  // this machine only
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) fail("listen on");
  if (::listen(fd_, 16) != 0) fail("listen on");
  socklen_t size = sizeof address;
  if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &size) != 0) fail("find the port of");
  port_ = ntohs(address.sin_port);
}

Server::~Server() {
  if (fd_ >= 0) ::close(fd_);
}

void Server::run(const std::string& page, const ViewData& data, Precision resolved, const std::function<bool()>& stop) {
  std::vector<Pending> pending;
  std::vector<pollfd> watched;
  while (!stop()) {
    watched.assign(1, pollfd{fd_, POLLIN, 0});
    for (const Pending& c : pending) watched.push_back(pollfd{c.fd, POLLIN, 0});
    if (::poll(watched.data(), watched.size(), poll_ms) < 0 && errno != EINTR) break;
    if (stop()) break;  // a timeout or a signal (EINTR) comes back here to ask
    const auto now = std::chrono::steady_clock::now();
    std::vector<Pending> still;
    for (std::size_t k = 0; k < pending.size(); ++k) {
      Pending& c = pending[k];
      bool done = false;
      if (watched[k + 1].revents != 0) {
        char buffer[4096];
        const ssize_t got = ::recv(c.fd, buffer, sizeof buffer, MSG_DONTWAIT);
        if (got > 0) {
          c.request.append(buffer, static_cast<std::size_t>(got));
          if (c.request.find("\r\n\r\n") != std::string::npos || c.request.size() >= max_request) {
            respond(c.fd, c.request, page, data, resolved, stop);
            done = true;
          }
        } else if (got == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
          done = true;  // the client went away
        }
      }
      if (!done && now - c.since > std::chrono::milliseconds(request_ms)) done = true;  // silent too long
      if (done) {
        ::close(c.fd);
      } else {
        still.push_back(std::move(c));
      }
    }
    pending = std::move(still);
    if (watched[0].revents != 0 && pending.size() < max_pending) {
      const int client = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (client >= 0) {
        // A client that stops reading an answer gives up the server after this long.
        const timeval limit{request_ms / 1000, 0};
        ::setsockopt(client, SOL_SOCKET, SO_SNDTIMEO, &limit, sizeof limit);
        pending.push_back(Pending{client, {}, now});
      }
    }
  }
  for (const Pending& c : pending) ::close(c.fd);
}

}  // namespace sesi::view
