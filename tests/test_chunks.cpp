// Issue 40: a shot denoised in chunks (`denoise --frames A:B --warmup W`), as a farm runs it:
// the chunks' results match one run over the whole shot, carry the input's frame numbers, and a
// chunk's run touches only its own frames' files.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "metrics/metrics.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace rtd {
namespace {

using test::quoted;
using test::runCli;

const ChannelChoices kRgb{{"R"}, {"G"}, {"B"}};

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

std::vector<std::string> namesIn(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::vector<std::string> resultNames(int first, int end, const char* extension = ".exr") {
    std::vector<std::string> names;
    for (int i = first; i < end; ++i) names.push_back(fmt::format("result_{}{}", i, extension));
    std::sort(names.begin(), names.end());
    return names;
}

// docs/farm.md's seam table (2026-12-05): with a warm-up of 16 frames, the worst join of any
// temporal method on the scenes with camera motion, moving objects and a light switch had a
// temporal error of 4.6e-3 against the whole run (display space) and a relMSE of 7.1e-4; these
// bound them. Without a warm-up the joins are several times worse (1.4e-2 to 6.5e-2).
constexpr double kSeamTemporalErrorW16 = 5e-3;
constexpr double kSeamRelMseW16 = 1e-3;

// Frames 0..frames-1 of `chunks` against the same frames of `whole`, per frame: relMSE, and the
// temporal error (0 for frame 0).
struct Difference {
    std::vector<double> relMse;
    std::vector<double> temporalError;
};

Difference differenceOf(const fs::path& chunks, const fs::path& whole, int frames) {
    Difference d;
    Image previousChunk, previousWhole;
    for (int i = 0; i < frames; ++i) {
        const std::string name = fmt::format("result_{}.exr", i);
        const Image chunk = readExr(chunks / name, kRgb), reference = readExr(whole / name, kRgb);
        d.relMse.push_back(metrics::relMse(chunk, reference));
        const Image chunkDisplay = toneMap(chunk), wholeDisplay = toneMap(reference);
        d.temporalError.push_back(i == 0 ? 0.0
                                         : metrics::temporalError(chunkDisplay, previousChunk,
                                                                  wholeDisplay, previousWhole));
        previousChunk = chunkDisplay;
        previousWhole = wholeDisplay;
    }
    return d;
}

double largest(const std::vector<double>& values, std::size_t first, std::size_t end) {
    return *std::max_element(values.begin() + std::ptrdiff_t(first),
                             values.begin() + std::ptrdiff_t(end));
}

// A rendered 48-frame camera pan (camera motion: the history is reprojected at every frame) in
// 4 chunks of 12 frames into one folder, with `method`:
//  - the default warm-up (48) reaches frame 0 from every chunk: the results are the whole run's,
//    bit for bit (and every chunk left the others' files alone);
//  - with `shorterWarmups` (the default method): a warm-up of 16 starts chunks 2 and 3 mid-shot,
//    their joins are within the measured bounds; without one each join is a jump beyond them
//    (the test can fail).
void expectChunksMatchTheWholeRun(const std::string& method, bool shorterWarmups) {
    test::TempFolder dir("chunks-" + method);
    const fs::path scene = dir.path() / "scene";
    const test::CliResult render = runCli("render camera-pan -o " + quoted(scene) +
                                          " --width 64 --height 48 --frames 48 --ref-spp 1 -q");
    ASSERT_EQ(render.exitCode, 0) << render.output;
    ASSERT_GE(kDefaultChunkWarmup, 36);
    const std::string options = " --method " + method + " --device cpu -q";
    const fs::path whole = dir.path() / "whole";
    test::CliResult r = runCli("denoise " + quoted(scene) + " -o " + quoted(whole) + options);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::vector<std::string> warmups{""};
    if (shorterWarmups) warmups.insert(warmups.end(), {" --warmup 16", " --warmup 0"});
    for (const std::string& warmup : warmups) {
        SCOPED_TRACE(warmup);
        const fs::path chunks = dir.path() / ("chunks" + std::to_string(warmup.size()));
        for (int first = 0; first < 48; first += 12) {
            r = runCli("denoise " + quoted(scene) + " -o " + quoted(chunks) + options +
                       fmt::format(" --frames {}:{}", first, first + 12) + warmup);
            ASSERT_EQ(r.exitCode, 0) << r.output;
        }
        EXPECT_EQ(namesIn(chunks), resultNames(0, 48));
        const Difference d = differenceOf(chunks, whole, 48);
        // The first chunk starts where the shot does: the whole run's frames exactly.
        EXPECT_EQ(largest(d.relMse, 0, 12), 0.0);
        if (warmup.empty()) {
            EXPECT_EQ(largest(d.relMse, 0, 48), 0.0);
            EXPECT_EQ(largest(d.temporalError, 0, 48), 0.0);
            continue;
        }
        for (std::size_t join : {12u, 24u, 36u}) {
            SCOPED_TRACE(join);
            if (warmup == " --warmup 16") {
                EXPECT_LE(largest(d.temporalError, join, join + 12), kSeamTemporalErrorW16);
                EXPECT_LE(largest(d.relMse, join, join + 12), kSeamRelMseW16);
            } else {  // no warm-up: a join a viewer sees
                EXPECT_GT(largest(d.temporalError, join, join + 2), 2 * kSeamTemporalErrorW16);
            }
        }
    }
}

TEST(Chunks, FourChunksMatchOneRunOverTheRenderedShotDetail) {
    expectChunksMatchTheWholeRun("detail", true);
}
TEST(Chunks, FourChunksMatchOneRunOverTheRenderedShotSvgf) {
    expectChunksMatchTheWholeRun("svgf", false);
}
TEST(Chunks, FourChunksMatchOneRunOverTheRenderedShotTemporal) {
    expectChunksMatchTheWholeRun("temporal", false);
}

// A small moving-object sequence in the course layout (frames 0..frames-1).
void writeSequence(const fs::path& folder, int frames) {
    for (int i = 0; i < frames; ++i) {
        test::SceneDescription d;
        d.width = 24;
        d.height = 16;
        d.objectCount = 2;
        d.id = [i](int x, int) { return x >= 2 + i && x < 8 + i ? 0 : 1; };
        Frame f = test::makeFrame(d);
        test::addNoise(f, 0.2f, unsigned(i));
        f.objectToWorld[0] =
            test::translation(test::worldShiftForPixels(float(i), 4.0f), 0.0f, 0.0f);
        writeFrame(folder, i, f);
    }
}

// A chunk's run owns its frames' numbers only: a rerun of a chunk without --png removes that
// chunk's PNGs and no other chunk's; its EXRs are rewritten, the others' untouched.
TEST(Chunks, AChunkRunTouchesOnlyItsOwnFrames) {
    test::TempFolder dir("chunks-own-files");
    writeSequence(dir.path() / "in", 8);
    const fs::path out = dir.path() / "out";
    const std::string command = "denoise " + quoted(dir.path() / "in") + " -o " + quoted(out) +
                                " --method svgf --device cpu -q --png";
    ASSERT_EQ(runCli(command + " --frames 0:4").exitCode, 0);
    ASSERT_EQ(runCli(command + " --frames 4:8").exitCode, 0);
    std::vector<std::string> all = resultNames(0, 8);
    const std::vector<std::string> pngs = resultNames(0, 8, ".png");
    all.insert(all.end(), pngs.begin(), pngs.end());
    std::sort(all.begin(), all.end());
    EXPECT_EQ(namesIn(out), all);

    const auto firstChunkTime = fs::last_write_time(out / "result_2.exr");
    test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(out) +
                               " --method svgf --device cpu -q --frames 4:8");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (int i = 0; i < 8; ++i) {
        EXPECT_TRUE(fs::exists(out / fmt::format("result_{}.exr", i))) << i;
        EXPECT_EQ(fs::exists(out / fmt::format("result_{}.png", i)), i < 4) << i;
    }
    EXPECT_EQ(fs::last_write_time(out / "result_2.exr"), firstChunkTime);

    // A run over the whole shot owns every number again: a shorter one removes the rest.
    ASSERT_EQ(runCli(command.substr(0, command.size() - 6) + " --frames 3").exitCode, 0);
    EXPECT_EQ(namesIn(out), resultNames(0, 3));
}

// Chunks are the input's own frame numbers: Blender's 0001.exr.. are frames 1..4, and the
// results carry those numbers; a chunk reaching outside them fails naming the input and its
// frames, before anything is created; a warm-up without a chunk, or an empty chunk, is refused.
TEST(Chunks, ChunksUseTheInputsFrameNumbersAndBadRangesFailFirst) {
    test::TempFolder dir("chunks-numbers");
    const fs::path blender = fs::path(RTD_SOURCE_DIR) / "tests/data/blender/noisy";
    const fs::path out = dir.path() / "out";
    test::CliResult r = runCli("denoise " + quoted(blender) + " -o " + quoted(out) +
                               " --method svgf --device cpu --frames 3..4 --warmup 1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(namesIn(out), (std::vector<std::string>{"result_3.exr", "result_4.exr"}));
    EXPECT_TRUE(contains(r.output, "frames 3..4 (2 frames, after 1 warm-up frames not written)"))
        << r.output;

    // The same frames of a run from frame 1 (its result_<i> count from 0): the warm-up that
    // reaches the first frame makes them identical.
    const fs::path whole = dir.path() / "whole";
    ASSERT_EQ(runCli("denoise " + quoted(blender) + " -o " + quoted(whole) +
                     " --method svgf --device cpu -q")
                  .exitCode,
              0);
    r = runCli("denoise " + quoted(blender) + " -o " + quoted(out) +
               " --method svgf --device cpu -q --frames 3:5 --warmup 2");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(
        metrics::mse(readExr(out / "result_4.exr", kRgb), readExr(whole / "result_3.exr", kRgb)),
        0.0);

    const fs::path fresh = dir.path() / "fresh";
    for (const char* range : {"0:3", "4:6"}) {
        r = runCli("denoise " + quoted(blender) + " -o " + quoted(fresh) + " --frames " + range);
        EXPECT_NE(r.exitCode, 0);
        EXPECT_TRUE(contains(r.output, "reach outside")) << r.output;
        EXPECT_TRUE(contains(r.output, "frames 1..4")) << r.output;
        EXPECT_FALSE(fs::exists(fresh));
    }
    r = runCli("denoise " + quoted(blender) + " -o " + quoted(fresh) + " --frames 3 --warmup 2");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "--warmup is for a chunk")) << r.output;
    r = runCli("denoise " + quoted(blender) + " -o " + quoted(fresh) + " --frames 3:3");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "the chunk is empty")) << r.output;
    r = runCli("denoise " + quoted(blender) + " -o " + quoted(fresh) + " --frames 2:x");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "'x' is not a whole number")) << r.output;
    // --dry-run: checks the same, writes nothing.
    r = runCli("denoise " + quoted(blender) + " -o " + quoted(fresh) + " --frames 2: --dry-run");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "would denoise frames 2..4 (3 frames, after 1 warm-up"))
        << r.output;
    EXPECT_FALSE(fs::exists(fresh));
}

}  // namespace
}  // namespace rtd
