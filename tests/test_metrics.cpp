// Quality metrics against known answers, contact sheets, and `rtdenoise compare` as a user runs
// it (table, JSON, CSV, PNGs, and errors that name the file).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "metrics/metrics.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace rtd {
namespace {

using metrics::FrameMetrics;

Image constant(int w, int h, float value) {
    return Image(w, h, 3, value);
}

// A smooth pattern in [0.1, 0.9]: SSIM needs structure to have something to lose.
Image pattern(int w, int h) {
    Image image(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                image.at(x, y, c) =
                    0.5f + 0.4f * std::sin(0.3f * float(x) + 0.2f * float(y) + float(c));
    return image;
}

Image withNoise(const Image& image, float amplitude, unsigned seed) {
    Image out = image;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-amplitude, amplitude);
    for (float& v : out.pixels) v = std::clamp(v + u(rng), 0.0f, 1.0f);
    return out;
}

float display(float linear, float exposure = 1.0f) {
    return linearToSrgb(acesFilm(exposure * linear));
}

// SSIM straight from the definition: every pixel's restricted 11x11 window, weights
// renormalised over it. The library's separable, banded version must agree.
// With a mask, only the pixels it scores count, in the windows and in the mean.
double bruteForceSsim(const Image& a, const Image& b, const metrics::PixelMask& scored = {}) {
    const auto isScored = [&](int x, int y) {
        return scored.empty() || scored[std::size_t(y) * a.width + x];
    };
    double total = 0.0;
    int count = 0;
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                if (!isScored(x, y)) continue;
                ++count;
                double sw = 0, ma = 0, mb = 0, maa = 0, mbb = 0, mab = 0;
                for (int dy = -5; dy <= 5; ++dy)
                    for (int dx = -5; dx <= 5; ++dx) {
                        const int xx = x + dx, yy = y + dy;
                        if (xx < 0 || yy < 0 || xx >= a.width || yy >= a.height) continue;
                        if (!isScored(xx, yy)) continue;
                        const double w = std::exp(-(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5));
                        const double va = a.at(xx, yy, c), vb = b.at(xx, yy, c);
                        sw += w;
                        ma += w * va;
                        mb += w * vb;
                        maa += w * va * va;
                        mbb += w * vb * vb;
                        mab += w * va * vb;
                    }
                ma /= sw, mb /= sw, maa /= sw, mbb /= sw, mab /= sw;
                const double c1 = 0.0001, c2 = 0.0009;
                total += ((2 * ma * mb + c1) * (2 * (mab - ma * mb) + c2)) /
                         ((ma * ma + mb * mb + c1) * (maa - ma * ma + mbb - mb * mb + c2));
            }
    return total / double(count);
}

// ---- single metrics ----

TEST(Metrics, IdenticalImagesArePerfect) {
    const Image image = pattern(37, 29);
    const FrameMetrics m = metrics::compareFrame(image, image);
    EXPECT_EQ(m.mse, 0.0);
    EXPECT_EQ(m.relMse, 0.0);
    EXPECT_TRUE(std::isinf(m.psnr) && m.psnr > 0);
    EXPECT_DOUBLE_EQ(m.ssim, 1.0);
    EXPECT_FALSE(m.temporalError.has_value());

    metrics::SequenceComparer comparer;
    comparer.addFrame(image, image);
    const FrameMetrics& second = comparer.addFrame(constant(37, 29, 0.3f), constant(37, 29, 0.3f));
    ASSERT_TRUE(second.temporalError.has_value());
    EXPECT_EQ(*second.temporalError, 0.0);
}

TEST(Metrics, ConstantOffsetGivesSquaredOffset) {
    // Dyadic values: the difference and its square are exact in float and double.
    EXPECT_EQ(metrics::mse(constant(13, 7, 0.75f), constant(13, 7, 0.25f)), 0.25);
    EXPECT_EQ(metrics::mse(constant(13, 7, 0.125f), constant(13, 7, 0.25f)), 0.015625);
}

