// Shared by the libFuzzer targets: a scratch folder in memory (/dev/shm where there is one) for
// the inputs of readers that take a path, removed at exit, and the byte-exact writing of an input
// there. The readers are fuzzed through their public entry points, so the code under test is
// exactly what a program runs (the file checks and the parse alike).
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace rtd::fuzz {

inline const std::filesystem::path& scratchFolder(const char* target) {
    static const std::filesystem::path folder = [target] {
        std::error_code ec;
        const std::filesystem::path base = std::filesystem::is_directory("/dev/shm", ec)
                                               ? std::filesystem::path("/dev/shm")
                                               : std::filesystem::temp_directory_path();
        std::filesystem::path f =
            base / ("rtd-fuzz-" + std::string(target) + "-" + std::to_string(::getpid()));
        std::filesystem::remove_all(f, ec);
        std::filesystem::create_directories(f);
        return f;
    }();
    static const bool registered = [] {
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(folder, ec);
        });
        return true;
    }();
    (void)registered;
    return folder;
}

// Replaces `file` with exactly these bytes; aborts if that fails (a harness fault, not a find).
inline void writeBytes(const std::filesystem::path& file, const std::uint8_t* data,
                       std::size_t size) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        std::perror(file.c_str());
        std::abort();
    }
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(fd, data + done, size - done);
        if (n <= 0) {
            std::perror(file.c_str());
            std::abort();
        }
        done += std::size_t(n);
    }
    ::close(fd);
}

// A check of the harness's own: a broken invariant is a finding, reported as a crash.
#define RTD_FUZZ_CHECK(condition)                                                                  \
    do {                                                                                           \
        if (!(condition)) {                                                                        \
            std::fprintf(stderr, "%s:%d: invariant broken: %s\n", __FILE__, __LINE__, #condition); \
            std::abort();                                                                          \
        }                                                                                          \
    } while (0)

}  // namespace rtd::fuzz
