// Test support for the viewer's tests, benchmark and browser test: an HTTP GET over a raw socket,
// a raw WebSocket client that connects and then never reads (a stalled browser), and a
// websocketpp client in a thread of its own that collects what it is sent.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

namespace moslam::viewer::testing {

// A connected TCP socket to 127.0.0.1:port, closed on destruction; fd -1 when it failed.
class RawSocket {
 public:
  explicit RawSocket(int port, int receive_buffer = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (receive_buffer > 0) {
      ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
    }
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~RawSocket() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawSocket(const RawSocket&) = delete;
  RawSocket& operator=(const RawSocket&) = delete;
  bool Send(const std::string& bytes) {
    return fd_ >= 0 && ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) ==
                           static_cast<ssize_t>(bytes.size());
  }
  // Everything until the peer closes (HTTP/1.0 style) or `limit` bytes.
  std::string ReadAll(size_t limit = 64u << 20) {
    std::string out;
    char buffer[65536];
    while (fd_ >= 0 && out.size() < limit) {
      const ssize_t n = ::recv(fd_, buffer, std::min(sizeof buffer, limit - out.size()), 0);
      if (n <= 0) break;
      out.append(buffer, static_cast<size_t>(n));
    }
    return out;
  }
  // Reads up to the end of the HTTP headers (a WebSocket handshake's answer).
  std::string ReadHeaders() {
    std::string out;
    char c = 0;
    while (fd_ >= 0 && out.find("\r\n\r\n") == std::string::npos && ::recv(fd_, &c, 1, 0) == 1) {
      out.push_back(c);
    }
    return out;
  }
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

struct HttpResponse {
  int status = 0;
  std::string body;
};

// Polls `done` every 10 ms until it holds or `timeout` passes: for state that changes in another
// process or thread without notifying anyone (tests only).
inline bool PollUntil(const std::function<bool()>& done,
                      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

inline HttpResponse HttpGet(int port, const std::string& path) {
  RawSocket socket(port);
  socket.Send("GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
              "\r\nConnection: close\r\n\r\n");
  HttpResponse response;
  const std::string headers = socket.ReadHeaders();
  if (headers.size() > 12 && headers.compare(0, 5, "HTTP/") == 0) {
    response.status = std::stoi(headers.substr(9, 3));
  }
  // Not every server closes after the reply (Chromium's DevTools one does not): read what
  // Content-Length says when there is one.
  std::string lower = headers;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const size_t length = lower.find("content-length:");
  if (length == std::string::npos) {
    response.body = socket.ReadAll();
  } else {
    response.body = socket.ReadAll(std::stoul(headers.substr(length + 15)));
  }
  return response;
}

// Opens a WebSocket on `path` over a raw socket with a small receive buffer and never reads what
// it is sent: the browser that stopped reading. Returns the handshake's reply headers.
inline std::string StalledWebSocket(RawSocket* socket, const std::string& path = "/") {
  socket->Send("GET " + path +
               " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
  return socket->ReadHeaders();
}

// A websocketpp client in its own thread; every message it receives is kept.
class WsClient {
 public:
  using Client = websocketpp::client<websocketpp::config::asio_client>;
  struct Message {
    bool binary = false;
    std::string payload;
  };

  explicit WsClient(const std::string& uri) {
    client_.clear_access_channels(websocketpp::log::alevel::all);
    client_.clear_error_channels(websocketpp::log::elevel::all);
    client_.init_asio();
    client_.set_open_handler(
        [this](websocketpp::connection_hdl) { Set([this] { open_ = true; }); });
    client_.set_close_handler([this](websocketpp::connection_hdl h) {
      const int code = client_.get_con_from_hdl(h)->get_remote_close_code();
      Set([this, code] {
        closed_ = true;
        close_code_ = code;
      });
    });
    client_.set_fail_handler([this](websocketpp::connection_hdl h) {
      const auto con = client_.get_con_from_hdl(h);
      const std::string why =
          con->get_ec().message() + " (HTTP " + std::to_string(con->get_response_code()) + ")";
      Set([this, why] {
        closed_ = true;
        failure_ = why;
      });
    });
    client_.set_message_handler([this](websocketpp::connection_hdl, Client::message_ptr m) {
      Message message{m->get_opcode() == websocketpp::frame::opcode::binary, m->get_payload()};
      Set([this, &message] { messages_.push_back(std::move(message)); });
    });
    websocketpp::lib::error_code ec;
    Client::connection_ptr con = client_.get_connection(uri, ec);
    if (!ec) {
      handle_ = con->get_handle();
      client_.connect(con);
    }
    thread_ = std::thread([this] { client_.run(); });
  }
  ~WsClient() {
    Close();
    client_.stop();
    thread_.join();
  }
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  // Waits (up to `timeout`) until `done` holds for the client's state; returns whether it did.
  bool WaitUntil(const std::function<bool()>& done,
                 std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, timeout, done);
  }
  bool WaitOpen() {
    return WaitUntil([this] { return open_ || closed_; }) && open_;
  }
  // Waits for the n-th message (1-based count).
  bool WaitMessages(size_t n, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    return WaitUntil([this, n] { return messages_.size() >= n; }, timeout);
  }
  bool WaitClosed() {
    return WaitUntil([this] { return closed_; });
  }
  void Send(const std::string& payload, bool binary = false) {
    client_.get_io_service().post([this, payload, binary] {
      websocketpp::lib::error_code ec;
      client_.send(handle_, payload,
                   binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text,
                   ec);
    });
  }
  void Close() {
    client_.get_io_service().post([this] {
      websocketpp::lib::error_code ec;
      client_.close(handle_, websocketpp::close::status::normal, "", ec);
    });
  }
  std::vector<Message> messages() {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  bool closed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_;
  }
  // Why the connection could not be opened; empty when it was.
  std::string failure() {
    std::lock_guard<std::mutex> lock(mutex_);
    return failure_;
  }
  int close_code() {
    std::lock_guard<std::mutex> lock(mutex_);
    return close_code_;
  }
  // Waits for a message `match` accepts (any received so far counts).
  bool WaitForMessage(const std::function<bool(const Message&)>& match,
                      std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    return WaitUntil(
        [this, &match] {
          for (const Message& m : messages_) {
            if (match(m)) return true;
          }
          return false;
        },
        timeout);
  }

 private:
  template <typename F>
  void Set(F update) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      update();
    }
    changed_.notify_all();
  }

  Client client_;
  websocketpp::connection_hdl handle_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool open_ = false, closed_ = false;
  int close_code_ = 0;
  std::string failure_;
  std::vector<Message> messages_;
};

}  // namespace moslam::viewer::testing
