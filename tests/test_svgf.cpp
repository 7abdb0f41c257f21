// SVGF: known answers for its passes (kernel level) and its behaviour through the public API.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "kernel_harness.h"
#include "test_support.h"

namespace rtd {
namespace {

SvgfTerms paperTerms() {
    return {1.0f, 128.0f, 4.0f};
}

TEST(SvgfKernels, VarianceIsPropagatedWithSquaredWeights) {
    // Flat wall, constant illumination (luminance term 0), constant variance v: every weight is
    // its B3 tap, so var' = v * (sum of squared 1-D taps)^2 = v * 0.2734375^2.
    Harness h(21, 21, 8);
    DeviceBuffer<float> in = h.buffer(4), out = h.buffer(4), derivatives = h.buffer(3);
    const float v = 0.5f;
    for (int y = 0; y < 21; ++y)
        for (int x = 0; x < 21; ++x) {
            int i = h.layout.index(x, y);
            h.planeSet(in).rgb().store(i, make3(0.7f, 0.7f, 0.7f));
            h.planeSet(in).at(3, i) = v;
        }
    for (int stride : {1, 2, 4}) {
        h.device->launch(SvgfAtrousKernel{h.gbuffer(), h.planeSet(derivatives), h.planeSet(in),
                                          h.planeSet(out), stride, paperTerms()},
                         21, 21);
        int centre = h.layout.index(10, 10);
        EXPECT_NEAR(h.planeSet(out).at(3, centre), v * 0.2734375f * 0.2734375f, 1e-6f)
            << "stride " << stride;
        EXPECT_NEAR(h.planeSet(out).rgb().load(centre).x, 0.7f, 1e-6f);
    }
}

// The last iteration's fused modulation: the caller's interleaved RGB holds the plain kernel's
// result times the albedo factor (a background pixel too), and its own planes are not written.
TEST(SvgfKernels, ModulatedIterationWritesTheResultTimesTheAlbedoInterleavedInsteadOfItsPlanes) {
    const int n = 12;
    Harness h(n, n, 8);
    DeviceBuffer<float> in = h.buffer(4), plain = h.buffer(4), fused = h.buffer(4),
                        albedo = h.buffer(3), derivatives = h.buffer(3);
    std::vector<float> rgb(3 * n * n, -1.0f);
    UnitRandom next{7u};
    h.fillRandom(h.planeSet(in).rgb(), next);
    h.fillRandom(h.planes(albedo), next, 0.5f);
    const Float3 untouched = make3(-7.0f, -7.0f, -7.0f);
    h.setAll(fused, untouched);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            h.planeSet(in).at(3, h.layout.index(x, y)) = 0.05f;
            h.planeSet(fused).at(3, h.layout.index(x, y)) = -7.0f;
        }
    h.ids.data()[h.layout.index(3, 4)] = -1;  // background: passes through, modulated too
    h.device->launch(SvgfAtrousNormal128Kernel{h.gbuffer(), h.planeSet(derivatives), h.planeSet(in),
                                               h.planeSet(plain), 2, paperTerms()},
                     n, n);
    h.device->launch(SvgfAtrousNormal128ModulatedKernel{h.gbuffer(), h.planeSet(derivatives),
                                                        h.planeSet(in), h.planeSet(fused), 2,
                                                        paperTerms(), h.planes(albedo), rgb.data()},
                     n, n);
    h.expectModulatedOutput(h.planeSet(plain).rgb(), h.planes(albedo), rgb, 2e-6f);
    h.expectAll(fused, untouched);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) EXPECT_EQ(h.planeSet(fused).at(3, h.layout.index(x, y)), -7.0f);
    EXPECT_FLOAT_EQ(rgb[3 * (4 * n + 3)], h.planeSet(in).rgb().load(h.layout.index(3, 4)).x *
                                              h.planes(albedo).load(h.layout.index(3, 4)).x);
}

TEST(SvgfKernels, FixedSigmaNormalFactorMatchesThePower) {
    // sigma_n = 128 fixed (the polynomial for -log2 near 1) against max(0, n.n')^128 in double
    // precision, from parallel normals to opposite ones: within 128 times the rounding of n.n'
    // and the fit's 2.2e-7 relative in the exponent, plus exp2's 1e-7.
    const SvgfCentre centre{0.0f, make3(0.0f, 0.0f, 1.0f), 0.0f, 0.0f, 1.0f};
    int weighty = 0;
    for (int k = 0; k <= 2000; ++k) {
        double angle = 3.14159265358979 * k / 2000.0;
        Float3 n = make3(float(std::sin(angle)), 0.0f, float(std::cos(angle)));
        double expected = std::pow(std::max(double(n.z), 0.0), 128.0);  // n . (0, 0, 1)
        float w = svgfWeight<kPaperSigmaNormal>(paperTerms(), centre, 0.0f, 0.0f, n, 0.0f);
        EXPECT_NEAR(w, expected, 2e-5 * expected + 1e-12) << "angle " << angle;
        weighty += expected > 1e-3 ? 1 : 0;
    }
    EXPECT_GT(weighty, 20);  // the sweep covers the weights that matter
    EXPECT_EQ(svgfWeight<kPaperSigmaNormal>(paperTerms(), centre, 0.0f, 0.0f,
                                            make3(0.0f, 0.0f, 1.0f), 0.0f),
              1.0f);  // parallel normals: exactly 1
    EXPECT_LE(svgfWeight<kPaperSigmaNormal>(paperTerms(), centre, 0.0f, 0.0f,
                                            make3(0.0f, 0.0f, -1.0f), 0.0f),
              0x1p-126f);  // opposite ones: exp2's floor, nothing next to the centre's 1
}

