#include "moslam/viewer/server.h"

#include <atomic>
#include <chrono>
#include <future>
#include <string>

#include <gtest/gtest.h>

#include "moslam/util/error.h"
#include "moslam/viewer/test_client.h"

namespace moslam::viewer {
namespace {

using testing::HttpGet;
using testing::RawSocket;
using testing::WsClient;

ServerOptions AnyPort() {
  ServerOptions options;
  options.port = 0;
  return options;
}

std::string WsUrl(const Server& server) {
  return "ws://127.0.0.1:" + std::to_string(server.port()) + "/";
}

// Runs `task` in the server thread and waits for it.
void InServerThread(Server& server, std::function<void()> task) {
  std::promise<void> done;
  server.Post([&] {
    task();
    done.set_value();
  });
  done.get_future().wait();
}

bool WaitClients(const Server& server, size_t n) {
  return testing::PollUntil([&] { return server.clients() == n; });
}

TEST(ViewerServer, ServesThePageThreeJsAnd404) {
  Server server(AnyPort(), nullptr);
  const auto index = HttpGet(server.port(), "/");
  EXPECT_EQ(index.status, 200);
  EXPECT_NE(index.body.find("moslam viewer"), std::string::npos);
  EXPECT_EQ(HttpGet(server.port(), "/viewer.js?v=1").status, 200);
  const auto three = HttpGet(server.port(), "/three.min.js");
  EXPECT_EQ(three.status, 200);
  EXPECT_GT(three.body.size(), 100000u);
  EXPECT_EQ(HttpGet(server.port(), "/OrbitControls.js").status, 200);
  EXPECT_EQ(HttpGet(server.port(), "/nothing-here").status, 404);
  EXPECT_EQ(HttpGet(server.port(), "/../../etc/passwd").status, 404);
  EXPECT_EQ(server.stats().http_not_found.load(), 2u);
  // Not HTTP at all: the connection is dropped, the server goes on.
  {
    RawSocket junk(server.port());
    junk.Send("\x16\x03\x01 not http\r\n\r\n");
    junk.ReadAll();
  }
  EXPECT_EQ(HttpGet(server.port(), "/").status, 200);
}

TEST(ViewerServer, BadOptionsAndATakenPortAreInputErrors) {
  ServerOptions bad = AnyPort();
  bad.port = 70000;
  EXPECT_THROW(Server(bad, nullptr), InputError);
  bad = AnyPort();
  bad.host = "not-an-address";
  EXPECT_THROW(Server(bad, nullptr), InputError);
  bad = AnyPort();
  bad.three_dir = "/nonexistent";
  EXPECT_THROW(Server(bad, nullptr), InputError);
  Server first(AnyPort(), nullptr);
  ServerOptions same = AnyPort();
  same.port = first.port();
  EXPECT_THROW(Server(same, nullptr), InputError);
}

TEST(ViewerServer, SeveralClientsAndADisconnectChangeNothing) {
  Server server(AnyPort(), nullptr);
  WsClient a(WsUrl(server)), b(WsUrl(server));
  ASSERT_TRUE(a.WaitOpen());
  ASSERT_TRUE(b.WaitOpen());
  ASSERT_TRUE(WaitClients(server, 2));
  auto message = std::make_shared<const std::string>("first");
  InServerThread(server, [&] { server.Broadcast(message, /*binary=*/true); });
  EXPECT_TRUE(a.WaitMessages(1));
  EXPECT_TRUE(b.WaitMessages(1));
  b.Close();
  ASSERT_TRUE(WaitClients(server, 1));
  InServerThread(server,
                 [&] { server.Broadcast(std::make_shared<const std::string>("second"), true); });
  ASSERT_TRUE(a.WaitMessages(2));
  EXPECT_EQ(a.messages()[1].payload, "second");
  // A browser connecting later is sent the kept picture at once.
  WsClient c(WsUrl(server));
  ASSERT_TRUE(c.WaitMessages(1));
  EXPECT_EQ(c.messages()[0].payload, "second");
}

TEST(ViewerServer, MalformedMessagesAreIgnoredOrClosed) {
  std::atomic<int> commands{0};
  Server server(AnyPort(), [&](const nlohmann::json& c) {
    if (c["cmd"] == "pause") ++commands;
  });
  WsClient client(WsUrl(server));
  ASSERT_TRUE(client.WaitOpen());
  for (const char* junk : {"", "garbage", "{}", "[1,2]", "{\"cmd\": 5}", "{\"cmd\":", "\"cmd\""}) {
    client.Send(junk);
  }
  client.Send("{\"cmd\": \"pause\"}");
  ASSERT_TRUE(testing::PollUntil([&] { return commands.load() == 1; }));
  EXPECT_EQ(server.stats().ignored.load(), 7u);
  EXPECT_FALSE(client.closed());
  // A binary message is no command: its connection is closed.
  client.Send(std::string("\0\1\2", 3), /*binary=*/true);
  ASSERT_TRUE(client.WaitClosed());
  EXPECT_EQ(client.close_code(), 1003);
  // So is one longer than any command.
  WsClient big(WsUrl(server));
  ASSERT_TRUE(big.WaitOpen());
  big.Send(std::string(100000, 'x'));
  ASSERT_TRUE(big.WaitClosed());
  EXPECT_EQ(big.close_code(), 1009);
  // The server goes on.
  WsClient good(WsUrl(server));
  ASSERT_TRUE(good.WaitOpen());
  good.Send("{\"cmd\": \"pause\"}");
  EXPECT_TRUE(testing::PollUntil([&] { return commands.load() == 2; }));
}

TEST(ViewerServer, AStalledClientIsSkippedNotWaitedFor) {
  ServerOptions options = AnyPort();
  options.max_buffered_bytes = 1u << 20;
  Server server(options, nullptr);
  RawSocket stalled(server.port(), /*receive_buffer=*/4096);
  const std::string handshake = testing::StalledWebSocket(&stalled);
  ASSERT_NE(handshake.find("101"), std::string::npos) << handshake;
  WsClient reader(WsUrl(server));
  ASSERT_TRUE(reader.WaitOpen());
  ASSERT_TRUE(WaitClients(server, 2));
  const auto big = std::make_shared<const std::string>(std::string(512 * 1024, 'm'));
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 100; ++i) {
    InServerThread(server, [&] { server.Broadcast(big, true, /*keep=*/false); });
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 10.0);
  EXPECT_GT(server.stats().skipped.load(), 50u);  // the stalled one got a few, then none
  // The reader is skipped while it is behind too; once it has caught up it gets the next one.
  const auto last = std::make_shared<const std::string>("last");
  EXPECT_TRUE(testing::PollUntil(
      [&] {
        InServerThread(server, [&] { server.Broadcast(last, true, false); });
        return reader.WaitForMessage([](const auto& m) { return m.payload == "last"; },
                                     std::chrono::milliseconds(100));
      },
      std::chrono::seconds(60)));
}

// The kept picture (the latest frame; at the end of a run the final one) is not lost to a browser
// that was behind when it was broadcast: it follows once the browser has read the rest, with no
// later broadcast needed.
TEST(ViewerServer, TheKeptPictureReachesABrowserThatWasBehind) {
  ServerOptions options = AnyPort();
  options.max_buffered_bytes = 1u << 20;
  Server server(options, nullptr);
  WsClient reader(WsUrl(server));
  ASSERT_TRUE(reader.WaitOpen());
  ASSERT_TRUE(WaitClients(server, 1));
  const auto big = std::make_shared<const std::string>(std::string(512 * 1024, 'm'));
  const auto last = std::make_shared<const std::string>("last");
  size_t skipped = 0;
  InServerThread(server, [&] {
    for (int i = 0; i < 20; ++i) server.Broadcast(big, true, /*keep=*/false);
    skipped = server.stats().skipped.load();
    server.Broadcast(last, true, /*keep=*/true);
    skipped = server.stats().skipped.load() - skipped;
  });
  EXPECT_EQ(skipped, 1u) << "the reader was not behind: the test tests nothing";
  EXPECT_TRUE(reader.WaitForMessage([](const auto& m) { return m.payload == "last"; },
                                    std::chrono::seconds(60)));
}

// A page that acknowledges what it draws has at most two pictures undrawn; the ones broadcast
// meanwhile are skipped, and its next acknowledgement brings the latest.
TEST(ViewerServer, AnAcknowledgingPageGetsTwoUndrawnPicturesThenTheLatest) {
  Server server(AnyPort(), nullptr);
  WsClient page(WsUrl(server));
  ASSERT_TRUE(page.WaitOpen());
  ASSERT_TRUE(WaitClients(server, 1));
  page.Send(R"({"cmd": "ack"})");  // a page acknowledges from its first picture on
  ASSERT_TRUE(testing::PollUntil([&] { return server.stats().acknowledged.load() == 1; }));
  const size_t skipped_before = server.stats().skipped.load();
  for (int i = 1; i <= 5; ++i) {
    InServerThread(server, [&] {
      server.Broadcast(std::make_shared<const std::string>(std::to_string(i)), true, true);
    });
  }
  ASSERT_TRUE(page.WaitForMessage([](const auto& m) { return m.payload == "2"; }));
  EXPECT_EQ(server.stats().skipped.load() - skipped_before, 3u);
  page.Send(R"({"cmd": "ack"})");
  EXPECT_TRUE(page.WaitForMessage([](const auto& m) { return m.payload == "5"; }));
  for (const auto& m : page.messages()) {
    EXPECT_TRUE(m.payload != "3" && m.payload != "4") << m.payload;
  }
}

TEST(ViewerServer, StopsWithClientsConnected) {
  auto server = std::make_unique<Server>(AnyPort(), nullptr);
  WsClient client(WsUrl(*server));
  ASSERT_TRUE(client.WaitOpen());
  // The client's open handler may run before the server's (the server's runs once its handshake
  // reply is written): the server has to know it for it to be closed.
  ASSERT_TRUE(WaitClients(*server, 1));
  server->Stop();
  server->Stop();  // idempotent
  EXPECT_TRUE(client.WaitClosed());
  server.reset();
}

}  // namespace
}  // namespace moslam::viewer
