// libFuzzer target: the denoise command's --config reader (rtd::cli::applyConfigFile: a TOML/INI
// file parsed by CLI11 into the command's options, each value through its option's checks and
// callback). The input is the file; the first byte's low bit says whether a command line
// (`denoise in -o out --method svgf --radius 3`) was parsed first, so that options given there
// are kept. An rtd::Error is the expected outcome of a bad file; a crash, a leak, undefined
// behaviour, a hang, or any other exception escaping (CLI11's own, std::out_of_range from a
// choice, ...) is a finding: the program would report it as an internal error.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "commands.h"
#include "fuzz_support.h"
#include "rtdenoise/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const std::filesystem::path file = rtd::fuzz::scratchFolder("config") / "config.toml";
    const bool withCommandLine = size > 0 && (data[0] & 1) != 0;
    rtd::fuzz::writeBytes(file, data, size);
    CLI::App app("rtdenoise");
    const rtd::cli::Command denoise = rtd::cli::addDenoiseCommand(app);
    if (withCommandLine) {
        // Reversed: CLI11's vector form takes the last argument first.
        std::vector<std::string> args{"3",   "--radius", "svgf", "--method",
                                      "out", "-o",       "in",   "denoise"};
        app.parse(args);
        RTD_FUZZ_CHECK(denoise.app->parsed());
    }
    try {
        rtd::cli::applyConfigFile(*denoise.app, file);
    } catch (const rtd::Error&) {
    }
    return 0;
}
