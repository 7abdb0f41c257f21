// Each subcommand registers its options on the CLI11 app and returns the function that runs it.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>

#include "rtdenoise/settings.h"
#include "tuning.h"

namespace rtd::cli {

struct Command {
    CLI::App* app;
    std::function<int()> run;
};

Command addDenoiseCommand(CLI::App& app);
Command addRenderCommand(CLI::App& app);
Command addCompareCommand(CLI::App& app);
Command addBenchCommand(CLI::App& app);

// Sets the options of `command` not given on its command line from a TOML/INI file whose keys
// are the long option names; throws rtd::Error naming the file for an unknown key or bad value.
void applyConfigFile(CLI::App& command, const std::filesystem::path& file);

// Registers every denoiser setting as an option of `command` (shared by denoise and bench).
void addDenoiserOptions(CLI::App& command, DenoiserSettings& settings);

// The bench's --tile-passes option (auto|on|off, any case) into `target`.
void addTilePassesOption(CLI::App& command, TilePasses& target, const std::string& help);

}  // namespace rtd::cli