TEST(Metrics, RelMseByHand) {
    Image r(2, 1, 3), x(2, 1, 3);
    r.pixels = {0.1f, 0.2f, 0.3f, 1.0f, 0.0f, 0.5f};
    x.pixels = {0.2f, 0.2f, 0.1f, 0.5f, 0.1f, 0.5f};
    // (0.1^2/0.02 + 0 + 0.2^2/0.1 + 0.5^2/1.01 + 0.1^2/0.01 + 0) / 6
    const double expected = (0.5 + 0.0 + 0.4 + 0.25 / 1.01 + 1.0 + 0.0) / 6.0;
    EXPECT_NEAR(metrics::relMse(x, r), expected, 1e-6);
    EXPECT_NEAR(metrics::relMse(x, r), 0.3579207921, 1e-6);
}

TEST(Metrics, PsnrOfAKnownDifference) {
    // Display images 0.1 apart everywhere: MSE 0.01, 20 dB.
    EXPECT_NEAR(metrics::psnr(constant(9, 9, 0.6f), constant(9, 9, 0.5f)), 20.0, 1e-5);
    EXPECT_NEAR(metrics::psnr(constant(9, 9, 0.25f), constant(9, 9, 0.5f)),
                10.0 * std::log10(1.0 / 0.0625), 1e-9);

    // compareFrame tone-maps first: the PSNR is that of the ACES + sRGB values, with exposure.
    for (float exposure : {1.0f, 2.0f}) {
        const double d = double(display(0.36f, exposure)) - double(display(0.18f, exposure));
        const FrameMetrics m =
            metrics::compareFrame(constant(8, 6, 0.36f), constant(8, 6, 0.18f), exposure);
        EXPECT_NEAR(m.psnr, 10.0 * std::log10(1.0 / (d * d)), 1e-4) << exposure;
        EXPECT_NEAR(m.mse, 0.18 * 0.18, 1e-7);  // linear, whatever the exposure
    }
}

TEST(Metrics, SsimOfConstantImages) {
    const double c1 = metrics::kSsimC1;
    for (auto [a, b] : {std::pair{0.3f, 0.5f}, std::pair{0.9f, 0.1f}, std::pair{0.0f, 0.02f}}) {
        const double expected = (2.0 * a * b + c1) / (double(a) * a + double(b) * b + c1);
        // Larger than the window, and smaller than it (restricted windows everywhere).
        EXPECT_NEAR(metrics::ssim(constant(40, 35, a), constant(40, 35, b)), expected, 1e-9);
        EXPECT_NEAR(metrics::ssim(constant(4, 3, a), constant(4, 3, b)), expected, 1e-9);
    }
}

TEST(Metrics, SsimDropsWithNoiseAndMatchesTheDefinition) {
    const Image clean = pattern(45, 70);  // 70 rows: more than one band of 32
    const Image light = withNoise(clean, 0.05f, 1);
    const Image heavy = withNoise(clean, 0.2f, 2);
    const double sLight = metrics::ssim(light, clean);
    const double sHeavy = metrics::ssim(heavy, clean);
    EXPECT_LT(sLight, 0.99);
    EXPECT_LT(sHeavy, sLight);
    EXPECT_GT(sHeavy, 0.0);
    EXPECT_NEAR(sLight, bruteForceSsim(light, clean), 1e-9);
    EXPECT_NEAR(sHeavy, bruteForceSsim(heavy, clean), 1e-9);
    EXPECT_NEAR(metrics::ssim(clean, heavy), sHeavy, 1e-12);  // symmetric
}

