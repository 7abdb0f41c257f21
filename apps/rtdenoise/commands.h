// Each subcommand registers its options on the CLI11 app and returns the function that runs it.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

#include "rtdenoise/settings.h"

namespace rtd::cli {

struct Command {
    CLI::App* app;
    std::function<int()> run;
};

Command addDenoiseCommand(CLI::App& app);

// Registers every denoiser setting as an option of `command` (shared by denoise and bench).
void addDenoiserOptions(CLI::App& command, DenoiserSettings& settings);

}  // namespace rtd::cli
