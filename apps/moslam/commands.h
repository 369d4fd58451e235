// Subcommands of the `moslam` CLI. Each Add*Command registers one subcommand (and its own
// subcommands) on the app; the callback runs the work and throws InputError on bad input.
#pragma once

#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>

namespace moslam::app {

// CLI::ExistingFile with a message that says what the file should have been: "X is a directory,
// not a settings file" rather than CLI11's "File is actually a directory", which the log showed
// as a bare "Run with --help".
inline CLI::Validator ExistingFileOf(const std::string& what) {
  return CLI::Validator(
      [what](std::string& path) -> std::string {
        std::error_code error;
        if (std::filesystem::is_directory(path, error)) {
          return path + " is a directory, not a " + what;
        }
        if (!std::filesystem::is_regular_file(path, error)) return "no " + what + " " + path;
        return std::string();
      },
      "FILE");
}

// Thrown by a command that did its job but must end the process with another status than 0:
// `moslam run` interrupted by a signal ends with 128 + the signal's number, as a shell reports a
// process the signal killed, after writing its outputs. main() returns `code`.
struct ExitStatus {
  int code = 0;
};

void AddEvalCommand(CLI::App& app);
void AddDatasetCommand(CLI::App& app);
void AddFeaturesCommand(CLI::App& app);
void AddCrfCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddSynthCommand(CLI::App& app);
void AddSegmentCommand(CLI::App& app);
void AddSegEvalCommand(CLI::App& app);
void AddVocabCommand(CLI::App& app);
void AddTrainCommand(CLI::App& app);
void AddMapCommand(CLI::App& app);
void AddViewCommand(CLI::App& app);

}  // namespace moslam::app