TEST(Metrics, TemporalError) {
    // Result and reference change by the same amount: no temporal error.
    EXPECT_EQ(metrics::temporalError(constant(5, 4, 0.5f), constant(5, 4, 0.25f),
                                     constant(5, 4, 0.625f), constant(5, 4, 0.375f)),
              0.0);
    // 2x1: pixel 0's result moves by 0.25 where the reference moves by 0.125 (error 0.125 in
    // each channel), pixel 1 matches: mean 0.0625.
    Image x(2, 1, 3), xp(2, 1, 3), r(2, 1, 3), rp(2, 1, 3);
    xp.pixels = {0.25f, 0.25f, 0.25f, 0.5f, 0.5f, 0.5f};
    x.pixels = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f};
    rp.pixels = {0.25f, 0.25f, 0.25f, 0.75f, 0.75f, 0.75f};
    r.pixels = {0.375f, 0.375f, 0.375f, 0.75f, 0.75f, 0.75f};
    EXPECT_EQ(metrics::temporalError(x, xp, r, rp), 0.0625);

    // In a sequence: a result that lags one frame behind the reference.
    const std::vector<Image> reference{constant(6, 6, 0.1f), constant(6, 6, 0.4f),
                                       constant(6, 6, 0.4f)};
    const std::vector<Image> lagging{reference[0], reference[0], reference[1]};
    const metrics::SequenceMetrics s = metrics::compareSequence(lagging, reference);
    ASSERT_EQ(s.frames.size(), 3u);
    EXPECT_FALSE(s.frames[0].temporalError.has_value());
    const double step = double(display(0.4f)) - double(display(0.1f));
    EXPECT_NEAR(*s.frames[1].temporalError, step, 1e-7);  // reference moved, result did not
    EXPECT_NEAR(*s.frames[2].temporalError, step, 1e-7);  // result moved, reference did not
    EXPECT_NEAR(*s.mean.temporalError, step, 1e-7);
}

TEST(Metrics, MeanOverFrames) {
    std::vector<FrameMetrics> frames(3);
    frames[0] = {1.0, 2.0, 30.0, 0.9, std::nullopt};
    frames[1] = {2.0, 4.0, 40.0, 0.8, 0.5};
    frames[2] = {3.0, 6.0, 50.0, 0.7, 1.5};
    const FrameMetrics mean = metrics::meanOf(frames);
    EXPECT_DOUBLE_EQ(mean.mse, 2.0);
    EXPECT_DOUBLE_EQ(mean.relMse, 4.0);
    EXPECT_DOUBLE_EQ(mean.psnr, 40.0);
    EXPECT_DOUBLE_EQ(mean.ssim, 0.8);
    ASSERT_TRUE(mean.temporalError.has_value());
    EXPECT_DOUBLE_EQ(*mean.temporalError, 1.0);  // frames 1..N-1 only
    EXPECT_FALSE(metrics::meanOf({frames[0]}).temporalError.has_value());
    EXPECT_THROW(metrics::meanOf({}), Error);
}

TEST(Metrics, MismatchedImagesThrow) {
    EXPECT_THROW(metrics::mse(constant(4, 4, 0.0f), constant(4, 5, 0.0f)), Error);
    EXPECT_THROW(metrics::ssim(Image(4, 4, 1), Image(4, 4, 1)), Error);
    EXPECT_THROW(metrics::compareSequence({constant(2, 2, 0.0f)}, {}), Error);
    metrics::SequenceComparer comparer;
    comparer.addFrame(constant(4, 4, 0.0f), constant(4, 4, 0.0f));
    EXPECT_THROW(comparer.addFrame(constant(5, 4, 0.0f), constant(5, 4, 0.0f)), Error);
}

// Issue 37 item 7: a reference pixel with a NaN or Inf (in any channel) has no right answer: it is
// left out of every metric, which then scores the other pixels exactly.
// The energy ratio: the result's mean over the reference's, per frame and for the sequence (the
// ratio of the frames' summed means, not the mean of the ratios), over the finite reference
// pixels only.
TEST(Metrics, TheEnergyRatioIsTheMeansRatio) {
    Image reference(4, 2, 3, 1.0f), dark(4, 2, 3, 0.9f), bright(4, 2, 3, 3.0f);
    reference.at(0, 0, 1) = std::nanf("");
    dark.at(0, 0, 1) = 100.0f;  // under the reference's NaN: left out
    FrameMetrics a = metrics::compareFrame(dark, reference);
    EXPECT_NEAR(metrics::energyRatio(a), 0.9, 1e-7);  // 0.9f
    Image reference2(4, 2, 3, 2.0f);
    FrameMetrics b = metrics::compareFrame(bright, reference2);
    EXPECT_DOUBLE_EQ(metrics::energyRatio(b), 1.5);
    EXPECT_NEAR(metrics::energyRatio(metrics::meanOf({a, b})), (0.9 + 3.0) / (1.0 + 2.0), 1e-7);
    EXPECT_TRUE(
        std::isnan(metrics::energyRatio(metrics::compareFrame(dark, Image(4, 2, 3, 0.0f)))));
}

