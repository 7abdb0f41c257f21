// Quality on the real course sequence (shared/data/box): noise in a flat region, mean radiance,
// and frame-to-frame stability. Skips with a reason where the data is not beside the repo.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "test_support.h"

namespace rtd {
namespace {

// A flat, static patch of the back wall, clear of the moving sphere and its shadow.
constexpr int kX0 = 110, kX1 = 190, kY0 = 110, kY1 = 190;

float lum(const Image& im, int x, int y) {
    return 0.2126f * im.at(x, y, 0) + 0.7152f * im.at(x, y, 1) + 0.0722f * im.at(x, y, 2);
}

// Standard deviation of the luminance minus its 3x3 mean over the patch: noise, not shading.
double highPassNoise(const Image& im) {
    double sum = 0, sum2 = 0;
    int n = 0;
    for (int y = kY0; y < kY1; ++y)
        for (int x = kX0; x < kX1; ++x) {
            double mean = 0;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) mean += lum(im, x + dx, y + dy);
            double h = lum(im, x, y) - mean / 9.0;
            sum += h;
            sum2 += h * h;
            ++n;
        }
    double m = sum / n;
    return std::sqrt(sum2 / n - m * m);
}

double meanRadiance(const Image& im, const Frame& f) {
    double sum = 0;
    long n = 0;
    for (std::size_t i = 0; i < f.objectId.size(); ++i) {
        if (f.objectId[i] < 0) continue;
        for (int c = 0; c < 3; ++c) sum += im.pixels[3 * i + c];
        ++n;
    }
    return sum / (3.0 * double(n));
}

double patchChange(const Image& a, const Image& b) {
    double sum = 0;
    int n = 0;
    for (int y = kY0; y < kY1; ++y)
        for (int x = kX0; x < kX1; ++x, ++n)
            for (int c = 0; c < 3; ++c) sum += std::abs(a.at(x, y, c) - b.at(x, y, c));
    return sum / (3.0 * n);
}

struct MethodRun {
    std::vector<Image> outputs;
};

class BoxQuality : public ::testing::Test {
  protected:
    static void SetUpTestSuite() {
        if (!std::filesystem::exists(test::boxFolder() / "beauty_0.exr")) return;
        Sequence sequence(test::boxFolder());
        for (int i = 0; i < sequence.frameCount(); ++i) frames_.push_back(sequence.readFrame(i));
        for (Method m : {Method::Atrous, Method::Temporal}) {
            Denoiser denoiser(test::cpuSettings(m));
            MethodRun& run = runs_[m];
            for (const Frame& f : frames_) run.outputs.push_back(denoiser.processFrame(f));
        }
    }
    void SetUp() override {
        if (frames_.empty())
            GTEST_SKIP() << "course data not found at " << test::boxFolder()
                         << " (clone the repo with shared/ beside it)";
    }
    static std::vector<Frame> frames_;
    static std::map<Method, MethodRun> runs_;
};
std::vector<Frame> BoxQuality::frames_;
std::map<Method, MethodRun> BoxQuality::runs_;

TEST_F(BoxQuality, PatchIsOneFlatStaticSurface) {
    const Frame& f = frames_[0];
    int id = f.objectId[std::size_t(kY0) * f.width() + kX0];
    for (const Frame& frame : frames_)
        for (int y = kY0; y < kY1; ++y)
            for (int x = kX0; x < kX1; ++x) {
                ASSERT_EQ(frame.objectId[std::size_t(y) * f.width() + x], id);
                ASSERT_NEAR(frame.normal.at(x, y, 2), f.normal.at(kX0, kY0, 2), 1e-4f);
            }
}

TEST_F(BoxQuality, AtrousCutsFlatRegionNoiseFivefoldTemporalMore) {
    const int last = int(frames_.size()) - 1;
    double input = highPassNoise(frames_[last].beauty);
    double atrous = highPassNoise(runs_[Method::Atrous].outputs[last]);
    double temporal = highPassNoise(runs_[Method::Temporal].outputs[last]);
    std::printf(
        "high-pass noise on the back wall: input %.5f, atrous %.5f (%.1fx), temporal "
        "%.5f (%.1fx)\n",
        input, atrous, input / atrous, temporal, input / temporal);
    EXPECT_GE(input / atrous, 5.0);
    EXPECT_LT(temporal, atrous);
}

TEST_F(BoxQuality, MeanRadianceIsKeptWithinTwoPercent) {
    for (Method m : {Method::Atrous, Method::Temporal})
        for (std::size_t i = 0; i < frames_.size(); ++i) {
            double in = meanRadiance(frames_[i].beauty, frames_[i]);
            double out = meanRadiance(runs_[m].outputs[i], frames_[i]);
            EXPECT_NEAR(out / in, 1.0, 0.02) << toString(m) << " frame " << i;
        }
}

TEST_F(BoxQuality, TemporalIsSteadierThanAtrousInStaticRegions) {
    double atrous = 0, temporal = 0;
    for (std::size_t i = 1; i < frames_.size(); ++i) {
        atrous +=
            patchChange(runs_[Method::Atrous].outputs[i], runs_[Method::Atrous].outputs[i - 1]);
        temporal +=
            patchChange(runs_[Method::Temporal].outputs[i], runs_[Method::Temporal].outputs[i - 1]);
    }
    double steps = double(frames_.size() - 1);
    std::printf("mean frame-to-frame change on the back wall: atrous %.5f, temporal %.5f\n",
                atrous / steps, temporal / steps);
    EXPECT_LT(temporal, 0.5 * atrous);
}

TEST_F(BoxQuality, OutputIsFiniteEverywhere) {
    for (auto& [method, run] : runs_)
        for (const Image& im : run.outputs)
            for (float v : im.pixels) ASSERT_TRUE(std::isfinite(v)) << toString(method);
}

}  // namespace
}  // namespace rtd
