// The detail method (methods/detail.cpp): known answers on synthetic frames, and what it keeps
// that SVGF blurs (a thin shadow line) or lags on (a light switched off).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernel_harness.h"
#include "test_support.h"

namespace rtd {
namespace {

using test::makeFrame;
using test::SceneDescription;

// A static 48x48 wall whose illumination is `level` with a one-pixel shadow line (0.05 of it) at
// column 24, noise of +-amplitude added (the seed per frame).
Frame wallWithShadowLine(float level, float amplitude, unsigned seed) {
    SceneDescription d;
    d.width = 48;
    d.height = 48;
    d.colour = [level](int x, int) {
        float v = x == 24 ? 0.05f * level : level;
        return std::array<float, 3>{v, v, v};
    };
    Frame f = makeFrame(d);
    if (amplitude > 0.0f) test::addNoise(f, amplitude, seed);
    return f;
}

// Mean of channel 0 over column x, rows 8..39 (away from the borders).
double columnMean(const Image& image, int x) {
    double sum = 0.0;
    for (int y = 8; y < 40; ++y) sum += image.at(x, y, 0);
    return sum / 32.0;
}

TEST(Detail, ConstantIlluminationStaysConstantAndTextureIsKept) {
    // Radiance = albedo (a checker) * constant illumination: demodulation gives a constant, every
    // pass keeps it, remodulation restores the checker.
    SceneDescription d;
    d.width = 40;
    d.height = 32;
    auto checker = [](int x, int y) { return ((x / 2 + y / 2) % 2) ? 0.9f : 0.2f; };
    d.colour = [&](int x, int y) {
        float a = checker(x, y);
        return std::array<float, 3>{0.8f * a, 0.4f * a, 0.2f * a};
    };
    Frame frame = makeFrame(d);
    Image albedo(d.width, d.height, 3);
    for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x)
            for (int c = 0; c < 3; ++c) albedo.at(x, y, c) = checker(x, y) / float(1 << c);
    frame.albedo = albedo;
    Denoiser denoiser(test::cpuSettings(Method::Detail));
    for (int i = 0; i < 4; ++i) {
        Image out = denoiser.processFrame(frame);
        for (std::size_t k = 0; k < out.pixels.size(); ++k)
            ASSERT_NEAR(out.pixels[k], frame.beauty.pixels[k], 1e-5f) << "frame " << i;
    }
}

TEST(Detail, ReducesNoiseOnAStaticNoisyWall) {
    Denoiser denoiser(test::cpuSettings(Method::Detail));
    double inputError = 0, outputError = 0;
    for (int i = 0; i < 8; ++i) {
        SceneDescription d;
        d.width = d.height = 48;
        d.colour = [](int, int) { return std::array<float, 3>{0.5f, 0.5f, 0.5f}; };
        Frame frame = makeFrame(d);
        test::addNoise(frame, 0.4f, unsigned(100 + i));
        Image out = denoiser.processFrame(frame);
        if (i == 7)
            for (std::size_t k = 0; k < out.pixels.size(); ++k) {
                inputError += std::pow(frame.beauty.pixels[k] - 0.5, 2);
                outputError += std::pow(out.pixels[k] - 0.5, 2);
            }
    }
    EXPECT_LT(outputError, inputError / 50.0);
}

// A one-pixel shadow line on a noisy wall: after 16 frames SVGF's blurred feedback has filled
// it in, the detail method's unfiltered history keeps it dark.
TEST(Detail, KeepsAThinShadowLineThatSvgfFillsIn) {
    Denoiser detail(test::cpuSettings(Method::Detail)), svgf(test::cpuSettings(Method::Svgf));
    Image a, b;
    for (int i = 0; i < 16; ++i) {
        Frame frame = wallWithShadowLine(1.0f, 0.3f, unsigned(7 + i));
        a = detail.processFrame(frame);
        b = svgf.processFrame(frame);
    }
    const double truth = 0.05;
    const double detailError = std::fabs(columnMean(a, 24) - truth);
    const double svgfError = std::fabs(columnMean(b, 24) - truth);
    RecordProperty("detail_line", std::to_string(columnMean(a, 24)));
    RecordProperty("svgf_line", std::to_string(columnMean(b, 24)));
    EXPECT_LT(detailError, 0.5 * svgfError)
        << "detail " << columnMean(a, 24) << ", svgf " << columnMean(b, 24);
    // The fast history's 5x5 box holds one line column in five: the clamp lifts the line a
    // little (0.28 with the default clamp of 1.5 sigma, 0.12 with 2), SVGF's feedback to 0.82.
    EXPECT_LT(detailError, 0.3);
    EXPECT_NEAR(columnMean(a, 12), 1.0, 0.05);  // the lit wall keeps its level
}

// The light goes from 1 to 0.2 after 12 frames of history: without a confidence input the
// anti-lag follows within the frame of the switch.
TEST(Detail, FollowsALightSwitchedOffInTheSameFrame) {
    Denoiser denoiser(test::cpuSettings(Method::Detail));
    for (int i = 0; i < 12; ++i) denoiser.processFrame(wallWithShadowLine(1.0f, 0.3f, 30u + i));
    Image out = denoiser.processFrame(wallWithShadowLine(0.2f, 0.06f, 99u));
    EXPECT_NEAR(columnMean(out, 12), 0.2, 0.04);
}

// The anti-lag's re-blend, on DetailClamp alone (clamp off): the fast history is 1, the frame
// 0.8 everywhere (no noise: change 0.2), the slow history a checker the new light no longer
// casts, accumulated over 32 frames. The length is cut to 32 * 0.8^8 and the slow history
// blended again for it: the frame's share rises from 1/32 to 1/5.4 (a history only scaled by
// the ratio of the means, 0.8^0.6, would keep 31/32 of the old checker). The luminance moments
// likewise.
TEST(DetailKernels, TheAntiLagBlendsTheHistoryAgainForItsCutLength) {
    const int w = 12, h = 10;
    Harness hs(w, h, 4);
    DeviceBuffer<float> fast = hs.buffer(3), current = hs.buffer(3), slow = hs.buffer(3),
                        moments = hs.buffer(2), length = hs.buffer(1), filterIn = hs.buffer(4),
                        lagScale = hs.buffer(1), fastSums = hs.buffer(7),
                        currentSums = hs.buffer(3);
    auto checker = [](int x, int y) { return (x + y) % 2 ? 1.5f : 0.5f; };
    const float hAccumulated = 32.0f, now = 0.8f;
    // The luminance moments before this frame (mean 1, variance 0.01), accumulated with the
    // frame as DetailAccumulate does (weight max(alpha, 1/32)).
    constexpr float kAlpha = 0.2f, kMeanBefore = 1.0f, kVarianceBefore = 0.01f;
    const float dBefore = now - kMeanBefore;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = hs.layout.index(x, y);
            hs.planes(fast).store(i, make3(1.0f, 1.0f, 1.0f));
            hs.planes(current).store(i, make3(now, now, now));
            const float c0 = checker(x, y) * (1.0f - 1.0f / hAccumulated) + now / hAccumulated;
            hs.planes(slow).store(i, make3(c0, c0, c0));
            length.data()[i] = hAccumulated;
            moments.data()[i] = kMeanBefore + kAlpha * dBefore;
            hs.planeSet(moments).at(1, i) =
                (1.0f - kAlpha) * (kVarianceBefore + kAlpha * dBefore * dBefore);
        }
    GBufferView g = hs.gbuffer();
    constexpr int kRadius = DetailClampKernel::kRadius;
    DetailClampStep step{{g, hs.planes(fast), hs.planeSet(fastSums), kRadius},
                         {g, hs.planes(current), hs.planeSet(currentSums), kRadius},
                         {g, hs.planes(current), hs.planeSet(fastSums), hs.planeSet(currentSums),
                          hs.planes(slow), hs.planeSet(moments), length.data(),
                          hs.planeSet(filterIn), lagScale.data(), 0.0f, 6.0f, kAlpha, 1},
                         {hs.layout, hs.planes(fast), lagScale.data()}};
    runDetailClampStep(step, [&](const auto& kernel) { hs.device->launch(kernel, w, h); });
    const float cut = hAccumulated * std::pow(0.8f, 8.0f);  // 5.37 frames
    const float ratio = std::pow(0.8f, 0.6f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = hs.layout.index(x, y);
            // The length as written (the change is 0.2 less 3 standard errors of a mean that
            // float sums leave a hair above 0).
            const float cutHere = length.data()[i];
            ASSERT_NEAR(cutHere, cut, 0.01f * cut) << x << ", " << y;
            const float keep = (1.0f - 1.0f / cutHere) / (1.0f - 1.0f / hAccumulated);
            const float old = checker(x, y) * (1.0f - 1.0f / hAccumulated);
            const float want = now / cutHere + old * ratio * keep;
            ASSERT_NEAR(hs.planes(slow).load(i).x, want, 1e-3f) << x << ", " << y;
            ASSERT_NEAR(hs.planes(fast).load(i).y, ratio, 1e-4f);  // scaled, not re-blended
            // The moments from before the frame, scaled by the ratio, accumulated again with the
            // cut length's weight (max(alpha, 1/5.37) = alpha here).
            const float mean = kMeanBefore * ratio, d = now - mean;
            const float wantMean = mean + kAlpha * d;
            const float wantVariance =
                (1.0f - kAlpha) * (kVarianceBefore * ratio * ratio + kAlpha * d * d);
            ASSERT_NEAR(moments.data()[i], wantMean, 1e-4f) << x << ", " << y;
            ASSERT_NEAR(hs.planeSet(moments).at(1, i), wantVariance, 1e-5f) << x << ", " << y;
            ASSERT_NEAR(hs.planeSet(filterIn).at(3, i), wantVariance / cutHere, 1e-5f);
        }
}