TEST(Metrics, NonFiniteReferencePixelsAreLeftOutOfEveryMetric) {
    const int w = 9, h = 7;
    Image reference = constant(w, h, 0.25f), previousReference = reference;
    reference.at(2, 3, 0) = std::numeric_limits<float>::quiet_NaN();
    reference.at(5, 1, 2) = std::numeric_limits<float>::infinity();
    previousReference.at(0, 0, 1) = -std::numeric_limits<float>::infinity();
    const Image result = constant(w, h, 0.75f);
    // Every scored pixel is 0.75 against 0.25: the figures of two constant images.
    const FrameMetrics expected = metrics::compareFrame(result, constant(w, h, 0.25f));
    const FrameMetrics m = metrics::compareFrame(result, reference);
    EXPECT_EQ(m.mse, 0.25);
    EXPECT_NEAR(m.relMse, 0.25 / 0.0725, 1e-12);
    EXPECT_DOUBLE_EQ(m.psnr, expected.psnr);
    EXPECT_NEAR(m.ssim, expected.ssim, 1e-12);
    EXPECT_EQ(metrics::mse(result, reference), 0.25);
    EXPECT_NEAR(metrics::relMse(result, reference), 0.25 / 0.0725, 1e-12);
    EXPECT_EQ(m.excludedPixels, 2u);
    EXPECT_EQ(expected.excludedPixels, 0u);

    // The temporal error leaves out the pixels either frame's reference lacks.
    metrics::SequenceComparer comparer;
    comparer.addFrame(result, previousReference);
    const FrameMetrics second = comparer.addFrame(result, reference);
    ASSERT_TRUE(second.temporalError.has_value());
    EXPECT_EQ(*second.temporalError, 0.0);
    EXPECT_EQ(second.mse, 0.25);
    EXPECT_EQ(comparer.metrics().mean.excludedPixels, 3u);

    // SSIM over the scored pixels only: a pattern whose NaN pixel is left out scores as the brute
    // force over the other pixels' windows does; nothing left to score is an error, not a NaN.
    Image patterned = pattern(w, h);
    const Image noisy = withNoise(patterned, 0.1f, 7);
    patterned.at(4, 4, 1) = std::numeric_limits<float>::quiet_NaN();
    const metrics::PixelMask scored = metrics::finitePixels(patterned);
    ASSERT_EQ(scored.size(), std::size_t(w * h));
    EXPECT_EQ(metrics::excludedPixels(scored), 1u);
    EXPECT_NEAR(metrics::ssim(toneMap(noisy), toneMap(patterned), scored),
                bruteForceSsim(toneMap(noisy), toneMap(patterned), scored), 1e-12);
    EXPECT_THROW(metrics::mse(result, constant(w, h, std::numeric_limits<float>::quiet_NaN())),
                 Error);
}

// ---- images ----

TEST(Metrics, HeatMapUsesTheScale) {
    float dark[3], bright[3];
    metrics::viridis(0.0, dark);
    metrics::viridis(1.0, bright);
    EXPECT_NEAR(dark[0], 0.267f, 0.015f);  // viridis runs from dark purple...
    EXPECT_NEAR(dark[2], 0.329f, 0.015f);
    EXPECT_NEAR(bright[0], 0.993f, 0.015f);  // ...to yellow
    EXPECT_NEAR(bright[1], 0.906f, 0.015f);

    // Pixel 0 exact, pixel 1 far off (relative error > 100 %), pixel 2 NaN.
    Image r = constant(3, 1, 0.5f), x = constant(3, 1, 0.5f);
    for (int c = 0; c < 3; ++c) {
        x.at(1, 0, c) = 5.0f;
        x.at(2, 0, c) = std::numeric_limits<float>::quiet_NaN();
    }
    const Image map = metrics::errorHeatMap(x, r);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(map.at(0, 0, c), dark[c]);
        EXPECT_EQ(map.at(1, 0, c), bright[c]);
    }
    EXPECT_EQ(map.at(2, 0, 0), 1.0f);  // magenta: off the colour map
    EXPECT_EQ(map.at(2, 0, 1), 0.0f);
}

