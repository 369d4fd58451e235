#include "moslam/viewer/server.h"

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <asio/steady_timer.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include "moslam/util/error.h"

namespace moslam::viewer {
namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;

// The longest Stop() waits for the browsers' close handshakes before the server thread ends (it
// ends as soon as every browser has answered; one that never answers is cut when the server is
// destroyed). A fixed 300 ms was too short under TSan on a loaded 2-core machine: the loop ended
// before the browser's answer was read, and the browser waited for its own 5 s timeout.
constexpr auto kCloseGrace = std::chrono::seconds(3);
// How often a browser that skipped the latest picture is looked at again: once it has read what
// it was behind on, it gets that picture, so the last one of a run (and a paused frame) always
// arrives, however slowly the browser reads.
constexpr auto kCatchUpInterval = std::chrono::milliseconds(250);
// A page that acknowledges the pictures it has drawn ({"cmd": "ack"}) has at most this many not
// yet acknowledged: the browser's own network stack reads the socket whatever the page keeps up
// with, so the bytes this server has not sent say nothing of how far behind a slow page is (a
// page drawing 6 pictures a second of a run at 20 frames/s fell seconds behind, its pause
// arriving after the run had ended).
constexpr int kMaxUnacknowledged = 2;

std::string ReadWhole(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInput("viewer: cannot read {} (three.js: apt-get install libjs-three)", path);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

}  // namespace

void ServerOptions::Check() const {
  if (host.empty()) ThrowInput("--viewer-host: empty address");
  if (port < 0 || port > 65535) ThrowInput("--viewer: port {} is outside 0..65535", port);
  if (max_buffered_bytes == 0) ThrowInput("viewer.max_buffered_bytes: must be > 0");
  if (max_message_bytes == 0) ThrowInput("viewer.max_message_bytes: must be > 0");
}

class Server::Impl {
 public:
  Impl(const ServerOptions& options, CommandHandler on_command)
      : options_((options.Check(), options)), on_command_(std::move(on_command)) {
    files_["/three.min.js"] = ReadWhole(options.three_dir + "/build/three.min.js");
    files_["/OrbitControls.js"] =
        ReadWhole(options.three_dir + "/examples/js/controls/OrbitControls.js");
    // websocketpp logs to std::cout by default; the library's log is spdlog.
    ws_.clear_access_channels(websocketpp::log::alevel::all);
    ws_.clear_error_channels(websocketpp::log::elevel::all);
    ws_.init_asio();
    ws_.set_reuse_addr(true);
    ws_.set_max_message_size(options.max_message_bytes);
    ws_.set_http_handler([this](Handle h) { OnHttp(h); });
    ws_.set_open_handler([this](Handle h) { OnOpen(h); });
    ws_.set_close_handler([this](Handle h) { OnClose(h); });
    ws_.set_fail_handler([this](Handle h) { OnClose(h); });
    ws_.set_message_handler([this](Handle h, WsServer::message_ptr m) { OnMessage(h, m); });
    Listen();
    thread_ = std::thread([this] { Run(); });
  }

  ~Impl() { Stop(); }

  void Stop() {
    std::call_once(stopped_, [this] {
      asio::post(ws_.get_io_service(), [this] {
        websocketpp::lib::error_code ec;
        ws_.stop_listening(ec);
        for (const Handle& h : clients_) {
          ws_.close(h, websocketpp::close::status::going_away, "", ec);
          if (!ec) closing_.insert(h);
        }
        clients_.clear();
        behind_.clear();
        unacknowledged_.clear();
        stopping_ = true;
        if (catch_up_timer_) catch_up_timer_->cancel();
        stats_.clients = 0;
        signals_.reset();
        // The close frames get a moment to leave; then the loop ends, whoever still hangs on.
        stop_timer_ = std::make_unique<asio::steady_timer>(ws_.get_io_service(), kCloseGrace);
        stop_timer_->async_wait([this](const asio::error_code&) { ws_.stop(); });
        if (closing_.empty()) ws_.stop();
      });
      if (thread_.joinable()) thread_.join();
    });
  }

  void Post(std::function<void()> task) { asio::post(ws_.get_io_service(), std::move(task)); }

