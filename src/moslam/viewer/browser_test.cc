// The viewer in a real browser (issue 26): `moslam run --viewer` on a short synthetic sequence,
// the page loaded in headless Chromium, and the page's own state (window.moslam, read through the
// DevTools protocol) checked against the run's summary.json; pause and step are pressed on the
// page's buttons. Skips when chromium is not installed.
//
// Pausing mid-run relies on no timing: the run is started with --viewer-pause-at N (N two thirds
// into the sequence, from its rgb.txt), so it stops there by itself however late the page
// draws on a loaded machine; the page's own Pause is then pressed right after Resume, while the
// run cannot have reached its end (a third of the sequence, paced in real time, is left).
//
// Environment: MOSLAM_VIEWER_DATASET=DIR runs an existing TUM-layout folder (with settings.yaml)
// instead of a generated one; MOSLAM_VIEWER_SCREENSHOT=FILE.png saves the page while paused
// mid-run, with the keyframe graph and the depth on (docs/ screenshots); MOSLAM_VIEWER_PAUSE_AT=N
// holds the run at frame N instead; MOSLAM_VIEWER_VOCABULARY=FILE runs with that vocabulary
// (loop closing) instead of none; MOSLAM_VIEWER_SCREENSHOT_END=FILE.png saves the page after the
// run; MOSLAM_VIEWER_SCREENSHOT_VIEW=FILE.png saves `moslam view` of the finished run's folder,
// with the keyframe graph on.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "moslam/testing/shared_data.h"
#include "moslam/viewer/test_client.h"

extern char** environ;

namespace moslam::viewer {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

std::string FindOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return "";
}

// A child process, its output in `log`; SIGTERM'd and reaped on destruction.
class Child {
 public:
  Child(const std::vector<std::string>& args, const std::string& log) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    if (posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      Wait();
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  bool started() const { return pid_ > 0; }
  void Signal(int signal) { kill(pid_, signal); }
  int Wait() {
    int status = 0;
    if (pid_ > 0) waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

 private:
  pid_t pid_ = -1;
};

int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t size = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size);
  ::close(fd);
  return ntohs(address.sin_port);
}

