// The rtdenoise command as a user runs it: outputs, config files, progress, and the errors for
// bad input (message naming the file, non-zero exit, nothing half-written).
#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <half.h>
#include <signal.h>
#include <spawn.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <thread>

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
          "--separate-objects", "--compression",    "--half"})
        EXPECT_NE(r.output.find(option), std::string::npos) << option;
    // The comparisons' switches (same result, another speed) are the bench's only.
    for (const char* option : {"--cpu-isa", "--tile-passes"})
        EXPECT_EQ(r.output.find(option), std::string::npos) << option;
    Result bench = runCli("bench --help");
    EXPECT_NE(bench.output.find("--tile-passes"), std::string::npos) << bench.output;
    EXPECT_NE(bench.output.find("cpu-scalar"), std::string::npos) << bench.output;
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
        // The default method (detail) writes all three debug views.
        for (const char* view : {"reprojection_", "variance_", "history_"})
            EXPECT_TRUE(fs::exists(dir.path() / "out" / (view + n + ".png"))) << view << n;
    }
    EXPECT_NE(r.output.find("frame 3/3"), std::string::npos) << r.output;        // progress
    EXPECT_NE(r.output.find("detail-temporal"), std::string::npos) << r.output;  // per-pass summary
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
    EXPECT_NE(r.output.find("svgf-temporal"), std::string::npos) << r.output;  // per pass
    std::string json = readText(dir.path() / "bench.json");
    EXPECT_NE(json.find("\"method\": \"atrous\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"method\": \"svgf\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"width\": 64, \"height\": 48"), std::string::npos) << json;
    EXPECT_NE(runCli("bench --size 64by48").exitCode, 0);  // a bad size is an error
}

// bench --tile-passes on: the firefly removal as one tile pass, said in the bench's JSON (the
// result is the tile form's test, Denoiser.TilePassesGiveTheSeparatePassesResult).
TEST(Cli, BenchTimesTheTilePassesWhenAsked) {
    test::TempFolder dir("cli-tiles");
    Result bench = runBench(dir, "--method temporal --frames 2 --tile-passes on");
    ASSERT_EQ(bench.exitCode, 0) << bench.output;
    EXPECT_NE(readText(dir.path() / "bench.json").find("\"tile_passes\": \"on\""),
              std::string::npos);
    // denoise has no such switch.
    writeSequence(dir.path() / "in", 1);
    Result denoise = runCli("denoise " + quoted(dir.path() / "in") + " -o " +
                            quoted(dir.path() / "out") + " --tile-passes on");
    EXPECT_NE(denoise.exitCode, 0);
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
    // An unknown device is refused by name.
    Result bad = runBench(dir, "--method atrous --frames 2 --device cpu-avx9000");
    EXPECT_NE(bad.exitCode, 0);
    EXPECT_NE(bad.output.find("cpu-avx9000"), std::string::npos) << bad.output;
    EXPECT_NE(bad.output.find("cpu-avx2"), std::string::npos) << bad.output;  // those allowed
}

}  // namespace
}  // namespace rtd

// ---- bad input never gives a wrong result silently (issue 20) ----

namespace rtd {
namespace {

std::string denoiseCommand(const fs::path& in, const fs::path& out) {
    return "denoise " + quoted(in) + " -o " + quoted(out) + " -q";
}

std::vector<std::string> namesIn(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

// Defect 3: a second run into the same folder removes the first run's outputs it does not
// rewrite (and nothing else), so `compare` cannot score the two runs together.
TEST(Cli, ASecondRunLeavesOnlyItsOwnOutputs) {
    test::TempFolder dir("cli-rerun");
    writeSequence(dir.path() / "in", 3);
    const fs::path out = dir.path() / "out";
    ASSERT_EQ(runCli(denoiseCommand(dir.path() / "in", out) + " --png --debug").exitCode, 0);
    std::ofstream(out / "notes.txt") << "mine";
    std::ofstream(out / "result_7.exr.bak") << "mine";
    fs::create_directories(out / "result_5.exr");  // not a file this program wrote

    Result r = runCli(denoiseCommand(dir.path() / "in", out) + " --frames 1 --method jbf");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(namesIn(out), (std::vector<std::string>{"notes.txt", "result_0.exr", "result_5.exr",
                                                      "result_7.exr.bak"}));
}

// Defect 3: result and reference sets of different lengths are refused unless --frames says
// which frames to compare; the rows then carry the real frame numbers.
TEST(Cli, CompareRefusesSetsOfDifferentLengths) {
    test::TempFolder dir("cli-compare-lengths");
    const fs::path results = dir.path() / "results", references = dir.path() / "references";
    fs::create_directories(results);
    fs::create_directories(references);
    for (int i = 0; i < 3; ++i)
        writeExr(results / ("result_" + std::to_string(i) + ".exr"), Image(8, 4, 3, 0.5f));
    for (int i = 0; i < 2; ++i)
        writeExr(references / ("reference_" + std::to_string(i) + ".exr"), Image(8, 4, 3, 0.25f));

    Result r = runCli("compare " + quoted(results) + " " + quoted(references));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, results.string() + " holds 3 results")) << r.output;
    EXPECT_TRUE(contains(r.output, references.string() + " holds 2 references")) << r.output;
    EXPECT_TRUE(contains(r.output, "--frames")) << r.output;

