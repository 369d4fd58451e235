// `moslam view RUN_DIR`: a finished run in the viewer's page (viewer/run_dir.h), served until
// Ctrl-C.
#include <memory>
#include <string>

#include <spdlog/spdlog.h>

#include "commands.h"
#include "moslam/viewer/run_dir.h"
#include "moslam/viewer/server.h"

namespace moslam::app {
namespace {

struct ViewArgs {
  std::string run_dir;
  int port = viewer::ServerOptions{}.port;
  std::string host = viewer::ServerOptions{}.host;
};

void View(const ViewArgs& args) {
  viewer::RunView run = viewer::LoadRunView(args.run_dir);
  viewer::ServerOptions options;
  options.port = args.port;
  options.host = args.host;
  viewer::Server server(options, [](const nlohmann::json&) {});  // nothing to pause
  const auto message =
      std::make_shared<const std::string>(viewer::EncodeSnapshot(run.snapshot, run.picture));
  server.Post([&server, message] { server.Broadcast(message, /*binary=*/true); });
  const size_t loops = run.snapshot.view ? run.snapshot.view->loops.size() / 2 : 0;
  spdlog::info("view: {} ({} poses, {} keyframes, {} loops{}{}) at {} until Ctrl-C", args.run_dir,
               run.picture.trajectory.size() / 3,
               run.snapshot.view ? run.snapshot.view->keyframes.size() : 0, loops,
               run.map_path.empty() ? ", no map file" : ", map " + run.map_path,
               run.graph_from.empty() ? ", no keyframe graph" : ", graph from " + run.graph_from,
               server.url());
  server.WaitForStopSignal();
}

}  // namespace

void AddViewCommand(CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* command = app.add_subcommand(
      "view",
      "Show a finished run (the folder `moslam run` wrote) in the viewer's page: trajectory, "
      "keyframes, their graph and closed loops (keyframe_graph.json), ground truth, and the final "
      "map when the folder holds a *.map file (--save-map RUN_DIR/map.map); served until Ctrl-C "
      "(docs/RUNNING.md)");
  command->add_option("RUN_DIR", args->run_dir, "The run's output folder")->required();
  command->add_option("--port", args->port, "Port of the page")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  command
      ->add_option("--host", args->host,
                   "Address to listen on; anything but 127.0.0.1 EXPOSES THE PAGE TO EVERYONE "
                   "WHO CAN REACH THAT PORT")
      ->capture_default_str();
  command->callback([args] { View(*args); });
}

}  // namespace moslam::app
