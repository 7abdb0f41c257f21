// rtdenoise: the command line over the library.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <CLI/CLI.hpp>
#include <algorithm>
#include <csignal>
#include <exception>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "commands.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace {

// SIGINT/SIGTERM: no temporary file or ffmpeg child is left behind, and the exit code says which
// signal ended the run (128 + its number, as a shell reports it).
extern "C" void onTerminationSignal(int signal) {
    rtd::abandonTemporaryFiles();
    ::_exit(128 + signal);
}

// A run frees and allocates each frame's buffers (megabytes each) again and again: glibc would
// map them from the system and return them every time, to be zero-filled page by page anew;
// kept by malloc instead, reading a frame costs less (docs/performance-cpu.md, 2026-12-02).
void keepFreedFrameBuffers() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 32 << 20);  // the largest glibc allows
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

void installTerminationHandlers() {
    struct sigaction action {};
    action.sa_handler = onTerminationSignal;
    sigemptyset(&action.sa_mask);
    for (int signal : {SIGINT, SIGTERM}) sigaction(signal, &action, nullptr);
}

// Edits (insertions, deletions, substitutions) turning `a` into `b`: the closest command name.
std::size_t editDistance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
            diagonal = above;
        }
    }
    return row[b.size()];
}

// CLI11 reports a misspelt command only as "A subcommand is required": name it, list the
// commands and suggest the closest. Empty when `word` is a command or not a command word.
std::string unknownCommandMessage(CLI::App& app, const std::string& word) {
    if (word.empty() || word[0] == '-') return {};
    std::vector<std::string> names;
    for (const CLI::App* command : app.get_subcommands({})) names.push_back(command->get_name());
    if (std::find(names.begin(), names.end(), word) != names.end()) return {};
    std::string closest = names.front();
    for (const std::string& name : names)
        if (editDistance(word, name) < editDistance(word, closest)) closest = name;
    std::string message = fmt::format("rtdenoise: unknown command '{}'; the commands are {}", word,
                                      fmt::join(names, ", "));
    if (editDistance(word, closest) <= std::max<std::size_t>(2, closest.size() / 3))
        message += fmt::format(" (did you mean '{}'?)", closest);
    return message;
}

}  // namespace

int main(int argc, char** argv) {
    installTerminationHandlers();
    keepFreedFrameBuffers();
    CLI::App app{"rtdenoise: real-time denoising of path-traced frame sequences"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "rtdenoise 0.1.0");
    std::vector<rtd::cli::Command> commands{
        rtd::cli::addDenoiseCommand(app), rtd::cli::addRenderCommand(app),
        rtd::cli::addCompareCommand(app), rtd::cli::addBenchCommand(app)};
    if (argc > 1) {
        const std::string message = unknownCommandMessage(app, argv[1]);
        if (!message.empty()) {
            fmt::print(stderr, "{}\nRun with --help for more information.\n", message);
            return static_cast<int>(CLI::ExitCodes::ExtrasError);
        }
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    // EXR files are (de)compressed block by block on every core: the course data's ZIP blocks
    // and a compressed --compression's (the figures: docs/performance-cpu.md, 2026-12-02).
    rtd::setExrThreads(int(std::thread::hardware_concurrency()));
    try {
        for (auto& command : commands)
            if (command.app->parsed()) return command.run();
    } catch (const std::exception& e) {
        fmt::print(stderr, "rtdenoise: error: {}\n", e.what());
        return 1;
    }
    return 0;
}
