// Soak: 1000 frames of a moving, noisy 256x256 scene through one Denoiser per method (CPU). The
// resident memory after frame 1000 is within 1 % of that after frame 100 (nothing grows per
// frame: no leak, no cache or history that keeps what it was given), and no output holds a
// NaN or an Inf. Label `soak`: run by scripts/test.sh in the release build, not by the default
// ctest run (tests/CMakeLists.txt). Under AddressSanitizer the resident size is the allocator's
// quarantine, not the program's, so the sanitizer run leaves it out.
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace rtd {
namespace {

constexpr int kSize = 256;
constexpr int kFrames = 1000;
constexpr int kBaselineFrame = 100;  // resident memory is compared with the size after this one

// Resident set size in bytes (/proc/self/statm: size resident shared ... in pages).
std::size_t residentBytes() {
    std::ifstream statm("/proc/self/statm");
    std::size_t sizePages = 0, residentPages = 0;
    statm >> sizePages >> residentPages;
    return residentPages * std::size_t(::sysconf(_SC_PAGESIZE));
}

// Triangle wave 0, 1, ..., period/2, ..., 1, 0, ...: a motion that goes back and forth without a
// jump, so history is kept where the scene allows and rejected where it uncovers the wall.
int triangle(int t, int period) {
    const int phase = t % period;
    return phase <= period / 2 ? phase : period - phase;
}

// Frame t: a textured wall (object 0, depth 8, tilted normal on its right half), a box
// (object 1, depth 3) sliding 0..48 px and back, a band of sky (background, ID -1) along the
// top; the camera pans 0..16 px and back (all objects' world transforms move the other way);
// uniform noise of a new seed every frame, and a few fireflies.
Frame sceneFrame(int t) {
    const int boxShift = triangle(t, 96);
    const int panShift = triangle(t / 2, 32);
    test::SceneDescription d;
    d.width = kSize;
    d.height = kSize;
    d.objectCount = 2;
    d.id = [=](int x, int y) {
        if (y < 20) return -1;
        const int bx = x - 60 - boxShift + panShift;
        return bx >= 0 && bx < 80 && y >= 90 && y < 170 ? 1 : 0;
    };
    d.depth = [=](int x, int y) {
        const int bx = x - 60 - boxShift + panShift;
        return bx >= 0 && bx < 80 && y >= 90 && y < 170 ? 3.0f : 8.0f;
    };
    d.normal = [=](int x, int) {
        return x + panShift > kSize / 2 ? std::array<float, 3>{0.6f, 0.0f, -0.8f}
                                        : std::array<float, 3>{0.0f, 0.0f, -1.0f};
    };
    d.colour = [=](int x, int y) {
        if (y < 20) return std::array<float, 3>{0.3f, 0.5f, 0.9f};
        const int bx = x - 60 - boxShift + panShift;
        if (bx >= 0 && bx < 80 && y >= 90 && y < 170)
            return std::array<float, 3>{0.9f, 0.2f + 0.005f * float(bx), 0.1f};
        const int u = x + panShift;
        const bool check = ((u / 16) + (y / 16)) % 2 == 0;
        return check ? std::array<float, 3>{0.8f, 0.8f, 0.7f}
                     : std::array<float, 3>{0.2f, 0.25f, 0.3f};
    };
    Frame f = test::makeFrame(d);
    f.objectToWorld[0] = test::translation(test::worldShiftForPixels(-float(panShift), 8.0f), 0, 0);
    f.objectToWorld[1] =
        test::translation(test::worldShiftForPixels(float(boxShift - panShift), 3.0f), 0, 0);
    test::addNoise(f, 0.4f, 1000u + unsigned(t));
    for (int k = 0; k < 8; ++k) {  // fireflies at places that move with t
        const int x = (37 * t + 71 * k) % kSize, y = 20 + (53 * t + 29 * k) % (kSize - 20);
        for (int c = 0; c < 3; ++c) f.beauty.at(x, y, c) = 50.0f;
    }
    return f;
}

struct SoakCase {
    const char* name;
    DenoiserSettings settings;
};

class Soak : public ::testing::TestWithParam<SoakCase> {};

TEST_P(Soak, ResidentMemoryStaysConstantOverAThousandFrames) {
    // The measure sees memory that is touched: 8 MiB of fresh pages (a mapping of their own,
    // not the heap's free space) show as 8 MiB more resident.
    {
        constexpr std::size_t kBytes = std::size_t(8) << 20;
        const std::size_t before = residentBytes();
        ASSERT_GT(before, 0u);
        void* pages =
            ::mmap(nullptr, kBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        ASSERT_NE(pages, MAP_FAILED);
        std::memset(pages, 1, kBytes);
        const std::size_t after = residentBytes();
        ::munmap(pages, kBytes);
        EXPECT_GE(after, before + kBytes - (std::size_t(1) << 20)) << "statm does not follow";
    }

    Denoiser denoiser(GetParam().settings);
    Image output;
    std::vector<std::size_t> resident;  // after frames 100, 200, ..., 1000
    std::size_t baseline = 0;
    long long nonFinite = 0;
    double baselineMs = 0.0;
    const auto start = std::chrono::steady_clock::now();
    for (int t = 0; t < kFrames; ++t) {
        const Frame frame = sceneFrame(t);
        denoiser.processFrame(frame, output);
        ASSERT_EQ(output.width, kSize);
        ASSERT_EQ(output.height, kSize);
        for (float v : output.pixels) nonFinite += std::isfinite(v) ? 0 : 1;
        ASSERT_EQ(nonFinite, 0) << "frame " << t << " has NaN/Inf in its output";
        if ((t + 1) % 100 == 0) {
            resident.push_back(residentBytes());
            if (t + 1 == kBaselineFrame) {
                baseline = resident.back();
                baselineMs = std::chrono::duration<double, std::milli>(
                                 std::chrono::steady_clock::now() - start)
                                 .count();
            }
        }
    }
    const double totalMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const std::size_t last = resident.back();
    std::string series;
    for (std::size_t r : resident) series += " " + std::to_string(r / 1024);
    std::printf(
        "soak %-8s RSS frame 100: %zu KiB, frame 1000: %zu KiB (%+.3f %%); every 100 "
        "frames (KiB):%s; %.2f ms/frame (frames 101-1000), %.1f s in all\n",
        GetParam().name, baseline / 1024, last / 1024,
        100.0 * (double(last) - double(baseline)) / double(baseline), series.c_str(),
        (totalMs - baselineMs) / (kFrames - kBaselineFrame), totalMs / 1000.0);
    EXPECT_LE(double(last), 1.01 * double(baseline));
    EXPECT_GE(double(last), 0.99 * double(baseline));
    // Bounded as well as finite: inputs are in [0, 1.4] but for the fireflies' 50.
    for (float v : output.pixels) EXPECT_LT(std::abs(v), 1e3f);
}

// Every method with its default settings (JBF's radius 16 too: 75 ms a frame here, 2x radius 4).
DenoiserSettings method(Method m) {
    return test::cpuSettings(m);
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, Soak,
                         ::testing::Values(SoakCase{"jbf", method(Method::Jbf)},
                                           SoakCase{"atrous", method(Method::Atrous)},
                                           SoakCase{"temporal", method(Method::Temporal)},
                                           SoakCase{"svgf", method(Method::Svgf)},
                                           SoakCase{"detail", method(Method::Detail)}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace rtd
