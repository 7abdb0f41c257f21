// A progress line for long runs: frame i/N, frames per second, ETA. Redrawn in place on a
// terminal, one line per frame otherwise (logs), nothing when quiet.
#pragma once

#include <chrono>
#include <string>

namespace rtd::cli {

class Progress {
  public:
    Progress(int total, bool quiet);
    void update(int done);  // `done` frames finished
    // A warning line on stderr (shown when quiet too), clear of the progress line on a terminal.
    void warn(const std::string& message);
    void finish();

  private:
    int total_;
    bool quiet_;
    bool terminal_;
    std::chrono::steady_clock::time_point start_;
};

}  // namespace rtd::cli
