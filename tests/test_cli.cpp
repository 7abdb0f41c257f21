// The rtdenoise command as a user runs it: outputs, config files, progress, and the errors for
// bad input (message naming the file, non-zero exit, nothing half-written).
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>

#include "test_support.h"

namespace fs = std::filesystem;

namespace rtd {
namespace {

using Result = test::CliResult;
using test::quoted;
using test::runCli;

// A small moving-object sequence written in the course layout.
void writeSequence(const fs::path& folder, int frames) {
    for (int i = 0; i < frames; ++i) {
        test::SceneDescription d;
        d.width = 24;
        d.height = 16;
        d.objectCount = 2;
        d.id = [i](int x, int) { return x >= 4 + i && x < 10 + i ? 0 : 1; };
        d.colour = [](int x, int y) {
            return std::array<float, 3>{0.1f * (x % 4), 0.5f, 0.1f * (y % 3)};
        };
        Frame f = test::makeFrame(d);
        test::addNoise(f, 0.2f, unsigned(i));
        f.objectToWorld[0] =
            test::translation(test::worldShiftForPixels(float(i), 4.0f), 0.0f, 0.0f);
        writeFrame(folder, i, f);
    }
}

TEST(Cli, HelpDocumentsEveryOption) {
    Result r = runCli("denoise --help");
    EXPECT_EQ(r.exitCode, 0);
    for (const char* option :
         {"--method",           "--spatial-filter", "--device",      "--sigma-color",
          "--sigma-normal",     "--sigma-plane",    "--sigma-coord", "--radius",
          "--atrous-passes",    "--alpha",          "--clamp-k",     "--clamp-radius",
          "--outlier",          "--outlier-radius", "--outlier-k",   "--png",
          "--exposure",         "--video",          "--config",      "--debug",
          "--separate-objects", "--cpu-isa",        "--tile-passes"})
        EXPECT_NE(r.output.find(option), std::string::npos) << option;
}

TEST(Cli, DenoisesASequenceIntoResultFiles) {
    test::TempFolder dir("cli-run");
    writeSequence(dir.path() / "in", 3);
    Result r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out") +
                      " --png --debug");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (int i = 0; i < 3; ++i) {
        std::string n = std::to_string(i);
        EXPECT_TRUE(fs::exists(dir.path() / "out" / ("result_" + n + ".exr")));
        EXPECT_TRUE(fs::exists(dir.path() / "out" / ("result_" + n + ".png")));
        // The default method (svgf) writes all three debug views.
        for (const char* view : {"reprojection_", "variance_", "history_"})
            EXPECT_TRUE(fs::exists(dir.path() / "out" / (view + n + ".png"))) << view << n;
    }
    EXPECT_NE(r.output.find("frame 3/3"), std::string::npos) << r.output;        // progress
    EXPECT_NE(r.output.find("svgf-accumulate"), std::string::npos) << r.output;  // per-pass summary
    Image result = readExr(dir.path() / "out" / "result_2.exr", {{"R"}, {"G"}, {"B"}});
    EXPECT_EQ(result.width, 24);
    EXPECT_EQ(result.height, 16);
}

TEST(Cli, ConfigFileSetsOptionsAndFlagsOverrideIt) {
    test::TempFolder dir("cli-config");
    writeSequence(dir.path() / "in", 2);
    std::ofstream(dir.path() / "settings.toml") << "method = \"jbf\"\nradius = 3\n";
    Result r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out") +
                      " --config " + quoted(dir.path() / "settings.toml"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("method jbf"), std::string::npos) << r.output;
    r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out") +
               " --config " + quoted(dir.path() / "settings.toml") + " --method atrous");
    EXPECT_NE(r.output.find("method atrous"), std::string::npos) << r.output;
    // A misspelt key is an error naming the file and the key, not silently ignored.
    std::ofstream(dir.path() / "typo.toml") << "sigma_colour = 2\n";
    r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out") +
               " --config " + quoted(dir.path() / "typo.toml"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("typo.toml: unknown setting 'sigma_colour'"), std::string::npos)
        << r.output;
}