TEST(Metrics, ContactSheetLayout) {
    const int w = 24, h = 16;
    const Image input = withNoise(constant(w, h, 0.5f), 0.3f, 3);
    const Image reference = pattern(w, h);
    const Image result = withNoise(reference, 0.05f, 4);
    metrics::ContactSheetOptions options;
    options.exposure = 1.5f;
    const Image sheet = metrics::contactSheet(&input, result, reference, options);
    const metrics::ContactSheetLayout layout = metrics::contactSheetLayout(w, h, 4, options);
    EXPECT_EQ(sheet.width, 4 * w + 3 * options.gap);
    EXPECT_EQ(sheet.width, layout.width());
    EXPECT_EQ(sheet.height, layout.height());
    EXPECT_GT(layout.legendHeight, options.gap);  // the colour bar and its labels
    EXPECT_EQ(sheet.channels, 3);

    // Panel 3 is the tone-mapped reference, panel 2 the result, panel 4 the heat map.
    const Image referenceDisplay = toneMap(reference, options.exposure);
    const Image resultDisplay = toneMap(result, options.exposure);
    const Image heat = metrics::errorHeatMap(result, reference, options.scale);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                ASSERT_EQ(sheet.at(layout.panelX(2) + x, y, c), referenceDisplay.at(x, y, c));
                ASSERT_EQ(sheet.at(layout.panelX(1) + x, y, c), resultDisplay.at(x, y, c));
                ASSERT_EQ(sheet.at(layout.panelX(3) + x, y, c), heat.at(x, y, c));
            }
    EXPECT_EQ(layout.panelX(2), 2 * (w + options.gap));
    for (float v : sheet.pixels) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);

    // Without an input: three panels.
    const Image three = metrics::contactSheet(nullptr, result, reference, options);
    EXPECT_EQ(three.width, 3 * w + 2 * options.gap);
    EXPECT_EQ(three.at(2 * (w + options.gap), 0, 0), heat.at(0, 0, 0));

    options.legend = false;
    EXPECT_EQ(metrics::contactSheet(nullptr, result, reference, options).height, h);
}

// ---- the command ----

using Result = test::CliResult;
using test::quoted;
using test::runCli;