TEST(SvgfKernels, FixedSigmaNormalFormEqualsTheLogarithmForm) {
    // sigma_n = 128 both ways (fixed, the CPU's; 128 log2 n.n', the GPU's) over normals tilted by
    // up to ~25 degrees (weights from 1 down to ~1e-6) and a noisy colour: the same output.
    Harness h(24, 24, 8);
    DeviceBuffer<float> in = h.buffer(4), generic = h.buffer(4), fixedSigma = h.buffer(4),
                        derivatives = h.buffer(3);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> tilt(-0.45f, 0.45f), value(0.2f, 1.0f);
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 24; ++x) {
            auto i = h.layout.index(x, y);
            h.planes(h.normal).store(i, normalize(make3(tilt(rng), tilt(rng), -1.0f)));
            h.planeSet(in).rgb().store(i, make3(value(rng), value(rng), value(rng)));
            h.planeSet(in).at(3, i) = 0.05f;
        }
    for (int stride : {1, 2}) {
        h.device->launch(SvgfAtrousKernel{h.gbuffer(), h.planeSet(derivatives), h.planeSet(in),
                                          h.planeSet(generic), stride, paperTerms()},
                         24, 24);
        h.device->launch(
            SvgfAtrousNormal128Kernel{h.gbuffer(), h.planeSet(derivatives), h.planeSet(in),
                                      h.planeSet(fixedSigma), stride, paperTerms()},
            24, 24);
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 24; ++x) {
                auto i = h.layout.index(x, y);
                for (int c = 0; c < 4; ++c)
                    EXPECT_NEAR(h.planeSet(fixedSigma).at(c, i), h.planeSet(generic).at(c, i),
                                2e-5f * std::abs(h.planeSet(generic).at(c, i)) + 1e-7f)
                        << "stride " << stride << " (" << x << ", " << y << ") plane " << c;
            }
    }
}

TEST(SvgfKernels, LuminanceEdgeStopsScaleWithTheStandardDeviation) {
    // A luminance step of 1 between halves: with variance 1e-4 (stddev 0.01) it is 25 sigma_l
    // wide and nothing crosses; with variance 100 (stddev 10) it is blurred.
    for (float variance : {1e-4f, 100.0f}) {
        Harness h(20, 9, 8);
        DeviceBuffer<float> in = h.buffer(4), out = h.buffer(4), derivatives = h.buffer(3);
        for (int y = 0; y < 9; ++y)
            for (int x = 0; x < 20; ++x) {
                int i = h.layout.index(x, y);
                float value = x < 10 ? 1.0f : 2.0f;
                h.planeSet(in).rgb().store(i, make3(value, value, value));
                h.planeSet(in).at(3, i) = variance;
            }
        h.device->launch(SvgfAtrousKernel{h.gbuffer(), h.planeSet(derivatives), h.planeSet(in),
                                          h.planeSet(out), 1, paperTerms()},
                         20, 9);
        float edge = h.planeSet(out).rgb().load(h.layout.index(9, 4)).x;
        if (variance < 1.0f)
            EXPECT_NEAR(edge, 1.0f, 1e-4f);
        else
            EXPECT_GT(edge, 1.1f);
    }
}