// The stabilisation's known answer: on a +-0.1 checker around 1 (a 3x3 window's mean
// 1 +- 0.1/9, standard deviation sqrt(0.01 - (0.1/9)^2)), a previous output of 2 is clamped to
// mean + 1.5 sigma and blended in with 0.4; the output is that times the albedo. Where the
// history was not found or kept, the anti-lag fired or nothing is held, the result passes as is.
TEST(DetailKernels, TheStabilisationHoldsThePreviousOutputWithinTheNeighbourhood) {
    const int w = 8, h = 6;
    Harness hs(w, h, 2);
    DeviceBuffer<float> current = hs.buffer(4), held = hs.buffer(3), lagScale = hs.buffer(1),
                        length = hs.buffer(1), stable = hs.buffer(3), albedo = hs.buffer(3);
    std::vector<float> rgbOut(std::size_t(w) * h * 3, -1.0f);
    auto sign = [](int x, int y) { return (x + y) % 2 ? -1.0f : 1.0f; };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const auto i = hs.layout.index(x, y);
            const float v = 1.0f + 0.1f * sign(x, y);
            hs.planeSet(current).rgb().store(i, make3(v, v, v));
            hs.planes(held).store(i, make3(2.0f, 2.0f, 2.0f));
            hs.planes(albedo).store(i, make3(0.5f, 0.5f, 0.5f));
            lagScale.data()[i] = 1.0f;
            length.data()[i] = 5.0f;
            hs.validity.data()[i] = kReprojectionValid;
        }
    // Interior pixels that must pass as they are, one per reason.
    const int noHistory = hs.layout.index(1, 1), cut = hs.layout.index(3, 1),
              antiLag = hs.layout.index(5, 1), nothingHeld = hs.layout.index(2, 3);
    hs.validity.data()[noHistory] = kReprojectionOtherObject;
    length.data()[cut] = 1.0f;
    lagScale.data()[antiLag] = 1.2f;
    hs.planes(held).store(nothingHeld, make3(-1.0f, -1.0f, -1.0f));
    const DetailStabiliseKernel k{hs.gbuffer(),
                                  hs.planeSet(current),
                                  hs.planes(held),
                                  hs.validity.data(),
                                  lagScale.data(),
                                  length.data(),
                                  hs.planes(stable),
                                  hs.planes(albedo),
                                  rgbOut.data(),
                                  0.4f,
                                  1.5f,
                                  {},
                                  nullptr,
                                  0,
                                  4.0f};
    hs.device->launch(k, w, h);
    const float sigma = std::sqrt(0.01f - (0.1f / 9.0f) * (0.1f / 9.0f));
    for (int y = 1; y < h - 1; ++y)
        for (int x = 1; x < w - 1; ++x) {
            const auto i = hs.layout.index(x, y);
            const float c = 1.0f + 0.1f * sign(x, y), mean = 1.0f + 0.1f * sign(x, y) / 9.0f;
            const bool passes = i == noHistory || i == cut || i == antiLag || i == nothingHeld;
            const float want = passes ? c : c + (mean + 1.5f * sigma - c) * 0.4f;
            ASSERT_NEAR(hs.planes(stable).load(i).y, want, 1e-5f) << x << ", " << y;
            ASSERT_NEAR(rgbOut[(std::size_t(y) * w + x) * 3 + 1], 0.5f * want, 1e-5f);
        }
}