    const fs::path json = dir.path() / "m.json";
    r = runCli("compare " + quoted(results) + " " + quoted(references) + " --frames 1 --json " +
               quoted(json));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::ifstream in(json);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    EXPECT_TRUE(contains(text, "{\"frame\": 1, ")) << text;
    EXPECT_FALSE(contains(text, "\"frame\": 0")) << text;
    EXPECT_FALSE(contains(text, "\"frame\": 2")) << text;

    r = runCli("compare " + quoted(results) + " " + quoted(references) + " --frames 0..2");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "frame 2 is outside 0..1")) << r.output;
    // Contact sheets: --sheets chooses among the frames compared.
    r = runCli("compare " + quoted(results) + " " + quoted(references) + " --frames 0..1 -q" +
               " --images " + quoted(dir.path() / "png") + " --sheets 1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(namesIn(dir.path() / "png"), std::vector<std::string>{"contact_1.png"});
    r = runCli("compare " + quoted(results) + " " + quoted(references) + " --frames 1 --images " +
               quoted(dir.path() / "png") + " --sheets 0");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "--sheets: frame 0 is not among the frames compared"))
        << r.output;
}

// Starts the command without a shell (a signal must reach it, not sh), its output into `log`.
pid_t startCli(const std::vector<std::string>& arguments, const fs::path& log) {
    std::vector<std::string> all{RTD_CLI_PATH};
    all.insert(all.end(), arguments.begin(), arguments.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = -1;
    if (posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ) != 0) pid = -1;
    posix_spawn_file_actions_destroy(&actions);
    return pid;
}

bool waitUntil(const std::function<bool()>& condition) {
    for (int i = 0; i < 2000; ++i, std::this_thread::sleep_for(std::chrono::milliseconds(5)))
        if (condition()) return true;
    return false;
}

bool anyNameContains(const fs::path& folder, const std::string& part) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec))
        if (contains(entry.path().filename().string(), part)) return true;
    return false;
}

// Processes whose command line mentions `text` (the test's folder): an ffmpeg left running.
int processesMentioning(const std::string& text) {
    int count = 0;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator("/proc", ec)) {
        std::ifstream in(entry.path() / "cmdline");
        const std::string cmdline{std::istreambuf_iterator<char>(in),
                                  std::istreambuf_iterator<char>()};
        if (contains(cmdline, text) && !contains(cmdline, "test_cli")) ++count;
    }
    return count;
}

// A sequence long enough to be still running when interrupted, cheaply: one 128x128 frame
// written, the others links to its files (links to regular files are frames).
void writeLongSequence(const fs::path& folder, int frames) {
    test::SceneDescription d;
    d.width = 128;
    d.height = 128;
    d.colour = [](int x, int y) {
        return std::array<float, 3>{0.01f * (x % 7), 0.5f, 0.1f * (y % 3)};
    };
    writeFrame(folder, 0, test::makeFrame(d));
    for (int i = 1; i < frames; ++i)
        for (const char* file : {"beauty_", "normal_", "position_", "depth_", "ID_"})
            fs::create_symlink(std::string(file) + "0.exr",
                               folder / (file + std::to_string(i) + ".exr"));
    for (int i = 1; i < frames; ++i)
        fs::create_symlink("matrix_0.mat", folder / ("matrix_" + std::to_string(i) + ".mat"));
}