  void Broadcast(std::shared_ptr<const std::string> message, bool binary, bool keep) {
    const auto opcode =
        binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text;
    for (const Handle& h : clients_) {
      const bool sent = Send(h, *message, opcode);
      if (binary && keep) {
        if (sent) {
          behind_.erase(h);
        } else {
          behind_.insert(h);
        }
      }
    }
    if (keep) (binary ? kept_binary_ : kept_text_) = std::move(message);
    if (!behind_.empty()) ArmCatchUp();
  }

  int WaitForStopSignal() {
    // Made and waited on in the server thread, which owns it; the promise is shared so that the
    // handler may still hold it when this thread has returned.
    auto received = std::make_shared<std::promise<int>>();
    std::future<int> future = received->get_future();
    Post([this, received] {
      signals_ = std::make_unique<asio::signal_set>(ws_.get_io_service(), SIGINT, SIGTERM);
      signals_->async_wait([received](const asio::error_code& ec, int signal) {
        received->set_value(ec ? 0 : signal);
      });
    });
    return future.get();
  }

  int port() const { return port_; }
  const ServerOptions& options() const { return options_; }
  const ServerStats& stats() const { return stats_; }

 private:
  void Listen() {
    websocketpp::lib::error_code ec;
    const asio::ip::address address = asio::ip::make_address(options_.host, ec);
    if (ec) ThrowInput("--viewer-host: '{}' is no IP address ({})", options_.host, ec.message());
    ws_.listen(asio::ip::tcp::endpoint(address, static_cast<uint16_t>(options_.port)), ec);
    if (ec) {
      ThrowInput("--viewer: cannot listen on {}:{} ({}; another port: --viewer PORT)",
                 options_.host, options_.port, ec.message());
    }
    ws_.start_accept(ec);
    const auto endpoint = ws_.get_local_endpoint(ec);
    port_ = ec ? options_.port : endpoint.port();
  }

  void Run() {
    try {
      ws_.run();
    } catch (const std::exception& e) {
      spdlog::error("viewer server stopped: {}", e.what());
    }
  }

  // Whether `message` went to the connection (false: skipped, it is too far behind, or gone).
  bool Send(const Handle& h, const std::string& message, websocketpp::frame::opcode::value op) {
    websocketpp::lib::error_code ec;
    WsServer::connection_ptr con = ws_.get_con_from_hdl(h, ec);
    if (ec || !con) return false;
    const bool binary = op == websocketpp::frame::opcode::binary;
    const auto acks = binary ? unacknowledged_.find(h) : unacknowledged_.end();
    if (con->get_buffered_amount() > options_.max_buffered_bytes ||
        (acks != unacknowledged_.end() && acks->second >= kMaxUnacknowledged)) {
      ++stats_.skipped;
      return false;
    }
    con->send(message, op);
    if (acks != unacknowledged_.end()) ++acks->second;
    ++stats_.sent;
    return true;
  }

  // A page has drawn a picture: from now on it gets a new one only while fewer than
  // kMaxUnacknowledged are undrawn, and the latest one at once if it skipped it.
  void OnAcknowledged(const Handle& h) {
    ++stats_.acknowledged;
    int& undrawn = unacknowledged_[h];
    undrawn = std::max(0, undrawn - 1);
    if (behind_.count(h) > 0 && kept_binary_ &&
        Send(h, *kept_binary_, websocketpp::frame::opcode::binary)) {
      behind_.erase(h);
    }
  }

  // Server thread: the browsers that skipped the kept picture get it once they have caught up.
  void ArmCatchUp() {
    if (catch_up_armed_ || stopping_) return;
    catch_up_armed_ = true;
    if (!catch_up_timer_)
      catch_up_timer_ = std::make_unique<asio::steady_timer>(ws_.get_io_service());
    catch_up_timer_->expires_after(kCatchUpInterval);
    catch_up_timer_->async_wait([this](const asio::error_code& ec) {
      catch_up_armed_ = false;
      if (ec || stopping_ || !kept_binary_) return;
      for (auto it = behind_.begin(); it != behind_.end();) {
        websocketpp::lib::error_code error;
        if (!ws_.get_con_from_hdl(*it, error) || error ||
            Send(*it, *kept_binary_, websocketpp::frame::opcode::binary)) {
          it = behind_.erase(it);
        } else {
          ++it;
        }
      }
      if (!behind_.empty()) ArmCatchUp();
    });
  }