TEST(SvgfKernels, AccumulatedIlluminationVarianceFallsAsOneOverN) {
    // A static wall of noisy constant radiance; alpha 0 makes the accumulation a plain running
    // mean over the history (up to the cap), so the noise variance of the accumulated
    // illumination after n frames is the per-frame variance / n, and the moments' variance
    // estimate is the per-frame variance (uniform noise of half-width 0.5: 1/12).
    const int w = 64, hgt = 64;
    Harness h(w, hgt, 4);
    DeviceBuffer<float> derivatives = h.buffer(3);
    DeviceBuffer<float> illumination[2] = {h.buffer(4), h.buffer(4)};
    DeviceBuffer<float> moments[2] = {h.buffer(2), h.buffer(2)};
    DeviceBuffer<float> length[2] = {h.buffer(1), h.buffer(1)};
    DeviceBuffer<float> filterInput = h.buffer(4);
    DeviceBuffer<float> history = h.buffer(kSvgfHistoryPlanes);
    DeviceBuffer<float> normalPlanes = h.buffer(3);
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            h.validity.data()[h.layout.index(x, y)] = 0;
        }
    ObjectReprojection identity{};
    // The harness's wall pixel (x, y) is world (x, y, 5): this maps it to s = (5x + 2.5,
    // 5y + 2.5, 5, 5), i.e. pixel centre (x + 0.5, y + 0.5) at depth w = 5 (a static camera).
    identity.currentWorldToPreviousScreen =
        Mat4{{{5, 0, 0, 2.5f}, {0, 5, 0, 2.5f}, {0, 0, 1, 0}, {0, 0, 1, 0}}};
    identity.currentWorldToPreviousWorld =
        Mat4{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    identity.valid = 1;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> noise(-0.5f, 0.5f);
    double firstVariance = 0.0;
    for (int n = 1; n <= 16; ++n) {
        int cur = n % 2, prev = 1 - cur;
        for (int y = 0; y < hgt; ++y)
            for (int x = 0; x < w; ++x) {
                float v = 1.0f + noise(rng);
                h.planes(h.a).store(h.layout.index(x, y), make3(v, v, v));
            }
        PreviousGeometry previous{h.ids.data(), h.depth.data(), h.planes(h.normal)};
        h.device->launch(
            SvgfReprojectKernel{h.gbuffer(), previous, &identity, 1, h.planeSet(derivatives),
                                HistoryTest{1, 10.0f, 16.0f}, h.planeSet(illumination[prev]),
                                h.planeSet(moments[prev]), length[prev].data(), h.planeSet(history),
                                h.validity.data(), n > 1 ? 1 : 0},
            w, hgt);
        h.device->launch(
            SvgfAccumulateKernel{h.gbuffer(), h.planes(h.a), h.sumPlanes(), 3, 0.0f,
                                 h.planeSet(history), h.validity.data(),
                                 h.planes(illumination[cur]), h.planeSet(moments[cur]),
                                 length[cur].data(), h.planeSet(filterInput), 0.0f, 0.0f, 32.0f},
            w, hgt);
        double sum = 0, sum2 = 0, varianceEstimate = 0;
        for (int y = 0; y < hgt; ++y)
            for (int x = 0; x < w; ++x) {
                int i = h.layout.index(x, y);
                double v = h.planes(illumination[cur]).load(i).x;
                sum += v;
                sum2 += v * v;
                varianceEstimate += h.planeSet(moments[cur]).at(1, i);  // (mean, variance)
                ASSERT_EQ(length[cur].data()[i], float(n));
            }
        double count = double(w) * hgt;
        double variance = sum2 / count - std::pow(sum / count, 2);
        if (n == 1) firstVariance = variance;
        EXPECT_NEAR(variance * n / firstVariance, 1.0, 0.15) << "after " << n << " frames";
        if (n >= 8) {
            EXPECT_NEAR(varianceEstimate / count, 1.0 / 12.0, 0.012) << n;
        }
    }
}

// ---- through the public API ----

using test::makeFrame;
using test::SceneDescription;

DenoiserSettings svgfSettings() {
    DenoiserSettings s = test::cpuSettings(Method::Svgf);
    return s;
}

TEST(Svgf, ConstantIlluminationStaysConstantAndTextureIsKept) {
    // Radiance = albedo (a checker) * constant illumination 0.8: demodulation gives a constant,
    // every pass keeps it, remodulation restores the checker exactly.
    SceneDescription d;
    d.width = 40;
    d.height = 32;
    auto checker = [](int x, int y) { return ((x / 2 + y / 2) % 2) ? 0.9f : 0.2f; };
    d.colour = [&](int x, int y) {
        float a = checker(x, y);
        return std::array<float, 3>{0.8f * a, 0.8f * a * 0.5f, 0.8f * a * 0.25f};
    };
    Frame frame = makeFrame(d);
    Image albedo(d.width, d.height, 3);
    for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x) {
            albedo.at(x, y, 0) = checker(x, y);
            albedo.at(x, y, 1) = checker(x, y) * 0.5f;
            albedo.at(x, y, 2) = checker(x, y) * 0.25f;
        }
    frame.albedo = albedo;
    Denoiser denoiser(svgfSettings());
    for (int i = 0; i < 4; ++i) {
        Image out = denoiser.processFrame(frame);
        for (std::size_t k = 0; k < out.pixels.size(); ++k)
            ASSERT_NEAR(out.pixels[k], frame.beauty.pixels[k], 1e-5f) << "frame " << i;
    }
}

// Feedback from the last iteration: that iteration writes its slot (the next frame's colour
// history) and a modulate pass writes the output, where otherwise the last iteration writes the
// output itself. Within a frame both give the same result; the history they leave differs.
TEST(Svgf, FeedbackFromTheLastIterationGivesTheSameFrameAndItsOwnHistory) {
    SceneDescription d;
    d.width = 36;
    d.height = 28;
    d.colour = [](int x, int y) {
        float noise = float((x * 73 + y * 151) % 17) / 17.0f;
        return std::array<float, 3>{0.2f + noise, 0.5f * noise, 0.3f};
    };
    Frame frame = makeFrame(d);
    DenoiserSettings fused = svgfSettings(), separate = svgfSettings();
    separate.svgf.feedbackIteration = separate.svgf.iterations - 1;
    Denoiser a(fused), b(separate);
    Image first = a.processFrame(frame), second = b.processFrame(frame);
    ASSERT_FALSE(b.passes().empty());
    ASSERT_GE(a.passes().size(), 2u);
    EXPECT_EQ(b.passes()[b.passes().size() - 2].name, "modulate");
    EXPECT_EQ(a.passes()[a.passes().size() - 2].name, "svgf-atrous4");
    EXPECT_EQ(a.passes().back().name, "energy");
    double differs = 0.0;
    for (std::size_t k = 0; k < first.pixels.size(); ++k)
        ASSERT_NEAR(second.pixels[k], first.pixels[k], 1e-6f * std::fabs(first.pixels[k]) + 1e-9f);
    first = a.processFrame(frame);
    second = b.processFrame(frame);
    for (std::size_t k = 0; k < first.pixels.size(); ++k)
        differs = std::max(differs, double(std::fabs(second.pixels[k] - first.pixels[k])));
    // The histories differ (the feedback came from another iteration): far above rounding.
    EXPECT_GT(differs, 1e-4);
}