// Defect 4: SIGINT and SIGTERM remove the temporary files, stop ffmpeg and exit 128 + signal.
TEST(Cli, InterruptRemovesTemporariesAndStopsFfmpeg) {
    test::TempFolder dir("cli-interrupt");
    writeLongSequence(dir.path() / "in", 400);
    struct Case {
        int signal;
        bool video;
    };
    for (const Case c : {Case{SIGINT, false}, Case{SIGTERM, true}}) {
        if (c.video && !VideoWriter::ffmpegAvailable()) continue;
        const fs::path out = dir.path() / ("out-" + std::to_string(c.signal));
        std::vector<std::string> arguments{"denoise", (dir.path() / "in").string(), "-o",
                                           out.string(), "--png"};
        if (c.video) arguments.insert(arguments.end(), {"--video", (out / "v.mp4").string()});
        const pid_t pid = startCli(arguments, dir.path() / "log.txt");
        ASSERT_GT(pid, 0);
        // Running, with files being written (and ffmpeg started): now interrupt it.
        ASSERT_TRUE(waitUntil([&] {
            return fs::exists(out / "result_0.exr") &&
                   (!c.video || anyNameContains(out, ".v.mp4.tmp-"));
        }));
        ::kill(pid, c.signal);
        int status = 0;
        ASSERT_EQ(::waitpid(pid, &status, 0), pid);
        ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status);
        EXPECT_EQ(WEXITSTATUS(status), 128 + c.signal);
        EXPECT_FALSE(fs::exists(out / "result_399.exr"));  // it was interrupted
        EXPECT_FALSE(anyNameContains(out, ".tmp-")) << testing::PrintToString(namesIn(out));
        EXPECT_FALSE(fs::exists(out / "v.mp4"));
        EXPECT_EQ(processesMentioning(out.string()), 0);  // no ffmpeg left writing
    }
}

// Defect 5: options, output paths and every frame's files are checked before the first frame;
// an up-front failure creates nothing, not even the output folder.
TEST(Cli, EverythingIsCheckedBeforeTheFirstFrame) {
    test::TempFolder dir("cli-upfront");
    const fs::path in = dir.path() / "in", out = dir.path() / "out";
    writeSequence(in, 3);
    const auto expectFailureCreatingNothing = [&](const std::string& options,
                                                  const std::vector<std::string>& parts) {
        Result r = runCli(denoiseCommand(in, out) + " " + options);
        EXPECT_NE(r.exitCode, 0) << options;
        for (const std::string& part : parts) EXPECT_TRUE(contains(r.output, part)) << r.output;
        EXPECT_FALSE(fs::exists(out)) << options << ": " << r.output;
    };
    // A bad option value, named as the option (denoise and compare say the same).
    expectFailureCreatingNothing("--exposure -1 --png", {"--exposure must be a finite number > 0"});
    Result compare = runCli("compare " + quoted(in) + " " + quoted(in) + " --exposure -1");
    EXPECT_TRUE(contains(compare.output, "--exposure must be a finite number > 0"))
        << compare.output;
    // A --video path under a regular file.
    std::ofstream(dir.path() / "file") << "x";
    if (VideoWriter::ffmpegAvailable())
        expectFailureCreatingNothing("--video " + quoted(dir.path() / "file" / "v.mp4"),
                                     {"v.mp4", "is not a folder"});
    // A G-buffer file of the last frame missing; one of another size; a channel missing.
    fs::rename(in / "normal_2.exr", dir.path() / "normal_2.exr");
    expectFailureCreatingNothing("", {(in / "normal_2.exr").string(), "no such file"});
    writeExr(in / "normal_2.exr", Image(8, 8, 3));
    expectFailureCreatingNothing("", {(in / "normal_2.exr").string(), "8x8", "beauty_2.exr"});
    writeExr(in / "normal_2.exr", Image(24, 16, 1));
    expectFailureCreatingNothing("", {(in / "normal_2.exr").string(), "missing channel"});
    // A broken .mat of the last frame.
    fs::rename(dir.path() / "normal_2.exr", in / "normal_2.exr");
    fs::copy_file(in / "matrix_2.mat", dir.path() / "matrix_2.mat");
    fs::resize_file(in / "matrix_2.mat", 10);
    expectFailureCreatingNothing("", {(in / "matrix_2.mat").string()});
    // --frames 2: frame 2 is not read, so its broken file does not matter.
    EXPECT_EQ(runCli(denoiseCommand(in, out) + " --frames 2").exitCode, 0);
    EXPECT_TRUE(fs::exists(out / "result_1.exr"));
    fs::remove_all(out);
    fs::copy_file(dir.path() / "matrix_2.mat", in / "matrix_2.mat",
                  fs::copy_options::overwrite_existing);
    // An ID outside -1..K-1 needs the pixels: found when frame 1 is read, the run fails naming
    // the file.
    Image ids = readExr(in / "ID_1.exr", {{"Y"}});
    ids.at(3, 2) = 5.0f;
    writeExr(in / "ID_1.exr", ids);
    Result r = runCli(denoiseCommand(in, out));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (in / "ID_1.exr").string())) << r.output;
    EXPECT_FALSE(fs::exists(out / "result_1.exr"));
}