// Confidence 0 everywhere drops the history: the frame's result is a fresh denoiser's.
TEST(Detail, ZeroConfidenceGivesAFreshDenoisersResult) {
    DenoiserSettings s = test::cpuSettings(Method::Detail);
    Denoiser kept(s);
    for (int i = 0; i < 5; ++i) kept.processFrame(wallWithShadowLine(1.0f, 0.3f, 50u + i));
    Frame frame = wallWithShadowLine(0.4f, 0.1f, 77u);
    Image confidence(frame.beauty.width, frame.beauty.height, 1);  // zeros
    frame.confidence = confidence;
    Image dropped = kept.processFrame(frame);
    Denoiser fresh(s);
    Image first = fresh.processFrame(frame);
    ASSERT_EQ(dropped.pixels.size(), first.pixels.size());
    for (std::size_t k = 0; k < first.pixels.size(); ++k)
        ASSERT_NEAR(dropped.pixels[k], first.pixels[k], 1e-5f * (1.0f + first.pixels[k])) << k;
    // Confidence 1 keeps it: under the same lighting (where the anti-lag keeps the history
    // too), another result than a fresh denoiser's.
    Denoiser kept2(s);
    for (int i = 0; i < 5; ++i) kept2.processFrame(wallWithShadowLine(1.0f, 0.3f, 50u + i));
    Frame same = wallWithShadowLine(1.0f, 0.3f, 77u);
    same.confidence = Image(same.beauty.width, same.beauty.height, 1);
    same.confidence->pixels.assign(same.confidence->pixels.size(), 1.0f);
    Image continued = kept2.processFrame(same);
    Image sameFirst = Denoiser(s).processFrame(same);
    double differs = 0.0;
    for (std::size_t k = 0; k < sameFirst.pixels.size(); ++k)
        differs = std::max(differs, double(std::fabs(continued.pixels[k] - sameFirst.pixels[k])));
    EXPECT_GT(differs, 1e-2);
}