std::string readText(const fs::path& file) {
    std::ifstream in(file);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// Width from a PNG's IHDR chunk (big-endian at byte 16).
int pngWidth(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::array<unsigned char, 24> header{};
    in.read(reinterpret_cast<char*>(header.data()), header.size());
    if (!in || header[1] != 'P' || header[2] != 'N' || header[3] != 'G') return -1;
    return (header[16] << 24) | (header[17] << 16) | (header[18] << 8) | header[19];
}

constexpr int kW = 24, kH = 16;

// The renderer's layout: DIR/beauty_i.exr, DIR/reference/reference_i.exr; results elsewhere.
// Reference 0.25 everywhere, result 0.75: MSE 0.25, relMSE 0.25 / 0.0725 in every frame.
void writeFolders(const fs::path& dir, int frames) {
    fs::create_directories(dir / "scene" / "reference");
    fs::create_directories(dir / "out");
    for (int i = 0; i < frames; ++i) {
        const std::string n = std::to_string(i);
        writeExr(dir / "scene" / ("beauty_" + n + ".exr"),
                 withNoise(constant(kW, kH, 0.5f), 0.4f, i));
        writeExr(dir / "scene" / "reference" / ("reference_" + n + ".exr"),
                 constant(kW, kH, 0.25f));
        writeExr(dir / "out" / ("result_" + n + ".exr"), constant(kW, kH, 0.75f));
    }
}

TEST(CompareCli, PrintsTheTableAndWritesJsonAndCsv) {
    test::TempFolder dir("compare-run");
    writeFolders(dir.path(), 3);
    const Result r = runCli(
        "compare " + quoted(dir.path() / "out") + " " + quoted(dir.path() / "scene" / "reference") +
        " --json " + quoted(dir.path() / "m.json") + " --csv " + quoted(dir.path() / "m.csv"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* column : {"frame", "MSE", "relMSE", "PSNR", "SSIM", "temporal", "mean"})
        EXPECT_NE(r.output.find(column), std::string::npos) << column << "\n" << r.output;
    EXPECT_NE(r.output.find("2.5000e-01"), std::string::npos) << r.output;  // MSE
    EXPECT_NE(r.output.find("3.4483e+00"), std::string::npos) << r.output;  // relMSE

    const std::string json = readText(dir.path() / "m.json");
    EXPECT_EQ(json.front(), '{');
    EXPECT_NE(json.find("\"frames\": ["), std::string::npos) << json;
    EXPECT_NE(json.find("\"mean\": {"), std::string::npos) << json;
    EXPECT_NE(json.find("{\"frame\": 0, \"mse\": 0.25, \"rel_mse\": 3.448275"), std::string::npos)
        << json;
    EXPECT_NE(json.find("\"frame\": 2"), std::string::npos) << json;
    EXPECT_NE(json.find("\"temporal_error\": null, "), std::string::npos) << json;  // frame 0
    EXPECT_NE(json.find("\"temporal_error\": 0, "), std::string::npos) << json;     // static frames
    // Results of 0.75 against references of 0.25: three times the light.
    EXPECT_NE(json.find("\"energy_ratio\": 3}"), std::string::npos) << json;
    EXPECT_EQ(json.find("inf"), std::string::npos) << json;
    EXPECT_EQ(std::count(json.begin(), json.end(), '{'), std::count(json.begin(), json.end(), '}'));

    const std::string csv = readText(dir.path() / "m.csv");
    EXPECT_EQ(
        csv.rfind("frame,mse,rel_mse,psnr,ssim,temporal_error,energy_ratio\n0,0.25,3.448275", 0),
        0u)
        << csv;
    EXPECT_NE(csv.find("\nmean,0.25,3.448275"), std::string::npos) << csv;
    EXPECT_NE(csv.find(",3\n"), std::string::npos) << csv;   // the energy ratio
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5);  // header, 3 frames, mean

    // Quiet: nothing on the terminal, the files still written.
    fs::remove(dir.path() / "m.json");
    const Result q = runCli("compare " + quoted(dir.path() / "out") + " " +
                            quoted(dir.path() / "scene" / "reference") + " -q --json " +
                            quoted(dir.path() / "m.json"));
    EXPECT_EQ(q.exitCode, 0);
    EXPECT_EQ(q.output, "");
    EXPECT_TRUE(fs::exists(dir.path() / "m.json"));
}

TEST(CompareCli, IdenticalFramesHaveInfinitePsnr) {
    test::TempFolder dir("compare-same");
    writeFolders(dir.path(), 2);
    const Result r = runCli("compare " + quoted(dir.path() / "scene" / "reference") + " " +
                            quoted(dir.path() / "scene" / "reference") + " --json " +
                            quoted(dir.path() / "m.json"));
    // A folder of reference_<i>.exr has no result_<i>.exr: this fails, naming the folder...
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("no frames"), std::string::npos) << r.output;
    // ...so copy the references as results.
    for (int i = 0; i < 2; ++i)
        fs::copy_file(
            dir.path() / "scene" / "reference" / ("reference_" + std::to_string(i) + ".exr"),
            dir.path() / "out" / ("result_" + std::to_string(i) + ".exr"),
            fs::copy_options::overwrite_existing);
    const Result same = runCli("compare " + quoted(dir.path() / "out") + " " +
                               quoted(dir.path() / "scene" / "reference") + " --json " +
                               quoted(dir.path() / "m.json"));
    ASSERT_EQ(same.exitCode, 0) << same.output;
    EXPECT_NE(same.output.find("inf"), std::string::npos) << same.output;
    EXPECT_NE(same.output.find("1.0000"), std::string::npos) << same.output;  // SSIM
    const std::string json = readText(dir.path() / "m.json");
    EXPECT_NE(json.find("\"mse\": 0, \"rel_mse\": 0, \"psnr\": null, \"ssim\": 1,"),
              std::string::npos)
        << json;
}

