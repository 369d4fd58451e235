// Subcommands of the `moslam` CLI. Each Add*Command registers one subcommand (and its own
// subcommands) on the app; the callback runs the work and throws InputError on bad input.
#pragma once

#include <CLI/CLI.hpp>

namespace moslam::app {

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

}  // namespace moslam::app