TEST(Detail, PassesAreDeclaredInOrder) {
    Denoiser denoiser(test::cpuSettings(Method::Detail));
    denoiser.processFrame(wallWithShadowLine(1.0f, 0.0f, 1u));
    std::vector<std::string> names;
    for (const PassInfo& p : denoiser.passes()) names.push_back(p.name);
    const std::vector<std::string> expected = {
        "ingest",           "energy-input",   "outlier",         "geometry",
        "detail-temporal",  "detail-clamp",   "detail-variance", "detail-atrous0",
        "detail-atrous1",   "detail-atrous2", "detail-atrous3",  "detail-atrous4",
        "detail-stabilise", "energy"};
    EXPECT_EQ(names, expected);
}

// ---- the split signal ----

// The frame with specular = `part` of its beauty and roughness r everywhere.
Frame withSpecular(Frame f, float part, float roughness) {
    f.specular = Image(f.width(), f.height(), 3);
    for (std::size_t k = 0; k < f.beauty.pixels.size(); ++k)
        f.specular->pixels[k] = part * f.beauty.pixels[k];
    f.roughness = Image(f.width(), f.height(), 1, roughness);
    return f;
}

TEST(DetailSplit, ZeroSpecularGivesTheCombinedResult) {
    // The diffuse signal is then the beauty itself and the specular one filters zeros.
    Denoiser combined(test::cpuSettings(Method::Detail)), split(test::cpuSettings(Method::Detail));
    for (int i = 0; i < 4; ++i) {
        Frame frame = wallWithShadowLine(1.0f, 0.3f, 10u + unsigned(i));
        Image a = combined.processFrame(frame);
        Image b = split.processFrame(withSpecular(frame, 0.0f, 0.1f));
        ASSERT_EQ(a.pixels, b.pixels) << "frame " << i;
    }
    std::vector<std::string> names;
    for (const PassInfo& p : split.passes()) names.push_back(p.name);
    for (const char* name : {"detail-split", "outlier-specular", "detail-specular-temporal",
                             "detail-specular-atrous0", "add-specular"})
        EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
    // One A-Trous iteration on the specular signal (DetailSettings::specularIterations).
    EXPECT_EQ(std::find(names.begin(), names.end(), "detail-specular-atrous1"), names.end());
}