TEST(Svgf, WithoutAlbedoAConstantImageIsUnchanged) {
    SceneDescription d;
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 12 ? 0 : 1; };
    d.depth = [](int x, int) { return x < 12 ? 3.0f : 5.0f; };
    d.colour = [](int, int) { return std::array<float, 3>{0.3f, 0.6f, 0.9f}; };
    Frame frame = makeFrame(d);
    Denoiser denoiser(svgfSettings());
    for (int i = 0; i < 3; ++i) {
        Image out = denoiser.processFrame(frame);
        for (std::size_t k = 0; k < out.pixels.size(); ++k)
            ASSERT_NEAR(out.pixels[k], frame.beauty.pixels[k], 1e-5f);
    }
}

// The GPU's kernels read normal and depth interleaved (views.h: NormalDepth4). On the same
// values they compute what the planar kernels do: the same arithmetic, other loads (bit for bit
// with clang; GCC contracts multiply-adds differently in the two instantiations: under 1e-5).
// Random geometry (tilted normals, depths, two objects and background), colours and variances.
TEST(SvgfKernels, InterleavedGuideGivesThePlanarKernelsResults) {
    const int w = 23, h = 17;
    Harness hs(w, h, 8);
    DeviceBuffer<float> guide = hs.buffer(4), in = hs.buffer(4), derivatives = hs.buffer(3),
                        moments = hs.buffer(2), length = hs.buffer(1);
    UnitRandom next{11u};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = hs.layout.index(x, y);
            Float3 n = make3(next() - 0.5f, next() - 0.5f, -1.0f);
            n = n * (1.0f / std::sqrt(dot(n, n)));
            hs.planes(hs.normal).store(i, n);
            hs.depth.data()[i] = 4.0f + next();
            hs.ids.data()[i] = (x == 5 || x == 6) && y == 6 ? -1 : (x + y) % 7 == 0 ? 1 : 0;
            hs.planeSet(in).rgb().store(i, make3(next(), next(), next()));
            hs.planeSet(in).at(3, i) = 0.1f * next();
            hs.planeSet(derivatives).at(0, i) = 0.1f * (next() - 0.5f);
            hs.planeSet(derivatives).at(1, i) = 0.1f * (next() - 0.5f);
            hs.planeSet(moments).at(0, i) = next();
            hs.planeSet(moments).at(1, i) = 0.1f * next();
            length.data()[i] = 1.0f + 4.0f * next();  // short histories and long ones
        }
    // The interleaved copy, border included (zeros there, as in the Denoiser's buffers).
    NormalDepth4 interleaved{guide.data()};
    for (int i = 0; i < hs.layout.planeSize; ++i)
        interleaved.store(i, hs.planes(hs.normal).load(i), hs.depth.data()[i]);
    GBufferView planar = hs.gbuffer(), packed = hs.gbuffer();
    packed.normalDepth = interleaved;
    const SvgfTerms terms{1.0f, 100.0f, 4.0f};  // sigma_n != 128: the log2 form on both
    auto expectSamePlanes = [&](const DeviceBuffer<float>& a, const DeviceBuffer<float>& b,
                                int planes, const char* what) {
        for (int k = 0; k < planes; ++k)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    auto i = hs.layout.index(x, y);
                    ASSERT_NEAR(hs.planeSet(a).at(k, i), hs.planeSet(b).at(k, i),
                                roundingTolerance(hs.planeSet(a).at(k, i)))
                        << what << " plane " << k << " at " << x << ", " << y;
                }
    };
    for (int stride : {1, 2, 4}) {
        DeviceBuffer<float> outPlanar = hs.buffer(4), outPacked = hs.buffer(4);
        hs.device->launch(SvgfAtrousKernel{planar, hs.planeSet(derivatives), hs.planeSet(in),
                                           hs.planeSet(outPlanar), stride, terms},
                          w, h);
        hs.device->launch(
            SvgfAtrousInterleavedKernel{packed, hs.planeSet(derivatives), hs.planeSet(in),
                                        hs.planeSet(outPacked), stride, terms},
            w, h);
        expectSamePlanes(outPlanar, outPacked, 4, "iteration");
        // The GPU's pairs of pixels a stride apart (filterPair, as the CUDA launcher maps them:
        // runInPixelPairs; a top whose partner is outside filtered alone) give
        // filter's result up to the order of the sums (h = 17 leaves lone tops at strides 2, 4).
        DeviceBuffer<float> outPaired = hs.buffer(4);
        SvgfAtrousInterleavedKernel paired{packed,          hs.planeSet(derivatives),
                                           hs.planeSet(in), hs.planeSet(outPaired),
                                           stride,          terms};
        runInPixelPairs(paired, stride, w, h);
        expectSamePlanes(outPacked, outPaired, 4, "iteration in pairs");
        // Background passes through: skipped by a branch in the GPU's form, computed and then
        // replaced in the CPU's (where the background pixel beside it would have mixed in).
        for (int k = 0; k < 4; ++k)
            EXPECT_EQ(hs.planeSet(outPlanar).at(k, hs.layout.index(5, 6)),
                      hs.planeSet(in).at(k, hs.layout.index(5, 6)));
        // Something was filtered: the result differs from the input somewhere.
        EXPECT_NE(hs.planeSet(outPlanar).at(0, hs.layout.index(11, 8)),
                  hs.planeSet(in).at(0, hs.layout.index(11, 8)));
    }
    DeviceBuffer<float> albedo = hs.buffer(3), unused = hs.buffer(4);
    hs.fillRandom(hs.planes(albedo), next, 0.5f);
    std::vector<float> rgbPlanar(3 * w * h), rgbPacked(3 * w * h, -1.0f);
    hs.device->launch(SvgfAtrousModulatedKernel{planar, hs.planeSet(derivatives), hs.planeSet(in),
                                                hs.planeSet(unused), 2, terms, hs.planes(albedo),
                                                rgbPlanar.data()},
                      w, h);
    hs.device->launch(
        SvgfAtrousInterleavedModulatedKernel{packed, hs.planeSet(derivatives), hs.planeSet(in),
                                             hs.planeSet(unused), 2, terms, hs.planes(albedo),
                                             rgbPacked.data()},
        w, h);
    for (std::size_t k = 0; k < rgbPlanar.size(); ++k)
        ASSERT_NEAR(rgbPlanar[k], rgbPacked[k], roundingTolerance(rgbPlanar[k])) << k;
    // The short-history variance, revised in place from the same start.
    DeviceBuffer<float> varPlanar = hs.buffer(4), varPacked = hs.buffer(4);
    for (auto* b : {&varPlanar, &varPacked})
        for (int i = 0; i < 4 * hs.layout.planeSize; ++i) b->data()[i] = in.data()[i];
    hs.device->launch(SvgfVarianceKernel{planar, hs.planeSet(derivatives), hs.planeSet(in).rgb(),
                                         hs.planeSet(moments), length.data(),
                                         hs.planeSet(varPlanar), terms, 4.0f},
                      w, h);
    hs.device->launch(
        SvgfVarianceInterleavedKernel{packed, hs.planeSet(derivatives), hs.planeSet(in).rgb(),
                                      hs.planeSet(moments), length.data(), hs.planeSet(varPacked),
                                      terms, 4.0f},
        w, h);
    expectSamePlanes(varPlanar, varPacked, 4, "variance");
    EXPECT_NE(hs.planeSet(varPlanar).at(3, hs.layout.index(11, 8)),
              hs.planeSet(in).at(3, hs.layout.index(11, 8)));
    // Faded (the detail method's form): the spatial estimate's share falls from 1 at a length
    // of 1 to 0 at 5, mixed with the kept values. Known answer from the unfaded estimate of
    // every pixel (shortHistory 5, all lengths below it; its variance is scaled by 5 / h
    // rather than 1 / h).
    DeviceBuffer<float> fullPlanar = hs.buffer(4), fadedPlanar = hs.buffer(4),
                        fadedPacked = hs.buffer(4);
    for (auto* b : {&fullPlanar, &fadedPlanar, &fadedPacked})
        for (int i = 0; i < 4 * hs.layout.planeSize; ++i) b->data()[i] = in.data()[i];
    hs.device->launch(SvgfVarianceKernel{planar, hs.planeSet(derivatives), hs.planeSet(in).rgb(),
                                         hs.planeSet(moments), length.data(),
                                         hs.planeSet(fullPlanar), terms, 5.0f},
                      w, h);
    hs.device->launch(SvgfVarianceKernel{planar, hs.planeSet(derivatives), hs.planeSet(in).rgb(),
                                         hs.planeSet(moments), length.data(),
                                         hs.planeSet(fadedPlanar), terms, 1.0f, 5.0f},
                      w, h);
    hs.device->launch(
        SvgfVarianceInterleavedKernel{packed, hs.planeSet(derivatives), hs.planeSet(in).rgb(),
                                      hs.planeSet(moments), length.data(), hs.planeSet(fadedPacked),
                                      terms, 1.0f, 5.0f},
        w, h);
    expectSamePlanes(fadedPlanar, fadedPacked, 4, "faded variance");
    int mixed = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = hs.layout.index(x, y);
            if (hs.ids.data()[i] < 0) continue;
            const float share = (5.0f - length.data()[i]) / 4.0f;
            mixed += share > 0.1f && share < 0.9f;
            for (int k = 0; k < 4; ++k) {
                const float kept = hs.planeSet(in).at(k, i);
                const float spatial =
                    hs.planeSet(fullPlanar).at(k, i) * (k == 3 ? 1.0f / 5.0f : 1.0f);
                const float want = kept + (spatial - kept) * share;
                ASSERT_NEAR(
                    hs.planeSet(fadedPlanar).at(k, i), want,
                    1e-5f * (std::fabs(want) + std::fabs(kept) + std::fabs(spatial)) + 1e-7f)
                    << "plane " << k << " at " << x << ", " << y << ", length " << length.data()[i];
            }
        }
    EXPECT_GT(mixed, w * h / 2);
    // The geometry derivatives (depth slopes, normal change).
    DeviceBuffer<float> slopesPlanar = hs.buffer(3), slopesPacked = hs.buffer(3);
    hs.device->launch(GeometryDerivativesKernel{planar, hs.planeSet(slopesPlanar)}, w, h);
    hs.device->launch(GeometryDerivativesInterleavedKernel{packed, hs.planeSet(slopesPacked)}, w,
                      h);
    expectSamePlanes(slopesPlanar, slopesPacked, 3, "derivatives");
    EXPECT_NE(hs.planeSet(slopesPlanar).at(2, hs.layout.index(11, 8)), 0.0f);
}

