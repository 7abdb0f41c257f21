#include "progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace rtd::cli {

Progress::Progress(int total, bool quiet)
    : total_(total),
      quiet_(quiet),
      terminal_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()) {}

void Progress::update(int done) {
    if (quiet_) return;
    double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    double fps = elapsed > 0.0 ? done / elapsed : 0.0;
    double eta = fps > 0.0 ? (total_ - done) / fps : 0.0;
    constexpr int kBarWidth = 30;
    int filled = total_ > 0 ? done * kBarWidth / total_ : kBarWidth;
    std::string bar = std::string(filled, '#') + std::string(kBarWidth - filled, '.');
    std::string line =
        fmt::format("[{}] frame {}/{}  {:.1f} fps  ETA {:.1f} s", bar, done, total_, fps, eta);
    if (terminal_)
        fmt::print(stderr, "\r{}", line);
    else
        fmt::print(stderr, "{}\n", line);
    std::fflush(stderr);
}

void Progress::warn(const std::string& message) {
    // On a terminal the progress line is erased first; the next update() draws it again.
    fmt::print(stderr, "{}rtdenoise: warning: {}\n", terminal_ && !quiet_ ? "\r\033[K" : "",
               message);
}

void Progress::finish() {
    if (!quiet_ && terminal_) fmt::print(stderr, "\n");
}

}  // namespace rtd::cli