TEST(DetailSplit, BothSignalsAddUpToAConstantBeauty) {
    // Noise-free, constant red: a glossy lobe (roughness 0.1, kept apart) of 0.4 of the beauty;
    // the two filtered signals add back to the beauty; a rough lobe (0.9, merged) likewise.
    SceneDescription d;
    d.width = d.height = 32;
    d.colour = [](int x, int) { return std::array<float, 3>{0.8f, 0.5f + 0.01f * float(x), 0.2f}; };
    const Frame frame = makeFrame(d);
    DenoiserSettings s = test::cpuSettings(Method::Detail);
    // The signals alone: the energy restoration's luminance gain corrects the green ramp's
    // filtered border, which moves red by 1e-3.
    s.energy.keep = false;
    for (float roughness : {0.1f, 0.9f}) {
        Denoiser denoiser(s);
        for (int i = 0; i < 3; ++i) {
            Image out = denoiser.processFrame(withSpecular(frame, 0.4f, roughness));
            for (std::size_t k = 0; k < out.pixels.size(); k += 3)
                ASSERT_NEAR(out.pixels[k], frame.beauty.pixels[k], 1e-4f)
                    << "pixel " << k / 3 << " roughness " << roughness;
        }
    }
}

TEST(DetailSplit, ANanRoughnessSendsTheLobeToTheDiffuseSignal) {
    // Two objects (left, right), noisy; the left's lobe glossy (kept apart). The right's
    // roughness NaN gives there what a rough one (0.9, merged into the diffuse signal) gives:
    // its pixels are never the specular passes' (which skip them and filter none of theirs).
    SceneDescription d;
    d.width = d.height = 32;
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 16 ? 0 : 1; };
    d.colour = [](int x, int) { return std::array<float, 3>{0.8f, 0.5f + 0.01f * float(x), 0.2f}; };
    Image out[2];
    for (int variant = 0; variant < 2; ++variant) {
        Denoiser denoiser(test::cpuSettings(Method::Detail));
        for (int i = 0; i < 4; ++i) {
            Frame frame = makeFrame(d);
            test::addNoise(frame, 0.3f, 40u + unsigned(i));
            frame = withSpecular(frame, 0.4f, 0.1f);
            for (int y = 0; y < 32; ++y)
                for (int x = 16; x < 32; ++x)
                    frame.roughness->at(x, y, 0) =
                        variant == 0 ? std::numeric_limits<float>::quiet_NaN() : 0.9f;
            out[variant] = denoiser.processFrame(frame);
        }
    }
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_EQ(out[0].at(x, y, c), out[1].at(x, y, c)) << x << ", " << y;
}

