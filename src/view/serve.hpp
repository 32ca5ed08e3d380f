#pragma once
/// @file serve.hpp
/// `sesi view --serve` (issue #28): a small HTTP/1.1 server on 127.0.0.1 for runs too large to
/// pack into one page. GET / (or /view.html) answers the stream page, GET /frames/<k> frame line
/// k (text/plain, fetched by the page on demand); anything else is 404. One thread: the open
/// connections are watched together (poll), each answered in turn and closed after its answer
/// (Connection: close). POSIX sockets, no library.

#include <functional>
#include <string>

#include "view_page.hpp"

namespace sesi::view {

class Server {
 public:
  /// Listen on 127.0.0.1:port (0: a free port the system picks).
  /// @throws program::InputError naming --port when the address cannot be bound
  explicit Server(int port);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// The port listened on.
  int port() const { return port_; }

  /// Answer requests until stop() returns true (asked at least every 200 ms): page at / and
  /// /view.html, data's frame lines at /frames/<k>.
  void run(const std::string& page, const ViewData& data, Precision resolved, const std::function<bool()>& stop);

 private:
  int fd_ = -1;
  int port_ = 0;
};

}  // namespace sesi::view