TEST(Cli, BadInputFailsNamingTheProblem) {
    test::TempFolder dir("cli-bad");
    // Missing folder.
    Result r =
        runCli("denoise " + quoted(dir.path() / "nothing") + " -o " + quoted(dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("nothing"), std::string::npos) << r.output;
    // A gap in the numbering.
    writeSequence(dir.path() / "gap", 3);
    fs::remove(dir.path() / "gap" / "beauty_1.exr");
    r = runCli("denoise " + quoted(dir.path() / "gap") + " -o " + quoted(dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("beauty_1.exr"), std::string::npos) << r.output;
    // A truncated matrix file.
    writeSequence(dir.path() / "mat", 2);
    fs::resize_file(dir.path() / "mat" / "matrix_1.mat", 100);
    r = runCli("denoise " + quoted(dir.path() / "mat") + " -o " + quoted(dir.path() / "out2"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("matrix_1.mat"), std::string::npos) << r.output;
    // Buffers of different sizes.
    writeSequence(dir.path() / "size", 1);
    writeExr(dir.path() / "size" / "depth_0.exr", Image(8, 8, 1));
    r = runCli("denoise " + quoted(dir.path() / "size") + " -o " + quoted(dir.path() / "out3"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("depth_0.exr"), std::string::npos) << r.output;
    // An output "folder" that is a file.
    std::ofstream(dir.path() / "file") << "x";
    r = runCli("denoise " + quoted(dir.path() / "mat") + " -o " + quoted(dir.path() / "file"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("file"), std::string::npos) << r.output;
    // Unknown method.
    r = runCli("denoise " + quoted(dir.path() / "mat") + " -o " + quoted(dir.path() / "o") +
               " --method magic");
    EXPECT_NE(r.exitCode, 0);
}

TEST(Cli, VideoWithoutFfmpegIsAClearError) {
    test::TempFolder dir("cli-video");
    writeSequence(dir.path() / "in", 1);
    Result r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out") +
                          " --video " + quoted(dir.path() / "v.mp4"),
                      "PATH=/nonexistent");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("ffmpeg"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir.path() / "v.mp4"));
}

TEST(Cli, WritesAVideoWhenFfmpegIsThere) {
    if (!VideoWriter::ffmpegAvailable()) GTEST_SKIP() << "ffmpeg is not installed";
    test::TempFolder dir("cli-video2");
    writeSequence(dir.path() / "in", 3);
    Result r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out") +
                      " --video " + quoted(dir.path() / "v.mp4"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_GT(fs::file_size(dir.path() / "v.mp4"), 100u);
}

}  // namespace
}  // namespace rtd

namespace rtd {
namespace {

// `rtdenoise bench` on small rendered inputs cached in `dir`, its JSON in dir/bench.json.
Result runBench(const test::TempFolder& dir, const std::string& options) {
    return runCli("bench --size 64x48 --input-frames 2 " + options + " --cache " +
                  quoted(dir.path() / "cache") + " --json " + quoted(dir.path() / "bench.json"));
}

std::string readText(const fs::path& path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(Cli, BenchReportsEveryCaseAsTableAndJson) {
    test::TempFolder dir("cli-bench");
    Result r = runBench(dir, "--method atrous svgf --frames 3");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("machine:"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("svgf-accumulate"), std::string::npos) << r.output;  // per pass
    std::string json = readText(dir.path() / "bench.json");
    EXPECT_NE(json.find("\"method\": \"atrous\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"method\": \"svgf\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"width\": 64, \"height\": 48"), std::string::npos) << json;
    EXPECT_NE(runCli("bench --size 64by48").exitCode, 0);  // a bad size is an error
}

// --tile-passes on: the firefly removal as one pass (in the per-pass summary, the bench's rows
// and its JSON), the same results as off.
TEST(Cli, TilePassesRunAsOnePassWithTheSameResult) {
    test::TempFolder dir("cli-tiles");
    writeSequence(dir.path() / "in", 2);
    Result on = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "on") +
                       " --tile-passes on");
    ASSERT_EQ(on.exitCode, 0) << on.output;
    EXPECT_NE(on.output.find("outlier+clamp-rows"), std::string::npos) << on.output;
    EXPECT_EQ(on.output.find("outlier-rows"), std::string::npos) << on.output;
    Result off = runCli("denoise " + quoted(dir.path() / "in") + " -o " +
                        quoted(dir.path() / "off") + " --tile-passes off");
    ASSERT_EQ(off.exitCode, 0) << off.output;
    EXPECT_NE(off.output.find("outlier-rows"), std::string::npos) << off.output;
    Image a = readExr(dir.path() / "on" / "result_1.exr", {{"R"}, {"G"}, {"B"}}),
          b = readExr(dir.path() / "off" / "result_1.exr", {{"R"}, {"G"}, {"B"}});
    EXPECT_LE(test::maxRelativeDifference(a, b), 1e-5);
    Result bench = runBench(dir, "--method temporal --frames 2 --tile-passes on");
    ASSERT_EQ(bench.exitCode, 0) << bench.output;
    EXPECT_NE(bench.output.find("outlier-tile"), std::string::npos) << bench.output;
    EXPECT_NE(readText(dir.path() / "bench.json").find("\"tile_passes\": \"on\""),
              std::string::npos);
}

TEST(Cli, BenchComparesInstructionSetsAgainstTheScalarKernels) {
    test::TempFolder dir("cli-bench-isa");
    Result r = runBench(dir, "--method atrous --frames 2 --device cpu-scalar cpu");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // The scalar row is the baseline (1.0); the vectorised row carries its own speed-up, the
    // last number on its line.
    auto lastNumberOf = [&](const std::string& rowStart) {
        std::size_t at = r.output.find(rowStart);
        if (at == std::string::npos) return -1.0;
        std::string line = r.output.substr(at, r.output.find('\n', at) - at);
        return std::stod(line.substr(line.find_last_of(' ') + 1));
    };
    EXPECT_DOUBLE_EQ(lastNumberOf("atrous    cpu-scalar "), 1.0) << r.output;
    EXPECT_GT(lastNumberOf("atrous    cpu        "), 0.0) << r.output;
    std::string json = readText(dir.path() / "bench.json");
    EXPECT_NE(json.find("\"device_bytes\": "), std::string::npos) << json;
    EXPECT_NE(json.find("\"cpu_kernels\": "), std::string::npos) << json;
    // Choices are names in any case; the scalar kernels run from the command line too.
    writeSequence(dir.path() / "seq", 2);
    Result scalar = runCli("denoise " + quoted(dir.path() / "seq") + " -o " +
                           quoted(dir.path() / "scalar") + " --method ATROUS --cpu-isa Scalar");
    EXPECT_EQ(scalar.exitCode, 0) << scalar.output;
    EXPECT_TRUE(fs::exists(dir.path() / "scalar" / "result_1.exr"));
    // An unknown instruction set is refused by name.
    Result bad = runCli("denoise " + quoted(dir.path()) + " -o " + quoted(dir.path() / "o") +
                        " --cpu-isa avx9000");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.output.find("cpu-isa"), std::string::npos) << bad.output;
    EXPECT_NE(bad.output.find("avx2"), std::string::npos) << bad.output;  // the names allowed
}

}  // namespace
}  // namespace rtd