// A planar mirror at depth 4 (facing the camera) reflecting stripes 4 further away, seen by a
// camera trucking 0.05 per frame: the wall moves 0.8 pixels a frame, the reflection 0.4 (a
// 12-pixel period). Specular = beauty, with noise; `truth`: the noise-free frame.
Frame mirrorFrame(int frame, unsigned seed, Image* truth) {
    constexpr int kSize = 48;
    constexpr float kDepth = 4.0f, kHit = 4.0f;
    const float camera = 0.05f * float(frame);
    SceneDescription d;
    d.width = d.height = kSize;
    d.depth = [](int, int) { return kDepth; };
    Frame f = makeFrame(d);
    f.worldToCamera = test::translation(-camera, 0.0f, 0.0f);
    f.worldToScreen.m[0][3] = -test::kFocal * camera;  // pinhole after the translation
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            f.position.at(x, y, 0) += camera;
            // The virtual point: along the view ray, the hit distance behind the mirror.
            const float px = f.position.at(x, y, 0) - camera, py = f.position.at(x, y, 1);
            const float length = std::sqrt(px * px + py * py + kDepth * kDepth);
            const float virtualX = camera + px * (1.0f + kHit / length);
            const float v = 0.5f + 0.4f * std::sin(virtualX * 2.0f * 3.14159265f / 1.5f);
            for (int c = 0; c < 3; ++c) f.beauty.at(x, y, c) = v;
        }
    if (truth) *truth = f.beauty;
    test::addNoise(f, 0.5f, seed);
    f = withSpecular(f, 1.0f, 0.0f);
    f.hitDistance = Image(kSize, kSize, 1, kHit);
    return f;
}

TEST(DetailSplit, HitDistanceFollowsAReflectionTheSurfaceWouldSmear) {
    // Followed by its virtual point, the reflection accumulates aligned; followed by the surface,
    // its history is cut short by the parallax (or, without the split, smeared).
    double error[3] = {0, 0, 0};  // with hit distance, without, without the split
    for (int variant = 0; variant < 3; ++variant) {
        Denoiser denoiser(test::cpuSettings(Method::Detail));
        for (int i = 0; i < 16; ++i) {
            Image truth;
            Frame f = mirrorFrame(i, 500u + unsigned(i), &truth);
            if (variant >= 1) f.hitDistance.reset();
            if (variant == 2) {
                f.specular.reset();
                f.roughness.reset();
            }
            Image out = denoiser.processFrame(f);
            if (i < 12) continue;
            for (int y = 8; y < 40; ++y)
                for (int x = 8; x < 40; ++x)
                    error[variant] += std::pow(out.at(x, y, 0) - truth.at(x, y, 0), 2.0);
        }
    }
    // Measured 0.53x and 0.37x (with the anti-lag at 3 standard errors: 0.47x and 0.25x; the
    // lower threshold lowered all three errors, the smeared ones most).
    EXPECT_LT(error[0], 0.6 * error[1]) << error[0] << " " << error[1];
    EXPECT_LT(error[0], 0.5 * error[2]) << error[0] << " " << error[2];
}

TEST(DetailSplit, TheSurfaceFoundAfterTheReflectionGivesWhatItGaveBefore) {
    // A hit distance of 0 everywhere (unknown) follows no reflection: every pixel's specular
    // history is then the surface's, found after the attempt (DetailSpecularSurface, sparse)
    // where without a hit distance it is found first, on every pixel. Both must agree.
    Image out[2];
    for (int variant = 0; variant < 2; ++variant) {
        Denoiser denoiser(test::cpuSettings(Method::Detail));
        for (int i = 0; i < 8; ++i) {
            Frame f = mirrorFrame(i, 700u + unsigned(i), nullptr);
            if (variant == 0)
                f.hitDistance = Image(f.width(), f.height(), 1, 0.0f);
            else
                f.hitDistance.reset();
            out[variant] = denoiser.processFrame(f);
        }
    }
    for (std::size_t k = 0; k < out[0].pixels.size(); ++k)
        ASSERT_NEAR(out[0].pixels[k], out[1].pixels[k], 1e-5f) << "value " << k;
}

}  // namespace
}  // namespace rtd
