// moslam: movable-object-aware visual SLAM. One binary, one subcommand per job.
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include "commands.h"
#include "moslam/net/blas_core.h"
#include "moslam/util/error.h"
#include "moslam/util/log.h"

int main(int argc, char** argv) {
  // libtorch's OpenMP threads (libgomp) spin while they wait by default. Beside tracking and
  // mapping threads on a 2-core machine that made a network 10-70x slower; libgomp reads its wait
  // policy when it is loaded, before main, so the only way to change it from here is to run
  // again with it set. A policy the user sets is kept.
  bool run_again = false;
  if (std::getenv("OMP_WAIT_POLICY") == nullptr) {
    setenv("OMP_WAIT_POLICY", "passive", 1);
    run_again = true;
  }
  // OpenBLAS chose its kernels when it loaded; where it fell back to generic ones on a CPU it
  // does not know, the same re-run sets the right ones (net/blas_core.h). A coretype the user
  // set is kept.
  if (std::getenv("OPENBLAS_CORETYPE") == nullptr) {
    const std::string core = moslam::net::OpenBlasCore();
    if (const auto better =
            moslam::net::BetterOpenBlasCore(core, moslam::net::CpuFeatures::Detect())) {
      setenv("OPENBLAS_CORETYPE", better->c_str(), 1);
      setenv(moslam::net::kOpenBlasFallbackVariable, core.c_str(), 1);
      run_again = true;
    }
  }
  // execv returns only on failure: go on with the defaults.
  if (run_again) execv("/proc/self/exe", argv);
  // A write past the file-size limit (ulimit -f) fails with EFBIG, reported like a full disk,
  // instead of ending the process by SIGXFSZ's default action with nothing said.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"moslam: movable-object-aware visual SLAM (ORB-SLAM2 family) and its tools"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "moslam 0.1.0");
  std::string log_level = "info";
  app.add_option("--log-level", log_level,
                 "Log verbosity: trace, debug, info, warn, error, critical, off")
      ->capture_default_str();
  app.parse_complete_callback([&] { moslam::SetupLogging(log_level); });

  moslam::app::AddEvalCommand(app);
  moslam::app::AddDatasetCommand(app);
  moslam::app::AddFeaturesCommand(app);
  moslam::app::AddCrfCommand(app);
  moslam::app::AddRunCommand(app);
  moslam::app::AddSynthCommand(app);
  moslam::app::AddSegmentCommand(app);
  moslam::app::AddSegEvalCommand(app);
  moslam::app::AddVocabCommand(app);
  moslam::app::AddTrainCommand(app);
  moslam::app::AddMapCommand(app);
  moslam::app::AddViewCommand(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const moslam::app::ExitStatus& status) {
    return status.code;
  } catch (const moslam::InputError& e) {
    spdlog::error("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::error("unexpected error: {}", e.what());
    return 3;
  }
  return 0;
}
