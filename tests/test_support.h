// Synthetic frames with known geometry for the tests: a pinhole camera at the origin looking
// down +z, fronto-parallel surfaces, per-pixel IDs and colours from callbacks.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "render/render_sequence.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.hpp"

namespace rtd::test {

constexpr float kFocal = 64.0f;  // pixels

// pixel = (f x / z + w/2, f y / z + h/2), s.w = z: the convention of shared/data/README.md.
inline Matrix4 pinholeWorldToScreen(int width, int height) {
    Matrix4 m;
    m.m[0] = {kFocal, 0.0f, 0.5f * float(width), 0.0f};
    m.m[1] = {0.0f, kFocal, 0.5f * float(height), 0.0f};
    m.m[2] = {0.0f, 0.0f, 1.0f, 0.0f};
    m.m[3] = {0.0f, 0.0f, 1.0f, 0.0f};
    return m;
}

inline Matrix4 translation(float x, float y, float z) {
    Matrix4 m = Matrix4::identity();
    m.m[0][3] = x;
    m.m[1][3] = y;
    m.m[2][3] = z;
    return m;
}

// World x offset that moves a point at depth z by `pixels` pixels on screen.
inline float worldShiftForPixels(float pixels, float z) {
    return pixels * z / kFocal;
}

struct SceneDescription {
    int width = 32;
    int height = 32;
    int objectCount = 1;
    std::function<int(int, int)> id = [](int, int) { return 0; };
    std::function<float(int, int)> depth = [](int, int) { return 4.0f; };
    std::function<std::array<float, 3>(int, int)> normal = [](int, int) {
        return std::array<float, 3>{0.0f, 0.0f, -1.0f};
    };
    std::function<std::array<float, 3>(int, int)> colour = [](int, int) {
        return std::array<float, 3>{0.5f, 0.5f, 0.5f};
    };
};

// Positions are the unprojected pixel centres at each pixel's depth, so the G-buffer agrees with
// the matrices exactly; background pixels (ID -1) get normal 0, position 0, depth 0.
inline Frame makeFrame(const SceneDescription& d) {
    Frame f;
    f.beauty = Image(d.width, d.height, 3);
    f.normal = Image(d.width, d.height, 3);
    f.position = Image(d.width, d.height, 3);
    f.depth = Image(d.width, d.height, 1);
    f.objectId.resize(std::size_t(d.width) * d.height);
    f.objectToWorld.assign(d.objectCount, Matrix4::identity());
    f.worldToScreen = pinholeWorldToScreen(d.width, d.height);
    for (int y = 0; y < d.height; ++y) {
        for (int x = 0; x < d.width; ++x) {
            int id = d.id(x, y);
            f.objectId[std::size_t(y) * d.width + x] = id;
            auto c = d.colour(x, y);
            for (int k = 0; k < 3; ++k) f.beauty.at(x, y, k) = c[k];
            if (id < 0) continue;
            float z = d.depth(x, y);
            auto n = d.normal(x, y);
            f.depth.at(x, y) = z;
            f.position.at(x, y, 0) = (float(x) + 0.5f - 0.5f * float(d.width)) * z / kFocal;
            f.position.at(x, y, 1) = (float(y) + 0.5f - 0.5f * float(d.height)) * z / kFocal;
            f.position.at(x, y, 2) = z;
            for (int k = 0; k < 3; ++k) f.normal.at(x, y, k) = n[k];
        }
    }
    return f;
}

// Mean of every value of an image (all channels).
inline double meanValue(const Image& image) {
    double sum = 0.0;
    for (float v : image.pixels) sum += v;
    return sum / double(image.pixels.size());
}

// Adds zero-mean uniform noise of half-width `amplitude` to the beauty (deterministic).
inline void addNoise(Frame& f, float amplitude, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-amplitude, amplitude);
    for (float& v : f.beauty.pixels) v = std::max(0.0f, v + u(rng));
}

// How far two back ends' (or instruction sets') results of a method may lie apart, relative: the
// filters sum in another order (1e-3). The learned method's softmax turns the A-Trous levels'
// rounding into a slightly different choice of level at a few pixels, which detail's
// stabilisation carries into the next frames (measured on the 4 frames: at most 6.0e-3 between
// the SSE2 and scalar kernels, 3.2e-4 for AVX2 and AVX-512); its network itself agrees within
// 1e-4 (test_learned's known answer).
inline double backEndTolerance(Method method) {
    return method == Method::Learned ? 1e-2 : 1e-3;
}

inline DenoiserSettings cpuSettings(Method method) {
    DenoiserSettings s;
    s.method = method;
    s.device = DeviceType::Cpu;
    return s;
}

// A fresh empty folder under the system temp folder, removed with the object.
class TempFolder {
  public:
    explicit TempFolder(const std::string& name)
        : path_(std::filesystem::temp_directory_path() /
                ("rtdenoise-test-" + name + "-" + std::to_string(::getpid()))) {
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempFolder() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

// Runs the built `rtdenoise` command (RTD_CLI_PATH) with `arguments` (and optional environment
// assignments before it); returns its exit code and its stdout + stderr.
struct CliResult {
    int exitCode;
    std::string output;
};

inline CliResult runCli(const std::string& arguments, const std::string& environment = "") {
    std::string command = environment + " '" + RTD_CLI_PATH + "' " + arguments + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    std::string output;
    std::array<char, 4096> buffer;
    while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe))
        output.append(buffer.data(), n);
    int status = pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

// A path quoted for the shell command line above.
inline std::string quoted(const std::filesystem::path& p) {
    // Appended, not "'" + ... : g++ 12 warns falsely (-Wrestrict) about the operator+ form.
    std::string q = "'";
    q += p.string();
    q += '\'';
    return q;
}

inline std::filesystem::path boxFolder() {
    return std::filesystem::path(RTD_SHARED_DIR) / "data" / "box";
}

// max |b - a| / max(|a|, 1e-2) over all values: the measure of the back-end and
// instruction-set equivalence tests.
inline double maxRelativeDifference(const Image& a, const Image& b) {
    double worst = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        worst = std::max(worst, std::abs(double(b.pixels[i]) - a.pixels[i]) /
                                    std::max(std::abs(double(a.pixels[i])), 1e-2));
    return worst;
}

// The frames (G-buffer and 1-spp beauty) of a small rendered sequence: 96x64, 4 frames.
// split: with the split signal (specular, roughness, hit distance).
inline std::vector<Frame> renderSmallSequence(const std::string& scene, int width = 96,
                                              int height = 64, int frames = 4, bool split = false) {
    TempFolder dir("small-" + scene);
    render::RenderSettings r;
    r.width = width;
    r.height = height;
    r.frames = frames;
    r.gbufferOnly = true;
    r.split = split;
    render::renderSequence(scene, r, dir.path());
    Sequence sequence(dir.path());
    std::vector<Frame> result;
    for (int i = 0; i < sequence.frameCount(); ++i) result.push_back(sequence.readFrame(i));
    return result;
}

}  // namespace rtd::test
