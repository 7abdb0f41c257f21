// Time to write (and read back) an EXR per compression, FLOAT and HALF channels, and OpenEXR
// thread count, with the file sizes and the error of the lossy ones: what --compression's
// default is chosen by (docs/performance-cpu.md). The images are the ones a run writes, e.g. a
// denoise run's results:
//   build/release/bench/bench_exr [--repeats N] [--threads 0,1,2] OUT/result_*.exr
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "rtdenoise/io.h"

namespace fs = std::filesystem;

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double millisecondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
}

std::vector<int> parseList(const std::string& text) {
    std::vector<int> out;
    for (std::size_t at = 0; at <= text.size();) {
        const std::size_t comma = std::min(text.find(',', at), text.size());
        out.push_back(std::stoi(text.substr(at, comma - at)));
        at = comma + 1;
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    int repeats = 5;
    std::vector<int> threadCounts{0, 1, 2};
    std::vector<fs::path> files;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--repeats" && i + 1 < argc)
            repeats = std::max(1, std::stoi(argv[++i]));
        else if (arg == "--threads" && i + 1 < argc)
            threadCounts = parseList(argv[++i]);
        else
            files.emplace_back(arg);
    }
    if (files.empty()) {
        fmt::print(stderr, "usage: bench_exr [--repeats N] [--threads 0,1,2] IMAGE.exr...\n");
        return 2;
    }
    try {
        std::vector<rtd::Image> images;
        for (const fs::path& file : files)
            images.push_back(rtd::readExr(file, {{"R"}, {"G"}, {"B"}}));
        const fs::path folder =
            fs::temp_directory_path() / fmt::format("rtd-bench-exr-{}", ::getpid());
        fs::create_directories(folder);
        const fs::path file = folder / "image.exr";
        fmt::print(
            "{} images of {}x{}, {} writes each per case; threads: OpenEXR's pool (0: the "
            "calling thread alone)\n",
            images.size(), images[0].width, images[0].height, repeats);
        fmt::print("{:<6} {:<5} {:>7} {:>9} {:>9} {:>9} {:>8} {}\n", "compr", "type", "threads",
                   "write ms", "read ms", "size KiB", "ratio", "max error (relative)");
        const double rawBytes = double(images[0].pixels.size()) * sizeof(float);
        for (rtd::ExrCompression compression : rtd::exrCompressions()) {
            for (bool half : {false, true}) {
                for (int threads : threadCounts) {
                    rtd::setExrThreads(threads);
                    const rtd::ExrWriteOptions options{compression, half};
                    std::vector<double> writeMs, readMs, bytes;
                    double maxError = 0.0;
                    for (const rtd::Image& image : images) {
                        for (int r = 0; r < repeats; ++r) {
                            auto start = std::chrono::steady_clock::now();
                            rtd::writeExr(file, image, options);
                            writeMs.push_back(millisecondsSince(start));
                            start = std::chrono::steady_clock::now();
                            const rtd::Image back = rtd::readExr(file, {{"R"}, {"G"}, {"B"}});
                            readMs.push_back(millisecondsSince(start));
                            if (r > 0) continue;
                            bytes.push_back(double(fs::file_size(file)));
                            for (std::size_t i = 0; i < back.pixels.size(); ++i) {
                                const double written = image.pixels[i];
                                const double error = std::abs(back.pixels[i] - written) /
                                                     std::max(std::abs(written), 1e-3);
                                maxError = std::max(maxError, error);
                            }
                        }
                    }
                    fmt::print("{:<6} {:<5} {:>7} {:>9.2f} {:>9.2f} {:>9.0f} {:>8.2f} {:.2g}\n",
                               rtd::toString(compression), half ? "half" : "float", threads,
                               median(writeMs), median(readMs), median(bytes) / 1024.0,
                               rawBytes / median(bytes), maxError);
                }
            }
        }
        fs::remove_all(folder);
    } catch (const std::exception& e) {
        fmt::print(stderr, "bench_exr: {}\n", e.what());
        return 1;
    }
    return 0;
}