  void OnHttp(Handle h) {
    WsServer::connection_ptr con = ws_.get_con_from_hdl(h);
    std::string path = con->get_resource();
    path = path.substr(0, path.find('?'));
    const Resource* page = FindResource(path);
    const auto file = files_.find(path);
    if (page != nullptr || file != files_.end()) {
      con->set_status(websocketpp::http::status_code::ok);
      con->set_body(page != nullptr ? page->body : file->second);
      con->append_header("Content-Type",
                         page != nullptr ? page->type : "text/javascript; charset=utf-8");
      con->append_header("Cache-Control", "no-cache");
      return;
    }
    ++stats_.http_not_found;
    con->set_status(websocketpp::http::status_code::not_found);
    con->set_body("not found\n");
    con->append_header("Content-Type", "text/plain");
  }

  void OnOpen(Handle h) {
    if (stopping_) {
      // Its handshake finished after Stop() had closed the others (the browser may already
      // think itself connected): it is closed like them.
      websocketpp::lib::error_code ec;
      ws_.close(h, websocketpp::close::status::going_away, "", ec);
      if (!ec) closing_.insert(h);
      return;
    }
    clients_.insert(h);
    stats_.clients = clients_.size();
    if (kept_text_) Send(h, *kept_text_, websocketpp::frame::opcode::text);
    if (kept_binary_) Send(h, *kept_binary_, websocketpp::frame::opcode::binary);
  }

  void OnClose(Handle h) {
    if (stopping_ && closing_.erase(h) > 0 && closing_.empty()) ws_.stop();
    clients_.erase(h);
    behind_.erase(h);
    unacknowledged_.erase(h);
    stats_.clients = clients_.size();
  }

  void OnMessage(Handle h, const WsServer::message_ptr& message) {
    if (message->get_opcode() != websocketpp::frame::opcode::text) {
      ++stats_.ignored;
      websocketpp::lib::error_code ec;
      ws_.close(h, websocketpp::close::status::unsupported_data, "commands are text", ec);
      return;
    }
    const nlohmann::json command = nlohmann::json::parse(message->get_payload(), nullptr, false);
    if (command.is_discarded() || !command.is_object() || !command.contains("cmd") ||
        !command["cmd"].is_string()) {
      ++stats_.ignored;
      spdlog::debug("viewer: ignored a message that is no command");
      return;
    }
    if (command["cmd"] == "ack") {
      OnAcknowledged(h);  // the server's own: flow control, not a command of the viewer's
      return;
    }
    if (on_command_) on_command_(command);
  }

  const ServerOptions options_;
  CommandHandler on_command_;
  std::map<std::string, std::string> files_;
  WsServer ws_;
  // WaitForStopSignal's and Stop()'s; declared after ws_, so gone before its io service.
  std::unique_ptr<asio::signal_set> signals_;
  std::unique_ptr<asio::steady_timer> stop_timer_;
  std::unique_ptr<asio::steady_timer> catch_up_timer_;  // ArmCatchUp's
  std::thread thread_;
  std::once_flag stopped_;
  int port_ = 0;
  ServerStats stats_;
  // Server thread only.
  std::set<Handle, std::owner_less<Handle>> clients_;
  // Clients that skipped the kept binary message (Broadcast), and whether a look is due.
  std::set<Handle, std::owner_less<Handle>> behind_;
  // Pages that acknowledge what they draw (OnAcknowledged): pictures sent and not yet drawn.
  std::map<Handle, int, std::owner_less<Handle>> unacknowledged_;
  // Once stopping: the browsers sent a close frame whose handshake has not ended.
  std::set<Handle, std::owner_less<Handle>> closing_;
  bool catch_up_armed_ = false;
  bool stopping_ = false;
  std::shared_ptr<const std::string> kept_binary_, kept_text_;
};

Server::Server(const ServerOptions& options, CommandHandler on_command)
    : impl_(std::make_unique<Impl>(options, std::move(on_command))) {}
Server::~Server() = default;
int Server::port() const { return impl_->port(); }
std::string Server::url() const {
  return fmt::format("http://{}:{}/", impl_->options().host, impl_->port());
}
const ServerStats& Server::stats() const { return impl_->stats(); }
void Server::Post(std::function<void()> task) { impl_->Post(std::move(task)); }
void Server::Broadcast(std::shared_ptr<const std::string> message, bool binary, bool keep) {
  impl_->Broadcast(std::move(message), binary, keep);
}
void Server::Stop() { impl_->Stop(); }
int Server::WaitForStopSignal() { return impl_->WaitForStopSignal(); }

}  // namespace moslam::viewer