// The interleaving ingest (the GPU's) writes into the interleaved copy the normal and depth the
// planar one writes into the planes, non-finite geometry (made background, 0) included, and
// leaves the planes alone; its other outputs are the planar one's.
TEST(SvgfKernels, InterleavingIngestWritesThePlanarIngestsNormalAndDepth) {
    const int w = 9, h = 7, n = w * h;
    Harness hs(w, h, 4);
    std::vector<float> beauty(3 * n), normal(3 * n), position(3 * n), depth(n);
    std::vector<std::int32_t> ids(n, 0);
    UnitRandom next{5u};
    for (auto* v : {&beauty, &normal, &position, &depth})
        for (float& f : *v) f = next();
    normal[3 * 10 + 1] = std::numeric_limits<float>::quiet_NaN();
    depth[20] = std::numeric_limits<float>::infinity();
    ids[30] = -1;
    struct Out {
        DeviceBuffer<float> noisy, albedo, normal, position, depth, guide;
        DeviceBuffer<std::int32_t> ids, keys;
        std::vector<std::uint8_t> flags;
    };
    auto outputs = [&] {
        Out o{hs.buffer(3),
              hs.buffer(3),
              hs.buffer(3),
              hs.buffer(3),
              hs.buffer(1),
              hs.buffer(4),
              DeviceBuffer<std::int32_t>(*hs.device, std::size_t(hs.layout.planeSize)),
              DeviceBuffer<std::int32_t>(*hs.device, std::size_t(hs.layout.planeSize)),
              std::vector<std::uint8_t>(n)};
        for (int i = 0; i < hs.layout.planeSize; ++i) {
            hs.planes(o.normal).store(i, make3(-7.0f, -7.0f, -7.0f));
            o.depth.data()[i] = -7.0f;
        }
        return o;
    };
    auto run = [&]<class Kernel>(Out& o) {
        hs.device->launch(Kernel{hs.layout,
                                 beauty.data(),
                                 normal.data(),
                                 position.data(),
                                 depth.data(),
                                 ids.data(),
                                 1,
                                 nullptr,
                                 1e-3f,
                                 hs.planes(o.noisy),
                                 hs.planes(o.albedo),
                                 hs.planes(o.normal),
                                 hs.planes(o.position),
                                 o.depth.data(),
                                 o.ids.data(),
                                 o.flags.data(),
                                 {o.guide.data()},
                                 o.keys.data()},
                          w, h);
    };
    Out planar = outputs(), packed = outputs();
    run.template operator()<IngestKernel>(planar);
    run.template operator()<IngestInterleavedKernel>(packed);
    EXPECT_EQ(planar.flags, packed.flags);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = hs.layout.index(x, y);
            Float3 nPacked;
            float zPacked;
            NormalDepth4{packed.guide.data()}.load(i, nPacked, zPacked);
            Float3 nPlanar = hs.planes(planar.normal).load(i);
            EXPECT_EQ(nPacked.x, nPlanar.x);
            EXPECT_EQ(nPacked.y, nPlanar.y);
            EXPECT_EQ(nPacked.z, nPlanar.z);
            EXPECT_EQ(zPacked, planar.depth.data()[i]);
            // A NaN normal (pixel 10) leaves the pixel an object's, without a normal.
            EXPECT_EQ(zPacked, y * w + x == 20 ? 0.0f : depth[y * w + x]);
            EXPECT_EQ(hs.planes(packed.normal).load(i).y, -7.0f);  // planes untouched
            EXPECT_EQ(packed.depth.data()[i], -7.0f);
            EXPECT_EQ(packed.ids.data()[i], planar.ids.data()[i]);
            EXPECT_EQ(packed.keys.data()[i], planar.keys.data()[i]);
            // The NaN normal's pixel keeps its object, keyed as one without a normal.
            EXPECT_EQ(planar.keys.data()[i], y * w + x == 10 ? kWithoutNormalKey
                                             : y * w + x == 20 || y * w + x == 30 ? -1
                                                                                  : 0);
            for (int k = 0; k < 3; ++k) {
                EXPECT_EQ(hs.planeSet(packed.noisy).at(k, i), hs.planeSet(planar.noisy).at(k, i));
                EXPECT_EQ(hs.planeSet(packed.position).at(k, i),
                          hs.planeSet(planar.position).at(k, i));
            }
        }
}