// Defect 6: each message names the file or option and says what is wrong.
TEST(Cli, MessagesSayWhatIsWrong) {
    test::TempFolder dir("cli-messages");
    const fs::path in = dir.path() / "in", out = dir.path() / "out";
    writeSequence(in, 2);
    std::ofstream(dir.path() / "file") << "x";
    const std::string underFile = quoted(dir.path() / "file" / "x.json");

    fs::create_directories(dir.path() / "settings");
    Result r = runCli(denoiseCommand(in, out) + " --config " + quoted(dir.path() / "settings"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (dir.path() / "settings").string() + ": is a folder"))
        << r.output;

    r = runCli("compare " + quoted(in) + " " + quoted(in) + " --json " + underFile);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "'" + (dir.path() / "file").string() + "' is not a folder"))
        << r.output;
    r = runCli("bench --size 8x8 --json " + underFile);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "is not a folder")) << r.output;

    r = runCli(denoiseCommand(in, out) + " --frames -1");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "--frames: -1 is negative")) << r.output;
    EXPECT_LT(r.output.size(), 200u) << r.output;  // no DBL_MAX written out

    r = runCli("bench --size 99999999999x2");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "the width 99999999999 is out of range 1..16384")) << r.output;
    EXPECT_FALSE(contains(r.output, "rendering")) << r.output;

    r = runCli("denoize");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "unknown command 'denoize'")) << r.output;
    EXPECT_TRUE(contains(r.output, "denoise, render, compare, bench")) << r.output;
    EXPECT_TRUE(contains(r.output, "did you mean 'denoise'?")) << r.output;

    EXPECT_FALSE(fs::exists(out));
}