TEST(CompareCli, WritesContactSheets) {
    test::TempFolder dir("compare-images");
    writeFolders(dir.path(), 3);
    const std::string folders =
        quoted(dir.path() / "out") + " " + quoted(dir.path() / "scene" / "reference/");
    // Default frames (first, middle, last); the input found beside reference/: 4 panels.
    Result r = runCli("compare " + folders + " --images " + quoted(dir.path() / "png"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (int i = 0; i < 3; ++i) {
        const fs::path png = dir.path() / "png" / ("contact_" + std::to_string(i) + ".png");
        ASSERT_TRUE(fs::exists(png)) << png;
        EXPECT_EQ(pngWidth(png), 4 * kW + 3 * metrics::ContactSheetOptions{}.gap);
    }
    // Chosen frames; no input beside the reference folder: 3 panels.
    for (int i = 0; i < 3; ++i)
        fs::remove(dir.path() / "scene" / ("beauty_" + std::to_string(i) + ".exr"));
    r = runCli("compare " + folders + " --images " + quoted(dir.path() / "png2") + " --frames 2,1");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_FALSE(fs::exists(dir.path() / "png2" / "contact_0.png"));
    EXPECT_TRUE(fs::exists(dir.path() / "png2" / "contact_1.png"));
    EXPECT_EQ(pngWidth(dir.path() / "png2" / "contact_2.png"),
              3 * kW + 2 * metrics::ContactSheetOptions{}.gap);
    // An explicit --input must hold the frames.
    r = runCli("compare " + folders + " --images " + quoted(dir.path() / "png3") + " --input " +
               quoted(dir.path() / "scene"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("beauty_0.exr"), std::string::npos) << r.output;
    // A frame outside the sequence.
    r = runCli("compare " + folders + " --images " + quoted(dir.path() / "png4") + " --frames 0,7");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("frame 7"), std::string::npos) << r.output;
}

// Whether a NaN is printed as a number ("nan", "-nan", "NaN"; the words "NaN/Inf" aside).
bool containsNan(std::string text) {
    for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
    for (std::size_t at = text.find("nan"); at != std::string::npos; at = text.find("nan", at + 1))
        if (at + 3 == text.size() || text[at + 3] != '/') return true;
    return false;
}

// Issue 37 item 7: NaN/Inf pixels of a reference are left out of every metric, and the command
// says how many; a reference with nothing left, or a result with NaN/Inf, fails: no NaN is ever
// printed with exit status 0.
TEST(CompareCli, NonFiniteReferencePixelsAreLeftOutAndCounted) {
    test::TempFolder dir("compare-nonfinite");
    writeFolders(dir.path(), 3);
    const fs::path reference = dir.path() / "scene" / "reference";
    Image broken = constant(kW, kH, 0.25f);
    broken.at(3, 4, 1) = std::numeric_limits<float>::quiet_NaN();
    broken.at(7, 2, 0) = std::numeric_limits<float>::infinity();
    writeExr(reference / "reference_1.exr", broken);
    const std::string folders = quoted(dir.path() / "out") + " " + quoted(reference);
    Result r = runCli("compare " + folders + " --json " + quoted(dir.path() / "m.json") +
                      " --csv " + quoted(dir.path() / "m.csv"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_FALSE(containsNan(r.output)) << r.output;
    // Frame 1 scores its other pixels: the figures of every frame (MSE 0.25, relMSE 3.4483).
    EXPECT_NE(r.output.find("    1   2.5000e-01   3.4483e+00"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(" mean   2.5000e-01   3.4483e+00"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("warning: " + (reference / "reference_1.exr").string() +
                            ": 2 pixels with NaN/Inf left out of every metric"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(containsNan(readText(dir.path() / "m.json")));
    EXPECT_NE(readText(dir.path() / "m.json").find("\"excluded_reference_pixels\": 2\n}"),
              std::string::npos);
    EXPECT_FALSE(containsNan(readText(dir.path() / "m.csv")));

    // A reference with no finite pixel leaves nothing to score.
    writeExr(reference / "reference_2.exr",
             constant(kW, kH, std::numeric_limits<float>::quiet_NaN()));
    r = runCli("compare " + folders + " --json " + quoted(dir.path() / "m2.json"));
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(
        r.output.find((reference / "reference_2.exr").string() + ": every pixel holds NaN/Inf"),
        std::string::npos)
        << r.output;
    EXPECT_FALSE(containsNan(r.output.substr(0, r.output.find("error:")))) << r.output;
    EXPECT_FALSE(fs::exists(dir.path() / "m2.json"));

    // A result with NaN: its MSE is NaN (a broken result must not look good), and the run fails.
    writeExr(reference / "reference_2.exr", constant(kW, kH, 0.25f));
    Image result = constant(kW, kH, 0.75f);
    result.at(1, 1, 0) = std::numeric_limits<float>::quiet_NaN();
    writeExr(dir.path() / "out" / "result_2.exr", result);
    r = runCli("compare " + folders);
    EXPECT_NE(r.exitCode, 0) << r.output;
    EXPECT_NE(
        r.output.find((dir.path() / "out" / "result_2.exr").string() + ": 1 pixel with NaN/Inf"),
        std::string::npos)
        << r.output;
}

TEST(CompareCli, BadInputFailsNamingTheFile) {
    test::TempFolder dir("compare-bad");
    writeFolders(dir.path(), 3);
    const std::string reference = quoted(dir.path() / "scene" / "reference");

    // A missing reference.
    fs::remove(dir.path() / "scene" / "reference" / "reference_1.exr");
    Result r = runCli("compare " + quoted(dir.path() / "out") + " " + reference);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("reference_1.exr"), std::string::npos) << r.output;

    // A reference of another size.
    writeExr(dir.path() / "scene" / "reference" / "reference_1.exr", constant(kW, kH + 1, 0.25f));
    r = runCli("compare " + quoted(dir.path() / "out") + " " + reference);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("reference_1.exr: 24x17, but"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("result_1.exr is 24x16"), std::string::npos) << r.output;

    // A result and its reference of another size than frame 0.
    writeExr(dir.path() / "scene" / "reference" / "reference_1.exr", constant(kW, kH, 0.25f));
    writeExr(dir.path() / "scene" / "reference" / "reference_2.exr", constant(8, 8, 0.25f));
    writeExr(dir.path() / "out" / "result_2.exr", constant(8, 8, 0.25f));
    r = runCli("compare " + quoted(dir.path() / "out") + " " + reference);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("result_2.exr: 8x8, but"), std::string::npos) << r.output;

    // A --json file in a folder that does not exist.
    r = runCli("compare " + quoted(dir.path() / "out") + " " + reference + " --json " +
               quoted(dir.path() / "no" / "m.json"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("m.json: cannot write"), std::string::npos) << r.output;

    // An empty result folder.
    fs::create_directories(dir.path() / "empty");
    r = runCli("compare " + quoted(dir.path() / "empty") + " " + reference);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("empty: no frames"), std::string::npos) << r.output;

    // A gap in the results.
    fs::remove(dir.path() / "out" / "result_1.exr");
    r = runCli("compare " + quoted(dir.path() / "out") + " " + reference);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("result_1.exr is missing"), std::string::npos) << r.output;

    // No such folder, and a bad exposure.
    r = runCli("compare " + quoted(dir.path() / "nothing") + " " + reference);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("nothing: no such folder"), std::string::npos) << r.output;
    r = runCli("compare " + quoted(dir.path() / "out") + " " + reference + " --exposure 0");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--exposure"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace rtd