// The GPU's one-pass temporal stage (SvgfTemporalKernel, and its form reading the interleaved
// guide) against the CPU's three passes (reprojection, 3x3 search, accumulation): the same
// outputs. The history lies (0.3, 0.2) pixels away; a patch that was another object in the
// previous frame sends its pixels to the search (some find history there, some none), a strip
// that was further away fails the depth test, and the anti-lag clamp is on.
TEST(SvgfKernels, OnePassTemporalStageGivesTheThreePassesResults) {
    const int w = 20, hgt = 16;
    Harness h(w, hgt, 8);
    UnitRandom next{21u};
    DeviceBuffer<float> feedback = h.buffer(4), previousMoments = h.buffer(2),
                        previousLength = h.buffer(1), derivatives = h.buffer(3),
                        radiance = h.buffer(3), history = h.buffer(kSvgfHistoryPlanes);
    DeviceBuffer<std::int32_t> previousIds(*h.device, std::size_t(h.layout.planeSize));
    for (int i = 0; i < h.layout.planeSize; ++i) previousIds.data()[i] = h.ids.data()[i];
    for (int y = 6; y <= 9; ++y)
        for (int x = 8; x <= 11; ++x) previousIds.data()[h.layout.index(x, y)] = 1;
    h.ids.data()[h.layout.index(3, 3)] = 1;
    h.ids.data()[h.layout.index(15, 12)] = -1;
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            h.planeSet(feedback).rgb().store(i, make3(next(), next(), next()));
            h.planeSet(previousMoments).at(0, i) = next();
            h.planeSet(previousMoments).at(1, i) = 0.1f * next();
            previousLength.data()[i] = 1.0f + 8.0f * next();
            h.planes(radiance).store(i, make3(2.0f * next(), next(), next()));
        }
    ObjectReprojection shift{};
    // Screen = (x + 0.8, y + 0.7) at w = z = 5, the wall's depth (the depth test compares w).
    shift.currentWorldToPreviousScreen = {
        {{5, 0, 0, 4.0f}, {0, 5, 0, 3.5f}, {0, 0, 1, 0}, {0, 0, 1, 0}}};
    shift.currentWorldToPreviousWorld = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    shift.valid = 1;
    std::vector<ObjectReprojection> objects = {shift, shift};
    // A strip that was further away in the previous frame: the depth test rejects it.
    DeviceBuffer<float> previousDepth = h.buffer(1);
    for (int i = 0; i < h.layout.planeSize; ++i) previousDepth.data()[i] = h.depth.data()[i];
    for (int y = 0; y < hgt; ++y)
        for (int x = 12; x <= 18; ++x) previousDepth.data()[h.layout.index(x, y)] = 7.0f;
    const PreviousGeometry previous{previousIds.data(), previousDepth.data(), h.planes(h.normal)};
    const HistoryTest geometryTests{1, 10.0f, 16.0f};
    h.device->launch(ColorRowSumsKernel{h.gbuffer(), h.planes(radiance), h.sumPlanes(), 3}, w, hgt);
    struct Outputs {
        DeviceBuffer<float> illumination, moments, length, filterInput;
        DeviceBuffer<std::uint8_t> validity;
    };
    auto outputs = [&] {
        Outputs o{h.buffer(3), h.buffer(2), h.buffer(1), h.buffer(4),
                  DeviceBuffer<std::uint8_t>(*h.device, std::size_t(h.layout.planeSize))};
        h.device->fill(o.validity.data(), kReprojectionNoHistory, o.validity.bytes());
        return o;
    };
    auto reproject = [&]<class Kernel>(Outputs& o) {
        return Kernel{h.gbuffer(),
                      previous,
                      objects.data(),
                      2,
                      h.planeSet(derivatives),
                      geometryTests,
                      h.planeSet(feedback),
                      h.planeSet(previousMoments),
                      previousLength.data(),
                      h.planeSet(history),
                      o.validity.data(),
                      1};
    };
    auto accumulate = [&](Outputs& o) {
        return SvgfAccumulateKernel{h.gbuffer(),
                                    h.planes(radiance),
                                    h.sumPlanes(),
                                    3,
                                    1.0f,
                                    h.planeSet(history),
                                    o.validity.data(),
                                    h.planes(o.illumination),
                                    h.planeSet(o.moments),
                                    o.length.data(),
                                    h.planeSet(o.filterInput),
                                    0.2f,
                                    0.2f,
                                    32.0f};
    };
    Outputs three = outputs(), one = outputs();
    h.device->launch(reproject.template operator()<SvgfReprojectKernel>(three), w, hgt);
    h.device->launch(reproject.template operator()<SvgfReprojectSearchKernel>(three), w, hgt);
    h.device->launch(accumulate(three), w, hgt);
    h.device->launch(SvgfTemporalKernel{reproject.template operator()<SvgfReprojectKernel>(one),
                                        accumulate(one)},
                     w, hgt);
    // The GPU's form: normals and depths from the interleaved copies (the same geometry serves
    // as this frame's and the last, as the planes do above).
    DeviceBuffer<float> guide = h.buffer(4), previousGuide = h.buffer(4);
    for (int i = 0; i < h.layout.planeSize; ++i) {
        NormalDepth4{guide.data()}.store(i, h.planes(h.normal).load(i), h.depth.data()[i]);
        NormalDepth4{previousGuide.data()}.store(i, h.planes(h.normal).load(i),
                                                 previousDepth.data()[i]);
    }
    Outputs packed = outputs();
    SvgfReprojectKernel packedReproject =
        reproject.template operator()<SvgfReprojectKernel>(packed);
    packedReproject.g.normalDepth = {guide.data()};
    packedReproject.previous.normalDepth = {previousGuide.data()};
    SvgfAccumulateKernel packedAccumulate = accumulate(packed);
    packedAccumulate.g.normalDepth = {guide.data()};
    h.device->launch(SvgfTemporalInterleavedKernel{packedReproject, packedAccumulate}, w, hgt);
    int searched = 0, found = 0;
    // Within rounding: the CPU vectorises the passes but not the one-pass kernel (its search
    // is a branch), and the compiler may contract other multiply-adds in each.
    auto expectClose = [](float a, float b, const char* what, int x, int y) {
        ASSERT_NEAR(a, b, 2e-6f * std::fabs(a) + 1e-7f) << what << " at " << x << ", " << y;
    };
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            for (Outputs* o : {&one, &packed}) {
                ASSERT_EQ(three.validity.data()[i], o->validity.data()[i]) << x << ", " << y;
                for (int k = 0; k < 3; ++k)
                    expectClose(h.planeSet(three.illumination).at(k, i),
                                h.planeSet(o->illumination).at(k, i), "illumination", x, y);
                for (int k = 0; k < 2; ++k)
                    expectClose(h.planeSet(three.moments).at(k, i), h.planeSet(o->moments).at(k, i),
                                "moments", x, y);
                expectClose(three.length.data()[i], o->length.data()[i], "length", x, y);
                for (int k = 0; k < 4; ++k)
                    expectClose(h.planeSet(three.filterInput).at(k, i),
                                h.planeSet(o->filterInput).at(k, i), "filter input", x, y);
            }
            bool inPatch = x >= 7 && x <= 11 && y >= 5 && y <= 9;
            searched += inPatch ? 1 : 0;
            found += inPatch && one.validity.data()[i] == kReprojectionValid ? 1 : 0;
        }
    // The patch's pixels went through the search: some found history, some none.
    EXPECT_GT(found, 0);
    EXPECT_LT(found, searched);
    // The depth test rejected the strip (x 12-18 in the previous frame), the search too inside.
    EXPECT_NE(one.validity.data()[h.layout.index(15, 3)], kReprojectionValid);
    EXPECT_EQ(one.validity.data()[h.layout.index(9, 3)], kReprojectionValid);
}