// Defect 6: only regular files (or links to them) are frames: a folder or a dangling link of a
// frame's name is an error naming it, not a frame whose matrix file then seems to be missing.
TEST(Cli, AFolderOrDanglingLinkIsNotAFrame) {
    test::TempFolder dir("cli-not-frames");
    const fs::path in = dir.path() / "in";
    writeSequence(in, 3);
    fs::create_directories(in / "beauty_3.exr");
    Result r = runCli(denoiseCommand(in, dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (in / "beauty_3.exr").string() + ": is a folder")) << r.output;
    EXPECT_FALSE(contains(r.output, "matrix_3.mat")) << r.output;
    fs::remove(in / "beauty_3.exr");
    fs::create_symlink("nowhere.exr", in / "beauty_3.exr");
    r = runCli(denoiseCommand(in, dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (in / "beauty_3.exr").string() + ": a link to a file that "
                                                                    "does not exist"))
        << r.output;
    fs::remove(in / "beauty_3.exr");
    fs::remove(in / "depth_1.exr");
    fs::create_directories(in / "depth_1.exr");
    r = runCli(denoiseCommand(in, dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (in / "depth_1.exr").string() + ": is a folder")) << r.output;
    EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

// Defect 6: the NaN/Inf warning names the frames that had them.
TEST(Cli, NonFiniteWarningNamesTheFrames) {
    test::TempFolder dir("cli-nan");
    const fs::path in = dir.path() / "in";
    writeSequence(in, 3);
    Image beauty = readExr(in / "beauty_1.exr", {{"R"}, {"G"}, {"B"}});
    beauty.at(2, 3, 0) = std::nanf("");
    beauty.at(5, 1, 2) = INFINITY;
    writeExr(in / "beauty_1.exr", beauty);
    Result r = runCli(denoiseCommand(in, dir.path() / "out"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "warning: frame 1: ")) << r.output;
    EXPECT_TRUE(contains(r.output, "NaN/Inf radiance values replaced by 0")) << r.output;
}

// What the ingest clamps (radiance beyond kMaxRadiance) and the object pixels it takes without a
// normal are reported per frame, and the result is finite.
TEST(Cli, ClampedRadianceAndMissingNormalsAreReported) {
    test::TempFolder dir("cli-clamp");
    const fs::path in = dir.path() / "in";
    writeSequence(in, 3);
    Image beauty = readExr(in / "beauty_2.exr", {{"R"}, {"G"}, {"B"}});
    for (int c = 0; c < 3; ++c) beauty.at(12, 8, c) = 3.4e38f;
    writeExr(in / "beauty_2.exr", beauty);
    Image normal = readExr(in / "normal_0.exr", {{"R"}, {"G"}, {"B"}});
    for (int x = 0; x < 4; ++x)
        for (int c = 0; c < 3; ++c) normal.at(x, 5, c) = 0.0f;
    writeExr(in / "normal_0.exr", normal);
    Result r = runCli(denoiseCommand(in, dir.path() / "out"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "warning: frame 2: 3 radiance values beyond +-1e+16 clamped"))
        << r.output;
    EXPECT_TRUE(
        contains(r.output, "warning: frame 0: 4 object pixels with a zero or NaN/Inf normal"))
        << r.output;
    for (int i = 0; i < 3; ++i) {
        Image out = readExr(dir.path() / "out" / ("result_" + std::to_string(i) + ".exr"),
                            {{"R"}, {"G"}, {"B"}});
        for (float v : out.pixels) ASSERT_TRUE(std::isfinite(v)) << i;
    }
}

// A frame whose depth pass is NaN everywhere (or whose IDs are all -1) comes back as noisy as it
// came: the run succeeds, but the frame is named at once with the pass that broke it.
TEST(Cli, AFrameWithoutUsableGeometryIsNamedWithItsPass) {
    test::TempFolder dir("cli-no-geometry");
    const fs::path in = dir.path() / "in";
    writeSequence(in, 3);
    Image depth = readExr(in / "depth_1.exr", {{"Z", "R", "Y"}});
    for (float& z : depth.pixels) z = std::nanf("");
    writeExr(in / "depth_1.exr", depth);
    Result r = runCli(denoiseCommand(in, dir.path() / "out"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "NaN or Inf depth or position: read as background")) << r.output;
    EXPECT_TRUE(contains(r.output, "(frame 1; is the depth pass broken?)")) << r.output;
    EXPECT_FALSE(contains(r.output, "frame 0;")) << r.output;
    EXPECT_FALSE(contains(r.output, "frame 2;")) << r.output;
}

}  // namespace
}  // namespace rtd

// ---- result_<i>.exr's compression and channel type (issue 22) ----