// Polls `ready` every 100 ms until it holds or `seconds` pass (a test waiting on other processes).
template <typename F>
bool Eventually(F ready, double seconds) {
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < until) {
    if (ready()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return ready();
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string Base64Decode(const std::string& in) {
  std::string out;
  int value = 0, bits = -8;
  for (const char c : in) {
    const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = std::strchr(table, c);
    if (c == '=' || at == nullptr || c == '\0') break;
    value = (value << 6) + static_cast<int>(at - table);
    bits += 6;
    if (bits >= 0) {
      out.push_back(static_cast<char>((value >> bits) & 0xff));
      bits -= 8;
    }
  }
  return out;
}

// The DevTools protocol over the page's WebSocket.
class Page {
 public:
  explicit Page(const std::string& url) : socket_(url) {}
  bool Open() { return socket_.WaitOpen(); }
  std::string failure() { return socket_.failure(); }
  json Call(const std::string& method, const json& params) {
    const int id = ++id_;
    socket_.Send(json{{"id", id}, {"method", method}, {"params", params}}.dump());
    json reply;
    socket_.WaitForMessage([&](const testing::WsClient::Message& m) {
      const json j = json::parse(m.payload, nullptr, false);
      if (j.is_discarded() || j.value("id", -1) != id) return false;
      reply = j;
      return true;
    });
    return reply;
  }
  json Eval(const std::string& expression) {
    const json reply =
        Call("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}});
    return reply.contains("result") && reply["result"].contains("result")
               ? reply["result"]["result"].value("value", json())
               : json();
  }
  // The page's state; a few tries, since on a loaded machine a DevTools call can go unanswered
  // within its 10 s (and a page that is loading has none yet). An empty object when none came.
  json State() {
    for (int tries = 0; tries < 5; ++tries) {
      const json value = Eval("JSON.stringify(window.moslam || null)");
      const json state =
          value.is_string() ? json::parse(value.get<std::string>(), nullptr, false) : json();
      if (state.is_object()) return state;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return json::object();
  }
  void Click(const std::string& id) { Eval("document.getElementById('" + id + "').click()"); }

 private:
  testing::WsClient socket_;
  int id_ = 0;
};

// The frames of a TUM-layout folder (the lines of its rgb.txt), 0 when it has none.
int CountFrames(const std::string& folder) {
  std::ifstream in(folder + "/rgb.txt");
  int n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty() && line[0] != '#';
  return n;
}

void Screenshot(Page& page, const char* path) {
  const json reply = page.Call("Page.captureScreenshot", {{"format", "png"}});
  std::ofstream(path, std::ios::binary)
      << Base64Decode(reply["result"].value("data", std::string()));
}

// Once the page shows the run paused: the frame it settles on (the paused frame is always sent,
// but a page drawing slowly shows it late), which must then stay for a second; -1 when the run
// ended instead.
int PausedFrame(Page& page, const std::string& run_log) {
  int frame = -1;
  const bool settled = Eventually(
      [&] {
        const int before = page.State().value("frame", -1);
        std::this_thread::sleep_for(std::chrono::seconds(1));
        const json s = page.State();
        frame = s.value("frame", -1);
        return s.value("paused", false) && frame == before;
      },
      60);
  EXPECT_TRUE(settled) << page.State().dump();
  if (page.State().value("finished", true)) {
    ADD_FAILURE() << "the run ended before the pause took: " << page.State().dump() << "\n"
                  << ReadFile(run_log);
    return -1;
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(page.State().value("frame", -1), frame) << "the run went on while paused";
  return frame;
}

// What the page gets only on demand, on a run paused at `frame`: no keyframe graph or depth
// before the page asks; turned on from the page's checkboxes, they arrive with the paused frame
// (sent again), the spanning tree linking every keyframe. The keypoints the mask took away come
// without asking, once a browser watches.
void CheckOnDemand(Page& page, int frame, const std::string& run_log) {
  json s = page.State();
  EXPECT_EQ(s.value("graphMessages", -1), 0) << s.dump();
  EXPECT_EQ(s.value("covisibilityEdges", -1), 0);
  EXPECT_EQ(s.value("spanningEdges", -1), 0);
  EXPECT_EQ(s.value("depthMessages", -1), 0);
  // (A sequence without movers, such as loop_room, has no mask to take any.)
  if (s["numbers"].value("mask_coverage", 0.0) > 0.01) {
    EXPECT_GT(s.value("rejectedMax", 0), 0) << "no keypoint taken by the mask drawn";
  }
  page.Click("graph");
  page.Click("depth");
  ASSERT_TRUE(Eventually(
      [&] {
        s = page.State();
        return s.value("graphMessages", 0) > 0 && s.value("depthWidth", 0) > 0;
      },
      30))
      << s.dump() << "\n"
      << ReadFile(run_log);
  EXPECT_TRUE(s.value("graphOn", false));
  EXPECT_TRUE(s.value("depthOn", false));
  EXPECT_EQ(s.value("frame", -1), frame) << "the toggles moved the run";
  EXPECT_EQ(s.value("spanningEdges", -1), s.value("keyframes", 0) - 1);
  EXPECT_GT(s.value("covisibilityEdges", 0), 0);
  std::printf(
      "paused at frame %d: %d keyframes, %d covisibility edges, %d keypoints taken by the "
      "mask (most in a frame so far: %d), %d loops\n",
      frame, s.value("keyframes", 0), s.value("covisibilityEdges", 0),
      s.value("rejectedKeypoints", 0), s.value("rejectedMax", 0), s.value("loops", 0));
}

// `moslam view` of the finished run's folder in the same browser: the keyframes, the whole
// keyframe graph (keyframe_graph.json) and the loops the live page ended with.
void CheckViewOfTheFolder(Page& page, const std::string& moslam, const std::string& run_dir,
                          const std::string& log, const json& live) {
  const int port = FreePort();
  Child view({moslam, "view", run_dir, "--port", std::to_string(port)}, log);
  ASSERT_TRUE(Eventually([&] { return testing::HttpGet(port, "/").status == 200; }, 60))
      << ReadFile(log);
  page.Call("Page.navigate", {{"url", "http://127.0.0.1:" + std::to_string(port) + "/"}});
  json s;
  ASSERT_TRUE(Eventually(
      [&] {
        s = page.State();
        return s.is_object() && s.value("replay", false) && s.value("messages", 0) > 0;
      },
      60))
      << s.dump() << "\n"
      << ReadFile(log);
  EXPECT_EQ(s.value("keyframes", -1), live.value("keyframes", -2));
  EXPECT_EQ(s.value("spanningEdges", -1), s.value("keyframes", 0) - 1);
  EXPECT_EQ(s.value("covisibilityEdges", -1), live.value("covisibilityEdges", -2));
  EXPECT_EQ(s.value("loops", -1), live.value("loops", -2));
  EXPECT_EQ(s.value("error", std::string("?")), "") << s.dump();
  std::printf("moslam view of the folder: %d keyframes, %d covisibility edges, %d loops\n",
              s.value("keyframes", 0), s.value("covisibilityEdges", 0), s.value("loops", 0));
  if (const char* shot = std::getenv("MOSLAM_VIEWER_SCREENSHOT_VIEW")) {
    page.Click("graph");
    std::this_thread::sleep_for(std::chrono::seconds(1));
    Screenshot(page, shot);
  }
  view.Signal(SIGINT);
  EXPECT_EQ(view.Wait(), 0) << ReadFile(log);
}

TEST(ViewerBrowser, PageCountsMatchTheRunAndPauseStepWork) {
  std::string chromium = FindOnPath("chromium");
  if (chromium.empty()) chromium = FindOnPath("chromium-browser");
  if (chromium.empty()) {
    GTEST_SKIP() << "chromium is not installed (apt-get install chromium, scripts/setup.sh): "
                    "the viewer's browser test needs it";
  }
  const ::moslam::testing::TempDir dir;
  const std::string moslam = MOSLAM_BINARY;
  std::string data = dir.path() + "/seq";
  if (const char* given = std::getenv("MOSLAM_VIEWER_DATASET")) {
    data = given;
  } else {
    Child synth(
        {moslam, "synth", "--preset", "w_xyz", "--seed", "3", "--frames", "90", "--out", data},
        dir.path() + "/synth.log");
    ASSERT_EQ(synth.Wait(), 0) << ReadFile(dir.path() + "/synth.log");
  }
  // Where the run holds by itself: two thirds in, so that a map is there to look at and a third
  // of the run is left for the page's own Pause.
  const int frames = CountFrames(data);
  ASSERT_GT(frames, 6) << data << "/rgb.txt";
  const int hold_at = std::getenv("MOSLAM_VIEWER_PAUSE_AT")
                          ? std::atoi(std::getenv("MOSLAM_VIEWER_PAUSE_AT"))
                          : 2 * frames / 3;
  const int port = FreePort();
  const std::string run_dir = dir.path() + "/run";
  const std::string run_log = dir.path() + "/run.log";
  Child run(
      {moslam,
       "run",
       "--dataset",
       "tum",
       data,
       "--settings",
       data + "/settings.yaml",
       "--mask-source",
       "synth-gt",
       "--movable",
       "person",
       "--out",
       run_dir,
       "--vocabulary",
       std::getenv("MOSLAM_VIEWER_VOCABULARY") ? std::getenv("MOSLAM_VIEWER_VOCABULARY") : "none",
       "--realtime",
       "--viewer",
       std::to_string(port),
       "--viewer-paused",
       "--viewer-pause-at",
       std::to_string(hold_at)},
      run_log);
  ASSERT_TRUE(run.started());
  ASSERT_TRUE(Eventually([&] { return testing::HttpGet(port, "/").status == 200; }, 60))
      << ReadFile(run_log);

  const int cdp = FreePort();
  Child browser({chromium, "--headless=new", "--no-sandbox", "--no-first-run",
                 "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--window-size=1400,900",
                 "--remote-allow-origins=*", "--remote-debugging-port=" + std::to_string(cdp),
                 "--user-data-dir=" + dir.path() + "/chromium",
                 "http://127.0.0.1:" + std::to_string(port) + "/"},
                dir.path() + "/chromium.log");
  std::string page_url;
  ASSERT_TRUE(Eventually(
      [&] {
        const json list = json::parse(testing::HttpGet(cdp, "/json/list").body, nullptr, false);
        if (!list.is_array()) return false;
        for (const json& target : list) {
          if (target.value("type", "") == "page" &&
              target.value("url", "").find(std::to_string(port)) != std::string::npos) {
            page_url = target.value("webSocketDebuggerUrl", "");
          }
        }
        return !page_url.empty();
      },
      60))
      << ReadFile(dir.path() + "/chromium.log");
  Page page(page_url);
  ASSERT_TRUE(page.Open()) << page_url << ": " << page.failure();

  // Paused after frame 0 (--viewer-paused): the page shows it and nothing moves.
  ASSERT_TRUE(Eventually(
      [&] {
        const json s = page.State();
        return s.is_object() && s.value("connected", false) && s.value("paused", false) &&
               s.value("frame", -1) == 0;
      },
      60))
      << page.State().dump();
  page.Click("step");
  ASSERT_TRUE(Eventually([&] { return page.State().value("frame", -1) == 1; }, 30));
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(page.State().value("frame", -1), 1) << "a step moved more than one frame";

  // Running until the run holds itself at `hold_at` (--viewer-pause-at): the page shows it paused
  // there and the counter stays; what the page shows on demand arrives with the paused frame.
  page.Click("resume");
  // Past frame 1, the page has had the resume (the server sends in order), so a pause it shows
  // from then on is the hold's.
  ASSERT_TRUE(Eventually([&] { return page.State().value("frame", -1) > 1; }, 60))
      << page.State().dump();
  const int held_at = PausedFrame(page, run_log);
  ASSERT_EQ(held_at, hold_at) << ReadFile(run_log);
  CheckOnDemand(page, held_at, run_log);
  if (const char* shot = std::getenv("MOSLAM_VIEWER_SCREENSHOT")) {
    // Closer than the page's default orbit (3.3 m behind the camera), so that the keyframe graph
    // of a small room shows; the page's own camera and controls, from its global scope.
    page.Eval(
        "camera.position.sub(controls.target).multiplyScalar(0.4).add(controls.target);"
        "controls.update()");
    std::this_thread::sleep_for(std::chrono::seconds(1));  // the page draws the images async
    Screenshot(page, shot);
  }
  page.Click("step");
  ASSERT_TRUE(Eventually([&] { return page.State().value("frame", -1) == held_at + 1; }, 30))
      << "held at " << held_at << ": " << page.State().dump();

  // The page's own Pause on a running run: pressed right after Resume, in one go, so that it
  // reaches the run long before the third of the sequence left is over (paced in real time),
  // however slowly the page draws. The run stops where the pause found it and stays there.
  const int statuses = page.State().value("statuses", 0);
  page.Eval("document.getElementById('resume').click(); document.getElementById('pause').click()");
  // The server has carried out both once the page has their two statuses.
  ASSERT_TRUE(Eventually([&] { return page.State().value("statuses", 0) >= statuses + 2; }, 60))
      << page.State().dump();
  const int stopped_at = PausedFrame(page, run_log);
  ASSERT_GE(stopped_at, held_at + 1);
  std::printf(
      "held at frame %d by --viewer-pause-at, stepped once, resumed and paused from the "
      "page at frame %d (of %d)\n",
      held_at, stopped_at, frames);
  page.Click("step");
  ASSERT_TRUE(Eventually([&] { return page.State().value("frame", -1) == stopped_at + 1; }, 30))
      << "paused at " << stopped_at << ": " << page.State().dump();
  page.Click("resume");

  // The end: the page's own counts against summary.json.
  ASSERT_TRUE(Eventually([&] { return page.State().value("finished", false); }, 300))
      << ReadFile(run_log);
  const json summary = json::parse(ReadFile(run_dir + "/summary.json"), nullptr, false);
  ASSERT_TRUE(summary.is_object());
  const json state = page.State();
  EXPECT_EQ(state.value("frames", -1), summary.value("frames", -2));
  EXPECT_EQ(state.value("keyframes", -1), summary.value("keyframes", -2));
  EXPECT_EQ(state.value("mapPoints", -1), summary.value("map_points", -2));
  EXPECT_EQ(state.value("trajectory", -1), summary.value("camera_poses", -2));
  EXPECT_GT(state.value("keyframes", 0), 1);
  EXPECT_GT(state.value("mapPoints", 0), 100);
  EXPECT_GT(state.value("groundTruth", 0), 0);
  EXPECT_EQ(state.value("error", std::string("?")), "") << state.dump();
  // The final picture: the whole keyframe graph, which the page still shows.
  EXPECT_EQ(state.value("spanningEdges", -1), state.value("keyframes", 0) - 1);
  EXPECT_EQ(state.value("loops", -1), summary.value("loops_closed", -2));
  std::printf("at the end: %d keyframes, %d loops marked on the page (summary.json: %d closed)\n",
              state.value("keyframes", 0), state.value("loops", 0),
              summary.value("loops_closed", 0));
  if (const char* shot = std::getenv("MOSLAM_VIEWER_SCREENSHOT_END")) Screenshot(page, shot);
  // Each closed loop was announced on the page as it happened.
  EXPECT_EQ(state.value("loopNotices", -1), state.value("loops", -2));
  // The run has ended and the page stays until Ctrl-C, which ends moslam with status 0.
  run.Signal(SIGINT);
  EXPECT_EQ(run.Wait(), 0) << ReadFile(run_log);
  CheckViewOfTheFolder(page, moslam, run_dir, dir.path() + "/view.log", state);
}

}  // namespace
}  // namespace moslam::viewer