TEST(Svgf, HistoryLengthGrowsAndResetsWhereAnObjectUncoversTheWall) {
    // Object 0 (x in [8, 16)) slides 3 pixels right per frame in front of a wall (object 1).
    const float z = 4.0f;
    auto scene = [&](int frame) {
        SceneDescription d;
        d.objectCount = 2;
        int left = 8 + 3 * frame;
        d.id = [left](int x, int) { return x >= left && x < left + 8 ? 0 : 1; };
        d.depth = [left, z](int x, int) { return x >= left && x < left + 8 ? z - 1.0f : z; };
        Frame f = makeFrame(d);
        f.objectToWorld[0] =
            test::translation(test::worldShiftForPixels(3.0f * frame, z - 1.0f), 0, 0);
        return f;
    };
    Denoiser denoiser(svgfSettings());
    const int frames = 4;
    for (int i = 0; i < frames; ++i) denoiser.processFrame(scene(i));
    Image length = denoiser.debugImage(DebugView::HistoryLength);
    const float cap = 32.0f;
    // Static wall far from the object: every frame accumulated.
    EXPECT_NEAR(length.at(30, 10, 0), frames / cap, 1e-6f);
    // Uncovered by the object's last move (wall pixels left-3..left-1): their own history was
    // the object. Two of them have no wall pixel in their 3x3 either: history starts again;
    // the third finds the wall next to it through the 3x3 search and continues.
    int left = 8 + 3 * (frames - 1);
    for (int x = left - 2; x < left; ++x) EXPECT_NEAR(length.at(x, 10, 0), 1.0f / cap, 1e-6f) << x;
    EXPECT_NEAR(length.at(left - 3, 10, 0), 2.0f / cap, 1e-6f);
    // The object itself carries its history along.
    EXPECT_NEAR(length.at(left + 4, 10, 0), frames / cap, 1e-6f);
    Image reprojection = denoiser.debugImage(DebugView::Reprojection);
    EXPECT_EQ(reprojection.at(left - 1, 10, 0), 1.0f);  // yellow: rejected (other object)
    EXPECT_EQ(reprojection.at(30, 10, 1), 1.0f);        // green: valid
}