namespace rtd {
namespace {

Imf::Header resultHeader(const fs::path& out, int frame) {
    return Imf::InputFile((out / ("result_" + std::to_string(frame) + ".exr")).c_str()).header();
}

// --compression and --half (or their config keys) choose how result_<i>.exr is stored; the
// values are the run's, rounded to half with --half.
TEST(Cli, CompressionAndHalfChooseTheResultFiles) {
    test::TempFolder dir("cli-compression");
    const fs::path in = dir.path() / "in", out = dir.path() / "out";
    writeSequence(in, 2);
    ASSERT_EQ(runCli(denoiseCommand(in, out)).exitCode, 0);
    EXPECT_EQ(resultHeader(out, 1).compression(), Imf::NO_COMPRESSION);  // the default
    EXPECT_EQ(resultHeader(out, 1).channels().findChannel("R")->type, Imf::FLOAT);
    const Image floats = readExr(out / "result_1.exr", {{"R"}, {"G"}, {"B"}});

    Result r = runCli(denoiseCommand(in, out) + " --compression ZIP --half");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(resultHeader(out, 1).compression(), Imf::ZIP_COMPRESSION);
    for (const char* name : {"R", "G", "B"})
        EXPECT_EQ(resultHeader(out, 1).channels().findChannel(name)->type, Imf::HALF) << name;
    const Image halves = readExr(out / "result_1.exr", {{"R"}, {"G"}, {"B"}});
    ASSERT_EQ(halves.pixels.size(), floats.pixels.size());
    std::size_t rounded = 0;
    for (std::size_t i = 0; i < floats.pixels.size(); ++i) {
        EXPECT_EQ(halves.pixels[i], float(half(floats.pixels[i]))) << i;
        rounded += halves.pixels[i] != floats.pixels[i];
    }
    EXPECT_GT(rounded, 0u);  // the check above tells half from float

    std::ofstream(dir.path() / "exr.toml") << "compression = \"piz\"\nhalf = true\n";
    const std::string config = " --config " + quoted(dir.path() / "exr.toml");
    ASSERT_EQ(runCli(denoiseCommand(in, out) + config).exitCode, 0);
    EXPECT_EQ(resultHeader(out, 0).compression(), Imf::PIZ_COMPRESSION);
    EXPECT_EQ(resultHeader(out, 0).channels().findChannel("G")->type, Imf::HALF);
    ASSERT_EQ(runCli(denoiseCommand(in, out) + config + " --compression rle").exitCode, 0);
    EXPECT_EQ(resultHeader(out, 0).compression(), Imf::RLE_COMPRESSION);  // the command wins
}

// A compression that does not exist fails naming the option and the choices, before anything
// is written: on the command line and in a config file.
TEST(Cli, AnUnknownCompressionIsRefusedBeforeAnythingIsWritten) {
    test::TempFolder dir("cli-bad-compression");
    const fs::path in = dir.path() / "in", out = dir.path() / "out";
    writeSequence(in, 1);
    const std::vector<std::string> choices = {"none",  "rle", "zips", "zip",  "piz",
                                              "pxr24", "b44", "b44a", "dwaa", "dwab"};
    Result r = runCli(denoiseCommand(in, out) + " --compression lzma");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "--compression: lzma not in")) << r.output;
    for (const std::string& name : choices)
        EXPECT_TRUE(contains(r.output, name)) << name << ": " << r.output;
    EXPECT_FALSE(fs::exists(out));

    std::ofstream(dir.path() / "bad.toml") << "compression = \"lzma\"\n";
    r = runCli(denoiseCommand(in, out) + " --config " + quoted(dir.path() / "bad.toml"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (dir.path() / "bad.toml").string() + ": compression = lzma"))
        << r.output;
    for (const std::string& name : choices)
        EXPECT_TRUE(contains(r.output, name)) << name << ": " << r.output;
    EXPECT_FALSE(fs::exists(out));
}

// A weights file that is not one (or is missing) stops the run before anything is written, naming
// the file; an earlier run's results stay.
TEST(Cli, ABadWeightsFileIsRefusedBeforeAnythingIsWritten) {
    test::TempFolder dir("cli-bad-weights");
    const fs::path in = dir.path() / "in", out = dir.path() / "out";
    writeSequence(in, 2);
    std::ofstream(dir.path() / "junk.txt") << "rtdenoise-weights 2\nnetwork learned-mix 14 16\n";
    Result r = runCli(denoiseCommand(in, out) + " --method learned --weights " +
                      quoted(dir.path() / "junk.txt"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, (dir.path() / "junk.txt").string() + ": not a learned-method "
                                                                        "weights file"))
        << r.output;
    EXPECT_FALSE(fs::exists(out));

    ASSERT_EQ(runCli(denoiseCommand(in, out) + " --method learned").exitCode, 0);
    r = runCli(denoiseCommand(in, out) + " --method learned --weights " +
               quoted(dir.path() / "absent.txt"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "absent.txt: no such weights file")) << r.output;
    EXPECT_TRUE(fs::exists(out / "result_0.exr"));
    EXPECT_TRUE(fs::exists(out / "result_1.exr"));
}

}  // namespace
}  // namespace rtd