TEST(Svgf, NoBleedingAcrossObjectBoundaries) {
    SceneDescription d;
    d.width = 32;
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 16 ? 0 : 1; };
    d.colour = [](int x, int) {
        return x < 16 ? std::array<float, 3>{1.0f, 0.2f, 0.2f}
                      : std::array<float, 3>{0.2f, 0.2f, 1.0f};
    };
    Frame frame = makeFrame(d);
    test::addNoise(frame, 0.05f, 11);
    Denoiser denoiser(svgfSettings());
    Image out;
    for (int i = 0; i < 3; ++i) out = denoiser.processFrame(frame);
    for (int y = 0; y < d.height; ++y) {
        EXPECT_LT(out.at(15, y, 2), 0.3f);  // red side: no blue from the right
        EXPECT_LT(out.at(16, y, 0), 0.3f);  // blue side: no red from the left
    }
}

TEST(Svgf, ReducesNoiseOnAStaticNoisyWall) {
    SceneDescription d;
    d.width = 48;
    d.height = 48;
    d.colour = [](int, int) { return std::array<float, 3>{0.5f, 0.5f, 0.5f}; };
    Denoiser denoiser(svgfSettings());
    Image out;
    double inputError = 0, outputError = 0;
    for (int i = 0; i < 8; ++i) {
        Frame frame = makeFrame(d);
        test::addNoise(frame, 0.4f, unsigned(100 + i));
        out = denoiser.processFrame(frame);
        if (i == 7)
            for (std::size_t k = 0; k < out.pixels.size(); ++k) {
                inputError += std::pow(frame.beauty.pixels[k] - 0.5, 2);
                outputError += std::pow(out.pixels[k] - 0.5, 2);
            }
    }
    EXPECT_LT(outputError, inputError / 50.0);
}

}  // namespace
}  // namespace rtd
