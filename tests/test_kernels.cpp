// Kernel-level known answers: the fast math against the standard library, the A-Trous tap
// positions per level, the history clamp and blend, firefly removal. Kernels run on the CPU
// device over padded buffers built here.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "devices/cpu/parallel_for.h"
#include "devices/cpu/where_keyed.h"
#include "kernel_harness.h"

namespace rtd {
namespace {

TEST(FastMath, ExpMatchesStdExpOverTheFilterRange) {
    for (float x = -87.0f; x <= 0.0f; x += 0.0137f) {
        float expected = std::exp(x);
        EXPECT_NEAR(expNegative(x), expected, (x > -10.0f ? 2e-6f : 1e-5f) * expected + 1e-37f)
            << "x = " << x;
    }
    EXPECT_EQ(expNegative(0.0f), 1.0f);
    EXPECT_FALSE(std::isnan(expNegative(-1e4f)));  // no NaN for huge exponents
    EXPECT_LT(expNegative(-1e4f), 1e-37f);
}

TEST(FastMath, Exp2AndLog2MatchTheStandardLibrary) {
    for (float t = -120.0f; t <= 0.0f; t += 0.0173f) {
        float expected = std::exp2(t);
        EXPECT_NEAR(exp2Negative(t), expected, 2e-7f * expected) << "t = " << t;
    }
    EXPECT_EQ(exp2Negative(0.0f), 1.0f);  // the centre tap's weight
    EXPECT_EQ(exp2Negative(-3.0f), 0.125f);
    for (float x = 1e-30f; x < 1e30f; x *= 1.37f)
        EXPECT_NEAR(log2Positive(x), std::log2(x), 4e-7f * std::max(1.0f, std::fabs(std::log2(x))))
            << "x = " << x;
    EXPECT_EQ(log2Positive(1.0f), 0.0f);
}

TEST(FastMath, AcosMatchesStdAcos) {
    for (float x = -1.0f; x <= 1.0f; x += 0.001f)
        EXPECT_NEAR(acosFast(x), std::acos(x), 1.5e-6f) << "x = " << x;
    EXPECT_NEAR(acosFast(1.0000001f), 0.0f, 1e-6f);  // dot products slightly above 1
    EXPECT_NEAR(acosFast(-1.0000001f), 3.14159265f, 1e-6f);
}

// The narrow normal term's acos(c)^2 = (1 - c) q(c): close to the standard library's where
// the term is small enough to matter, and never smaller than at c = 0.6 further out (a weight of
// e^-30 or less for any sigma_normal with OppositeNormalsVanish), opposite normals included.
TEST(FastMath, NarrowNormalTermMatchesAcosSquaredNearOneAndStaysLargeBelow) {
    for (float c = 0.6f; c < 1.0f; c += 1e-4f) {
        double expected = std::acos(double(c)) * std::acos(double(c));
        EXPECT_NEAR(normalAngleSquared<true>(c), expected, 2e-6 * expected) << "c = " << c;
    }
    EXPECT_EQ(normalAngleSquared<true>(1.0f), 0.0f);
    EXPECT_EQ(normalAngleSquared<true>(1.0001f), 0.0f);  // normals a little longer than 1
    const float atBoundary = normalAngleSquared<true>(0.6f);
    EXPECT_GE(atBoundary, 0.8598f);  // acos(0.6)^2 = 0.85988
    EdgeStoppingTerms widestNarrow{1.0f, 88.0f / 2.4674011f, 1.0f};
    ASSERT_TRUE(oppositeNormalsVanish(widestNarrow));
    EXPECT_LT(std::exp(-widestNarrow.normalScale * atBoundary), 1e-13);
    float previous = atBoundary;
    for (float c = 0.6f; c >= -1.0f; c -= 0.01f) {
        float v = normalAngleSquared<true>(c);
        EXPECT_GE(v, previous) << "c = " << c;
        previous = v;
    }
}

// SVGF's fixed-sigma normal factor: -log2(c) = (1 - c) L(c) close to the standard library's
// on [0.8, 1], and never smaller than at 0.8 further out (a factor of 2^-41 or less for
// sigma_n = 128), opposite normals included.
TEST(FastMath, NegLog2NearOneMatchesTheLogarithmAndStaysLargeBelow) {
    for (float c = 0.8f; c < 1.0f; c += 1e-4f) {
        double expected = -std::log2(double(c));
        EXPECT_NEAR((1.0f - c) * negLog2FactorNearOne(c), expected, 5e-7 * expected) << "c = " << c;
    }
    EXPECT_NEAR(negLog2FactorNearOne(1.0f), 1.0 / std::log(2.0), 3e-7);
    float previous = (1.0f - 0.8f) * negLog2FactorNearOne(0.8f);
    EXPECT_GE(previous, kNegLog2NearOneFloor);
    for (float c = 0.8f; c >= -1.0f; c -= 0.01f) {
        float v = (1.0f - c) * negLog2FactorNearOne(c);
        EXPECT_GE(v, previous) << "c = " << c;
        previous = v;
    }
}

TEST(FastMath, MatrixInverseRoundTrips) {
    Mat4 a{{{2, 0, 0, 1}, {0, 3, 0, 2}, {0, 0, 4, 3}, {0, 0, 0, 1}}};
    Mat4 inverse;
    ASSERT_TRUE(invert(a, inverse));
    Mat4 product = multiply(a, inverse);
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(product.m[i][j], i == j ? 1.0f : 0.0f, 1e-6f);
    Mat4 singular{};
    EXPECT_FALSE(invert(singular, inverse));
}

EdgeStoppingTerms wideOpenTerms() {
    // Colour sigma so large that the colour term vanishes: weights are the B3 taps alone.
    return {1e-12f, 1.0f / (2.0f * 0.1f * 0.1f), 1.0f / (2.0f * 0.1f * 0.1f)};
}

TEST(Atrous, TapsLieAtMultiplesOfTheStrideWithB3Weights) {
    const float b3[5] = {1 / 16.0f, 1 / 4.0f, 3 / 8.0f, 1 / 4.0f, 1 / 16.0f};
    for (int stride : {1, 2, 4, 8, 16}) {
        const int size = 4 * stride + 9, centre = size / 2;
        Harness h(size, size, 2 * stride);
        h.setAll(h.a, make3(0, 0, 0));
        h.planes(h.a).store(h.layout.index(centre, centre), make3(1, 1, 1));  // impulse
        h.device->launch(
            AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, wideOpenTerms()}, size,
            size);
        // Away from the border every pixel has all 25 taps, so the weights sum to 1 and the
        // output at offset (dx, dy) from the impulse is b3[dx] * b3[dy] on the stride lattice.
        for (int y = 2 * stride; y < size - 2 * stride; ++y)
            for (int x = 2 * stride; x < size - 2 * stride; ++x) {
                int dx = centre - x, dy = centre - y;
                float expected = 0.0f;
                if (dx % stride == 0 && dy % stride == 0 && std::abs(dx) <= 2 * stride &&
                    std::abs(dy) <= 2 * stride)
                    expected = b3[dx / stride + 2] * b3[dy / stride + 2];
                float got = h.planes(h.b).load(h.layout.index(x, y)).x;
                EXPECT_NEAR(got, expected, 1e-6f)
                    << "stride " << stride << " at offset (" << dx << ", " << dy << ")";
            }
    }
}

TEST(Atrous, ConstantImageIsUnchangedAtTheBorderToo) {
    Harness h(20, 12, 8);
    h.setAll(h.a, make3(0.3f, 0.6f, 0.9f));
    h.device->launch(AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), 4,
                                  EdgeStoppingTerms{1.39f, 50.0f, 50.0f}},
                     20, 12);
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 20; ++x) {
            Float3 v = h.planes(h.b).load(h.layout.index(x, y));
            EXPECT_NEAR(v.x, 0.3f, 1e-6f);
            EXPECT_NEAR(v.y, 0.6f, 1e-6f);
            EXPECT_NEAR(v.z, 0.9f, 1e-6f);
        }
}

// The atrous method's last level: the caller's interleaved RGB holds the plain kernel's result
// times the albedo factor (a background pixel, passed through, too), and its own planes are not
// written (nothing reads them).
TEST(Atrous, ModulatedLevelWritesTheResultTimesTheAlbedoInterleavedInsteadOfItsPlanes) {
    const int w = 14, hgt = 10;
    Harness h(w, hgt, 8);
    DeviceBuffer<float> albedo = h.buffer(3);
    std::vector<float> rgb(3 * w * hgt, -1.0f);
    UnitRandom next{5u};
    h.fillRandom(h.planes(h.a), next);
    h.fillRandom(h.planes(albedo), next, 0.5f);
    h.ids.data()[h.layout.index(6, 3)] = -1;
    const Float3 untouched = make3(-7.0f, -7.0f, -7.0f);
    h.setAll(h.c, untouched);
    const EdgeStoppingTerms terms{1.39f, 50.0f, 50.0f};
    h.device->launch(AtrousNarrowNormalKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), 2, terms},
                     w, hgt);
    h.device->launch(AtrousNarrowNormalModulatedKernel{h.gbuffer(), h.planes(h.a), h.planes(h.c), 2,
                                                       terms, h.planes(albedo), rgb.data()},
                     w, hgt);
    h.expectModulatedOutput(h.planes(h.b), h.planes(albedo), rgb, 2e-6f);
    h.expectAll(h.c, untouched);
    auto background = h.layout.index(6, 3);  // passes through
    EXPECT_FLOAT_EQ(rgb[3 * (3 * w + 6) + 1],
                    h.planes(h.a).load(background).y * h.planes(albedo).load(background).y);
}

TEST(Atrous, SquareRootFreeNormalTermGivesTheSameResultWhereOppositeNormalsVanish) {
    // sigma_normal 0.1 (the assignment's): normals in every direction, including opposite ones,
    // and a noisy colour; the square-root-free kernel equals the general one.
    EdgeStoppingTerms terms{1.0f / (2.0f * 0.6f * 0.6f), 1.0f / (2.0f * 0.1f * 0.1f),
                            1.0f / (2.0f * 0.1f * 0.1f)};
    ASSERT_TRUE(oppositeNormalsVanish(terms));
    EdgeStoppingTerms wide = terms;
    wide.normalScale = 1.0f / (2.0f * 0.5f * 0.5f);
    EXPECT_FALSE(oppositeNormalsVanish(wide));
    Harness h(24, 24, 8);
    UnitRandom next{7u};
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 24; ++x) {
            auto i = h.layout.index(x, y);
            // Mostly facing the camera, every fourth pixel anywhere (opposite ones included).
            Float3 n = (x + y) % 4 == 0
                           ? make3(next() - 0.5f, next() - 0.5f, next() - 0.5f)
                           : make3(0.3f * (next() - 0.5f), 0.3f * (next() - 0.5f), -1.0f);
            h.planes(h.normal).store(i, normalize(n));
            h.planes(h.a).store(i, make3(next(), next(), next()));
        }
    for (int stride : {1, 2}) {
        h.device->launch(AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, terms}, 24,
                         24);
        h.device->launch(
            AtrousNarrowNormalKernel{h.gbuffer(), h.planes(h.a), h.planes(h.c), stride, terms}, 24,
            24);
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 24; ++x) {
                Float3 general = h.planes(h.b).load(h.layout.index(x, y));
                Float3 fast = h.planes(h.c).load(h.layout.index(x, y));
                EXPECT_NEAR(fast.x, general.x, 1e-5f * general.x + 1e-7f) << x << ", " << y;
                EXPECT_NEAR(fast.y, general.y, 1e-5f * general.y + 1e-7f) << x << ", " << y;
                EXPECT_NEAR(fast.z, general.z, 1e-5f * general.z + 1e-7f) << x << ", " << y;
            }
    }
}

// The GPU's pairs of pixels a stride apart (Atrous::filterPair, as the CUDA launcher maps them:
// runInPixelPairs) give
// filter's result up to rounding (other pairs share the divisions). Random normals, positions,
// colours, two objects and background (a pair with both, one with neither object pixel).
TEST(Atrous, PixelPairsGiveTheSingleFilterResult) {
    const int w = 21, hgt = 17;
    Harness h(w, hgt, 8);
    UnitRandom next{13u};
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            h.planes(h.normal).store(
                i, normalize(make3(0.4f * (next() - 0.5f), 0.4f * (next() - 0.5f), -1.0f)));
            h.planes(h.position).store(i, make3(float(x), float(y), 5.0f + next()));
            h.planes(h.a).store(i, make3(next(), next(), next()));
            h.ids.data()[i] = (x + 2 * y) % 9 == 0 ? 1 : 0;
        }
    h.ids.data()[h.layout.index(4, 2)] = -1;  // its pair at stride 2: (4, 0), an object pixel
    h.ids.data()[h.layout.index(7, 8)] = h.ids.data()[h.layout.index(7, 9)] = -1;  // stride 1
    const EdgeStoppingTerms terms{1.0f / (2.0f * 0.6f * 0.6f), 1.0f / (2.0f * 0.1f * 0.1f),
                                  1.0f / (2.0f * 0.1f * 0.1f)};
    for (int stride : {1, 2, 4}) {
        AtrousNarrowNormalKernel single{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, terms};
        AtrousNarrowNormalKernel paired{h.gbuffer(), h.planes(h.a), h.planes(h.c), stride, terms};
        h.device->launch(single, w, hgt);
        runInPixelPairs(paired, stride, w, hgt);
        for (int y = 0; y < hgt; ++y)
            for (int x = 0; x < w; ++x)
                EXPECT_TRUE(nearUpToRounding(h.planes(h.c).load(h.layout.index(x, y)),
                                             h.planes(h.b).load(h.layout.index(x, y))))
                    << x << ", " << y << " stride " << stride;
        // Filtered (not passed through): the result differs from the input.
        EXPECT_NE(h.planes(h.c).load(h.layout.index(10, 6)).x,
                  h.planes(h.a).load(h.layout.index(10, 6)).x);
    }
    // The modulated last level (the general normal term).
    DeviceBuffer<float> albedo = h.buffer(3);
    h.fillRandom(h.planes(albedo), next, 0.5f);
    std::vector<float> rgbSingle(3 * w * hgt), rgbPaired(3 * w * hgt, -1.0f);
    h.device->launch(AtrousModulatedKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), 2, terms,
                                           h.planes(albedo), rgbSingle.data()},
                     w, hgt);
    runInPixelPairs(AtrousModulatedKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), 2, terms,
                                          h.planes(albedo), rgbPaired.data()},
                    2, w, hgt);
    for (std::size_t k = 0; k < rgbSingle.size(); ++k)
        ASSERT_NEAR(rgbPaired[k], rgbSingle[k], roundingTolerance(rgbSingle[k])) << k;
}

// The CPU's form that evaluates each pair of pixels once for both (filterSharingPairs, its
// weights carried between rows in each core's ring) gives filter's result up to rounding: at
// every stride, in plain and interleaved row order, on 1 and 2 cores (the rows above each
// core's first rows run for their weights; above the image they weigh nothing). Random normals,
// positions, colours, two objects and background; the general and the narrow normal term and
// the modulated last level.
TEST(Atrous, PairsSharedBetweenRowsGiveThePerPixelResult) {
    const int w = 37, hgt = 45;
    Harness h(w, hgt, 32);
    UnitRandom next{29u};
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            h.planes(h.normal).store(
                i, normalize(make3(0.6f * (next() - 0.5f), 0.6f * (next() - 0.5f), -1.0f)));
            h.planes(h.position).store(i, make3(float(x), float(y), 5.0f + next()));
            h.planes(h.a).store(i, make3(next(), next(), next()));
            h.ids.data()[i] = (x + 2 * y) % 9 == 0 ? 1 : (x * y) % 13 == 5 ? -1 : 0;
        }
    const EdgeStoppingTerms narrow{1.0f / (2.0f * 0.6f * 0.6f), 1.0f / (2.0f * 0.1f * 0.1f),
                                   1.0f / (2.0f * 0.1f * 0.1f)};
    const EdgeStoppingTerms wide{1.0f / (2.0f * 0.6f * 0.6f), 1.0f / (2.0f * 0.5f * 0.5f),
                                 1.0f / (2.0f * 0.3f * 0.3f)};
    CpuScratch scratch(*h.device);
    const int threadsBefore = omp_get_max_threads();
    auto expectPerPixelResult = [&]<class Kernel>(const Kernel& perPixel, const Kernel& shared,
                                                  int stride, bool interleaved, int cores) {
        parallelFor2D(w, hgt, perPixel);  // no scratch: the per-pixel form
        float* memory = scratch.floats(sharingScratchFloats(w, hgt, h.layout.padding));
        if (interleaved)
            parallelRowsSharingPairs(
                w, hgt, shared, [&](int k) { return interleavedRow(k, hgt, stride); }, stride,
                memory);
        else
            parallelRowsSharingPairs(
                w, hgt, shared, [](int k) { return k; }, 1, memory);
        for (int y = 0; y < hgt; ++y)
            for (int x = 0; x < w; ++x) {
                ASSERT_TRUE(nearUpToRounding(h.planes(h.c).load(h.layout.index(x, y)),
                                             h.planes(h.b).load(h.layout.index(x, y))))
                    << x << ", " << y << " stride " << stride << " interleaved " << interleaved
                    << " cores " << cores;
            }
    };
    // (Not more cores than the default: libomp keeps memory of a grown team to the end, which
    // LeakSanitizer reports.)
    for (int cores : {1, 2}) {
        omp_set_num_threads(std::min(cores, threadsBefore));
        for (int stride : {1, 2, 4, 8, 16}) {
            for (bool interleaved : {false, true}) {
                if (interleaved && stride == 1) continue;
                expectPerPixelResult(AtrousNarrowNormalKernel{h.gbuffer(), h.planes(h.a),
                                                              h.planes(h.b), stride, narrow},
                                     AtrousNarrowNormalKernel{h.gbuffer(), h.planes(h.a),
                                                              h.planes(h.c), stride, narrow},
                                     stride, interleaved, cores);
                expectPerPixelResult(
                    AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, wide},
                    AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.c), stride, wide}, stride,
                    interleaved, cores);
            }
        }
    }
    omp_set_num_threads(threadsBefore);
    // Filtered, not passed through: the result differs from the input; background passes.
    EXPECT_NE(h.planes(h.c).load(h.layout.index(10, 6)).x,
              h.planes(h.a).load(h.layout.index(10, 6)).x);
    ASSERT_EQ(h.ids.data()[h.layout.index(5, 1)], -1);
    EXPECT_EQ(h.planes(h.c).load(h.layout.index(5, 1)).x,
              h.planes(h.a).load(h.layout.index(5, 1)).x);
    // The modulated last level, through the device (its scratch and row order).
    DeviceBuffer<float> albedo = h.buffer(3);
    h.fillRandom(h.planes(albedo), next, 0.5f);
    std::vector<float> rgbPerPixel(3 * w * hgt), rgbShared(3 * w * hgt, -1.0f);
    for (int stride : {1, 16}) {
        parallelFor2D(w, hgt,
                      AtrousModulatedKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, wide,
                                            h.planes(albedo), rgbPerPixel.data()});
        h.device->launch(AtrousModulatedKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride,
                                               wide, h.planes(albedo), rgbShared.data()},
                         w, hgt);
        for (std::size_t k = 0; k < rgbPerPixel.size(); ++k)
            ASSERT_NEAR(rgbShared[k], rgbPerPixel[k], roundingTolerance(rgbPerPixel[k]))
                << k << " stride " << stride;
    }
}

// The blocks of rows the cores take for filterSharingPairs: in order, covering every row once,
// and in plain order those after the first shorter by half the rows they run for weights only.
TEST(CpuLauncher, SharingBlocksCoverTheRowsInOrderAndBalanceTheRowsAbove) {
    for (int height : {1, 5, 45, 512, 1080})
        for (int cores : {1, 2, 3, 5, 16})
            for (int above : {2, 8, 32})
                for (int step : {1, 4}) {
                    EXPECT_EQ(sharingBlockStart(0, cores, height, above, step), 0);
                    EXPECT_EQ(sharingBlockStart(cores, cores, height, above, step), height);
                    for (int c = 0; c < cores; ++c)
                        EXPECT_LE(sharingBlockStart(c, cores, height, above, step),
                                  sharingBlockStart(c + 1, cores, height, above, step))
                            << height << " " << cores << " " << above << " " << step;
                }
    // 512 rows, 2 cores, stride 8 in plain order (16 rows above): 260 rows for the first core,
    // 252 and 16 half rows for the second.
    EXPECT_EQ(sharingBlockStart(1, 2, 512, 16, 1), 260);
    EXPECT_EQ(sharingBlockStart(1, 2, 512, 16, 8), 256);  // interleaved: two rows above at most
}

// The same on images smaller than the taps' reach (a row, a column, a pixel), where most taps and
// most rows above a core's first lie in the border.
TEST(Atrous, PairsSharedBetweenRowsGiveThePerPixelResultOnTinyImages) {
    const EdgeStoppingTerms terms{1.0f / (2.0f * 0.6f * 0.6f), 1.0f / (2.0f * 0.5f * 0.5f),
                                  1.0f / (2.0f * 0.3f * 0.3f)};
    for (auto [w, hgt] : {std::pair{1, 1}, {3, 2}, {16, 1}, {1, 9}, {5, 33}}) {
        Harness h(w, hgt, 32);
        UnitRandom next{41u};
        for (int y = 0; y < hgt; ++y)
            for (int x = 0; x < w; ++x) {
                auto i = h.layout.index(x, y);
                h.planes(h.normal).store(
                    i, normalize(make3(0.6f * (next() - 0.5f), 0.6f * (next() - 0.5f), -1.0f)));
                h.planes(h.a).store(i, make3(next(), next(), next()));
            }
        for (int stride : {1, 2, 4, 8, 16}) {
            parallelFor2D(w, hgt,
                          AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, terms});
            h.device->launch(AtrousKernel{h.gbuffer(), h.planes(h.a), h.planes(h.c), stride, terms},
                             w, hgt);
            for (int y = 0; y < hgt; ++y)
                for (int x = 0; x < w; ++x) {
                    Float3 want = h.planes(h.b).load(h.layout.index(x, y));
                    Float3 got = h.planes(h.c).load(h.layout.index(x, y));
                    ASSERT_NEAR(got.y, want.y, roundingTolerance(want.y))
                        << w << "x" << hgt << " at " << x << ", " << y << " stride " << stride;
                }
        }
    }
}

// The scratch is that of the widest stride that shares pairs: strides of the image's height or
// more run per pixel (10 levels at 512x512: the ring of stride 512 would hold 1025 rows).
TEST(CpuLauncher, SharingScratchIgnoresStridesOfTheImageHeightOrMore) {
    EXPECT_EQ(sharingScratchFloats(512, 512, 1024), sharingScratchFloats(512, 512, 32));
    EXPECT_LT(sharingScratchFloats(512, 512, 1024) * sizeof(float),
              std::size_t(omp_get_max_threads()) << 20);  // under 1 MiB per core
    EXPECT_EQ(sharingScratchFloats(37, 1, 64), 0u);       // one row: nothing to share
}

// The device reserves the levels' scratch when it prepares a pipeline with A-Trous levels: the
// levels themselves, at every stride the padding allows, then allocate nothing.
TEST(CpuLauncher, AtrousLevelsAllocateNothingOnceTheWorkspaceIsReserved) {
    Harness h(37, 45, 64);
    Device& device = *h.device;
    const std::size_t buffers = device.allocatedBytes();
    device.prepare(h.layout, {StepKind::Ingest, StepKind::AtrousLevel});
    const std::size_t reserved = device.allocatedBytes();
    EXPECT_GE(reserved - buffers, sharingScratchFloats(37, 45, h.layout.padding) * sizeof(float));
    const EdgeStoppingTerms terms{1.0f, 50.0f, 50.0f};
    for (int stride : {1, 2, 4, 8, 16, 32}) {  // 32: the image's height or more, per pixel
        device.run(
            AtrousLevelStep{{h.gbuffer(), h.planes(h.a), h.planes(h.b), stride, terms}, false});
        EXPECT_EQ(device.allocatedBytes(), reserved) << "stride " << stride;
    }
}

TEST(Accumulate, ClampsHistoryToMeanPlusMinusKSigmaThenBlends) {
    // 3x3 image, radius 1: the centre's neighbourhood is the whole image. The window is read
    // at its compile-time width (masked taps), so the border is that wide.
    Harness h(3, 3, kNarrowWindow);
    const float values[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    for (int i = 0; i < 9; ++i)
        h.planes(h.a).store(h.layout.index(i % 3, i / 3), make3(values[i], values[i], 1.0f));
    // History: far above in R, far below in G, inside the range in B.
    h.planes(h.b).store(h.layout.index(1, 1), make3(100.0f, -100.0f, 1.0f));
    for (int i = 0; i < h.layout.planeSize; ++i) h.validity.data()[i] = kReprojectionValid;
    const float alpha = 0.2f, k = 1.5f;
    h.accumulate(alpha, k, 1);
    const float mean = 5.0f, sigma = std::sqrt(60.0f / 9.0f);  // population stddev of 1..9
    Float3 out = h.planes(h.c).load(h.layout.index(1, 1));
    EXPECT_NEAR(out.x, alpha * 5.0f + (1 - alpha) * (mean + k * sigma), 1e-4f);
    EXPECT_NEAR(out.y, alpha * 5.0f + (1 - alpha) * (mean - k * sigma), 1e-4f);
    EXPECT_NEAR(out.z, 1.0f, 1e-6f);  // sigma 0: history equals the mean, kept

    // Invalid history: a = 1, the current value passes unchanged.
    h.validity.data()[h.layout.index(1, 1)] = kReprojectionOtherObject;
    h.accumulate(alpha, k, 1);
    EXPECT_EQ(h.planes(h.c).load(h.layout.index(1, 1)).x, 5.0f);
}

// The fused modulation: the same history as the plain kernel, and the caller's interleaved RGB
// holding it times the albedo factor.
TEST(Accumulate, ModulatedKernelAlsoWritesTheResultTimesTheAlbedoInterleaved) {
    const int n = 9;
    Harness h(n, n, kNarrowWindow);
    DeviceBuffer<float> albedo = h.buffer(3), fused = h.buffer(3);
    std::vector<float> rgb(3 * n * n, -1.0f);
    UnitRandom next{3u};
    h.fillRandom(h.planes(h.a), next);
    h.fillRandom(h.planes(h.b), next);
    h.fillRandom(h.planes(albedo), next, 0.5f);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            h.validity.data()[h.layout.index(x, y)] =
                (x + y) % 3 ? kReprojectionValid : kReprojectionOtherObject;
    h.accumulate(0.2f, 1.0f, 2);  // the plain kernel, into h.c
    h.device->launch(AccumulateModulatedKernel{h.gbuffer(), h.sumPlanes(), h.planes(h.a),
                                               h.planes(h.b), h.validity.data(), h.planes(fused),
                                               0.2f, 1.0f, 2, h.planes(albedo), rgb.data()},
                     n, n);
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            auto i = h.layout.index(x, y);
            Float3 p = h.planes(h.c).load(i), f = h.planes(fused).load(i);
            // Another instantiation: the compiler may order the arithmetic differently.
            EXPECT_NEAR(f.x, p.x, 1e-6f * p.x);
            EXPECT_NEAR(f.y, p.y, 1e-6f * p.y);
            EXPECT_NEAR(f.z, p.z, 1e-6f * p.z);
        }
    h.expectModulatedOutput(h.planes(fused), h.planes(albedo), rgb);
}

// A 7x7 grey checker of 1 and 2 with a 50 at its centre: the firefly's window less itself holds
// 24 ones and 24 twos (mean 1.5, stddev 0.5), so it is clamped to 1.5 + 2 x 0.5 = 2.5 (with
// itself in its statistics it would keep 19.6).
void fillCheckerWithFirefly(Harness& h) {
    for (int y = 0; y < 7; ++y)
        for (int x = 0; x < 7; ++x) {
            const float v = x == 3 && y == 3 ? 50.0f : 1.0f + float((x + y + 1) % 2);
            h.planes(h.a).store(h.layout.index(x, y), make3(v, v, v));
        }
}

TEST(Outlier, FireflyIsClampedByItsWindowLessItselfOthersKept) {
    Harness h(7, 7, 3);
    fillCheckerWithFirefly(h);
    h.removeOutliers(3, 2.0f);
    EXPECT_NEAR(h.planes(h.b).load(h.layout.index(3, 3)).x, 2.5, 1e-4);
    EXPECT_EQ(h.planes(h.b).load(h.layout.index(0, 0)).x, 2.0f);  // the firefly widens its limit
    EXPECT_EQ(h.planes(h.b).load(h.layout.index(1, 0)).x, 1.0f);
}

// A light seen directly is kept (brightLikeItsObject): on the checker, a 50 of its own object
// alone in its 5x5, and two pixels of 40 and 30 of one object side by side, keep their values;
// the same 50 on the checker's object is still clamped to 2.5 (the test above), and so are a 40
// whose brighter neighbour belongs to another object and a pair of fireflies side by side on the
// checker (2 of its object's 24 pixels in their 5x5 bright: noise, not a light).
TEST(Outlier, ALightSeenDirectlyIsKept) {
    Harness h(9, 9, 3);
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 9; ++x) {
            const float v = 1.0f + float((x + y + 1) % 2);
            h.planes(h.a).store(h.layout.index(x, y), make3(v, v, v));
        }
    const auto set = [&](int x, int y, float v, int id) {
        h.planes(h.a).store(h.layout.index(x, y), make3(v, v, v));
        h.ids.data()[h.layout.index(x, y)] = id;
    };
    set(2, 2, 50.0f, 1);  // a light a pixel wide
    set(6, 6, 40.0f, 2);  // a light two pixels wide
    set(7, 6, 30.0f, 2);
    set(6, 2, 40.0f, 0);  // a firefly on the checker beside another object's light
    set(7, 2, 45.0f, 3);
    set(1, 7, 40.0f, 0);  // two fireflies side by side on the checker
    set(2, 7, 35.0f, 0);
    h.removeOutliers(3, 2.0f);
    EXPECT_EQ(h.planes(h.b).load(h.layout.index(2, 2)).x, 50.0f);
    EXPECT_EQ(h.planes(h.b).load(h.layout.index(6, 6)).x, 40.0f);
    EXPECT_EQ(h.planes(h.b).load(h.layout.index(7, 6)).x, 30.0f);
    EXPECT_LT(h.planes(h.b).load(h.layout.index(6, 2)).x, 20.0f);
    EXPECT_LT(h.planes(h.b).load(h.layout.index(1, 7)).x, 20.0f);
    EXPECT_LT(h.planes(h.b).load(h.layout.index(2, 7)).x, 20.0f);
}

// The firefly removal's tile pass (OutlierTile) gives the separate passes' result: the
// despeckled colour, and with the clamp window its row sums of that colour (ColorRowSums), on
// images that end inside a tile, with background and two objects, for radii 1 to 3; run by the
// CPU launcher and as the GPU's blocks would run it (any order of the items within a phase).
TEST(OutlierTile, GivesTheSeparatePassesResult) {
    for (auto [w, h] : {std::pair{45, 21}, std::pair{70, 9}, std::pair{3, 2}, std::pair{32, 8}})
        for (int radius = 1; radius <= kNarrowWindow; ++radius) {
            SCOPED_TRACE(::testing::Message() << w << "x" << h << ", radius " << radius);
            Harness harness(w, h, kNarrowWindow);
            const Layout& L = harness.layout;
            UnitRandom next{777u + unsigned(radius)};
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    auto i = L.index(x, y);
                    float firefly = next() < 0.05f ? 40.0f : 1.0f;
                    harness.planes(harness.a).store(i, make3(next(), next(), next()) * firefly);
                    float r = next();
                    harness.ids.data()[i] = r < 0.2f ? -1 : (x + y) % 7 < 3 ? 1 : 0;
                }
            const float k = 1.5f;
            // The separate passes: a -> b (despeckled), then the clamp's row sums of b.
            harness.removeOutliers(radius, k);
            DeviceBuffer<float> clampSums = harness.buffer(7);
            harness.device->launch(ColorRowSumsKernel{harness.gbuffer(), harness.planes(harness.b),
                                                      harness.planeSet(clampSums), 3},
                                   w, h);
            for (int form = 0; form < 2; ++form) {
                auto run = [&, w = w, h = h](const auto& kernel) {
                    if (form == 0)
                        harness.device->launch(kernel, w, h);
                    else
                        runTilesAsBlocks(kernel, w, h);
                };
                DeviceBuffer<float> out = harness.buffer(3), tileSums = harness.buffer(7),
                                    plainOut = harness.buffer(3);
                run(OutlierClampTileKernel{harness.gbuffer(), harness.planes(harness.a),
                                           harness.planes(out), harness.planeSet(tileSums), radius,
                                           k});
                // The plain tile (no clamp sums) writes the same colour.
                run(OutlierTileKernel{harness.gbuffer(),
                                      harness.planes(harness.a),
                                      harness.planes(plainOut),
                                      {},
                                      radius,
                                      k});
                for (int y = 0; y < h; ++y)
                    for (int x = 0; x < w; ++x) {
                        auto i = L.index(x, y);
                        Float3 want = harness.planes(harness.b).load(i);
                        EXPECT_TRUE(nearUpToRounding(harness.planes(out).load(i), want))
                            << "form " << form << " at " << x << ", " << y;
                        EXPECT_TRUE(nearUpToRounding(harness.planes(plainOut).load(i), want))
                            << "form " << form << " at " << x << ", " << y;
                        for (int p = 0; p < 7; ++p) {
                            float got = harness.planeSet(tileSums).at(p, i),
                                  expected = harness.planeSet(clampSums).at(p, i);
                            EXPECT_NEAR(got, expected, 4.0f * roundingTolerance(expected))
                                << "form " << form << ", plane " << p << " at " << x << ", " << y;
                        }
                    }
                // Nothing written outside the image (the border stays 0).
                for (int y = -kNarrowWindow; y < h + kNarrowWindow; ++y)
                    for (int x = -kNarrowWindow; x < w + kNarrowWindow; ++x) {
                        if (x >= 0 && x < w && y >= 0 && y < h) continue;
                        auto i = L.index(x, y);
                        EXPECT_EQ(harness.planes(out).load(i).x, 0.0f) << x << ", " << y;
                        EXPECT_EQ(harness.planeSet(tileSums).at(0, i), 0.0f) << x << ", " << y;
                    }
            }
        }
}

// The firefly really is removed by the tile pass (a known answer, as for Outlier above).
TEST(OutlierTile, FireflyIsClampedByItsWindowLessItself) {
    Harness h(7, 7, 3);
    fillCheckerWithFirefly(h);
    h.device->launch(OutlierTileKernel{h.gbuffer(), h.planes(h.a), h.planes(h.b), {}, 3, 2.0f}, 7,
                     7);
    EXPECT_NEAR(h.planes(h.b).load(h.layout.index(3, 3)).x, 2.5, 1e-4);
    EXPECT_EQ(h.planes(h.b).load(h.layout.index(0, 0)).x, 2.0f);
}

// The row + column sums equal the 2-D window sums, for a narrow and a wide kernel and radii
// below their compile-time width (the masked taps).
template <int MaxRadius>
void expectSeparableSumsEqualDirect(int r) {
    // Random colours and a background hole.
    Harness h(23, 17, kWideWindow);
    UnitRandom next{12345u};
    for (int y = 0; y < 17; ++y)
        for (int x = 0; x < 23; ++x) {
            h.planes(h.a).store(h.layout.index(x, y), make3(next(), next(), next()));
            if (x > 5 && x < 9 && y > 3 && y < 12) h.ids.data()[h.layout.index(x, y)] = -1;
        }
    h.device->launch(ColorRowSums<MaxRadius>{h.gbuffer(), h.planes(h.a), h.sumPlanes(), r}, 23, 17);
    for (int y = 0; y < 17; ++y)
        for (int x = 0; x < 23; ++x) {
            double direct[7] = {0, 0, 0, 0, 0, 0, 0};
            for (int yy = std::max(0, y - r); yy <= std::min(16, y + r); ++yy)
                for (int xx = std::max(0, x - r); xx <= std::min(22, x + r); ++xx) {
                    auto j = h.layout.index(xx, yy);
                    if (h.ids.data()[j] < 0) continue;
                    Float3 v = h.planes(h.a).load(j);
                    double c[3] = {v.x, v.y, v.z};
                    direct[0] += 1;
                    for (int k = 0; k < 3; ++k) {
                        direct[1 + k] += c[k];
                        direct[4 + k] += c[k] * c[k];
                    }
                }
            auto i = h.layout.index(x, y);
            for (int plane = 0; plane < 7; ++plane)
                EXPECT_NEAR(columnSum<MaxRadius>(h.sumPlanes(), plane, i, h.layout.pitch, r),
                            direct[plane], 1e-3)
                    << "radius " << r << ", plane " << plane << " at (" << x << ", " << y << ")";
        }
}

TEST(WindowSums, SeparableStatisticsEqualTheDirectWindow) {
    expectSeparableSumsEqualDirect<kNarrowWindow>(1);
    expectSeparableSumsEqualDirect<kNarrowWindow>(3);
    expectSeparableSumsEqualDirect<kWideWindow>(5);
    expectSeparableSumsEqualDirect<kWideWindow>(15);
}

// The CPU launcher's block-sparse mode: a kernel with active() has its body run on the runs of
// kSparseBlock pixels of a row that hold an active pixel, and on no other.
struct MarkVisited {
    int width;
    std::uint8_t* visited;
    const std::uint8_t* activeMask;
    bool active(int x, int y) const { return activeMask[y * width + x] != 0; }
    void operator()(int x, int y) const { visited[y * width + x] = 1; }
};

TEST(CpuLauncher, BlockSparseKernelsRunOnlyOnRunsWithAnActivePixel) {
    const int w = 70, h = 9;  // 70 = 4 runs of 16 and a short one
    std::vector<std::uint8_t> visited(w * h, 0), activeMask(w * h, 0);
    activeMask[5 * w + 3] = 1;   // row 5, run [0, 16)
    activeMask[7 * w + 47] = 1;  // row 7, run [32, 48)
    activeMask[7 * w + 69] = 1;  // row 7, the short run [64, 70)
    static_assert(BlockSparse<MarkVisited>);
    parallelFor2D(w, h, MarkVisited{w, visited.data(), activeMask.data()});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool expected = (y == 5 && x < 16) || (y == 7 && ((x >= 32 && x < 48) || x >= 64));
            EXPECT_EQ(visited[std::size_t(y * w + x)], expected ? 1 : 0) << x << ", " << y;
        }
}

// The launcher's interleaved row order (wide A-Trous strides): a permutation of the rows in
// which rows of one class (equal y mod stride) come one after another, stride apart.
TEST(CpuLauncher, InterleavedRowsVisitEveryRowOnceClassByClass) {
    for (int height : {1, 7, 64, 1080, 1081}) {
        for (int stride : {2, 3, 8, 16}) {
            if (stride >= height) continue;
            std::vector<int> seen(std::size_t(height), 0);
            int previous = -1;
            for (int k = 0; k < height; ++k) {
                int y = interleavedRow(k, height, stride);
                ASSERT_GE(y, 0);
                ASSERT_LT(y, height);
                ++seen[std::size_t(y)];
                if (previous >= 0 && previous % stride == y % stride) {
                    EXPECT_EQ(y, previous + stride) << height << ", " << stride << ", k " << k;
                } else if (previous >= 0) {
                    EXPECT_EQ(y % stride, previous % stride + 1) << "classes in order";
                }
                previous = y;
            }
            for (int y = 0; y < height; ++y) EXPECT_EQ(seen[std::size_t(y)], 1) << y;
        }
    }
}

struct CountVisits {
    int width, stride;
    int* visits;
    int tapRowStride() const { return stride; }
    void operator()(int x, int y) const { visits[y * width + x] += 1; }
};

TEST(CpuLauncher, StridedKernelsVisitEveryPixelOnce) {
    const int w = 4096, h = 40, stride = 16;  // wide enough to interleave (interleaveRows)
    ASSERT_TRUE(interleaveRows(stride, w));
    std::vector<int> visits(std::size_t(w) * h, 0);
    parallelFor2D(w, h, CountVisits{w, stride, visits.data()});
    for (std::size_t i = 0; i < visits.size(); ++i) ASSERT_EQ(visits[i], 1) << i;
}

// The matrices of two objects on the harness's wall, whose pixel (x, y) is world (x, y, 5):
// object 0 static, object 1 moved (dx, dy) pixels since the previous frame.
std::array<ObjectReprojection, 2> wallObjectsWithSecondMoved(float dx, float dy) {
    std::array<ObjectReprojection, 2> objects = {};
    for (int k = 0; k < 2; ++k) {
        float mx = k ? dx : 0.0f, my = k ? dy : 0.0f;
        objects[k].currentWorldToPreviousScreen =
            Mat4{{{5, 0, 0, 2.5f - 5 * mx}, {0, 5, 0, 2.5f - 5 * my}, {0, 0, 1, 0}, {0, 0, 1, 0}}};
        objects[k].currentWorldToPreviousWorld =
            Mat4{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
        objects[k].valid = 1;
    }
    return objects;
}

// The launcher's runs of one object ID (KeyedRuns: matrices loaded once per run) give what the
// per-pixel form gives, with two objects moving differently and a mixed run.
TEST(Reproject, RunsOfOneObjectGiveThePerPixelResult) {
    const int w = 48, hgt = 6;
    Harness h(w, hgt, 4);
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) h.ids.data()[h.layout.index(x, y)] = x < 21 ? 0 : 1;
    h.ids.data()[h.layout.index(40, 2)] = 0;  // a mixed run on the right
    UnitRandom next{9u};
    DeviceBuffer<float> history = h.buffer(3), viaRuns = h.buffer(3), perPixel = h.buffer(3),
                        derivatives = h.buffer(3);
    for (int i = 0; i < h.layout.planeSize; ++i)
        h.planes(history).store(i, make3(next(), next(), next()));
    // Object 1 moved 1.3 pixels right and 0.4 up since the previous frame.
    const auto wall = wallObjectsWithSecondMoved(1.3f, -0.4f);
    const ObjectReprojection* objects = wall.data();
    PreviousGeometry previous{h.ids.data(), h.depth.data(), h.planes(h.normal)};
    std::vector<std::uint8_t> codes(std::size_t(h.layout.planeSize));
    auto kernel = [&](DeviceBuffer<float>& out, std::uint8_t* validity) {
        return ReprojectKernel{h.gbuffer(),
                               previous,
                               objects,
                               2,
                               h.planeSet(derivatives),
                               HistoryTest{0, 10.0f, 16.0f},
                               h.planes(history),
                               h.planes(out),
                               validity,
                               1};
    };
    h.device->launch(kernel(viaRuns, h.validity.data()), w, hgt);
    const ReprojectKernel reference = kernel(perPixel, codes.data());
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) reference(x, y);
    int moved = 0;
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            Float3 a = h.planes(viaRuns).load(i), b = h.planes(perPixel).load(i);
            // Vectorised against scalar: FMA contraction may differ in the last bits.
            EXPECT_NEAR(a.x, b.x, 1e-6f) << x << ", " << y;
            EXPECT_NEAR(a.z, b.z, 1e-6f) << x << ", " << y;
            EXPECT_EQ(h.validity.data()[i], codes[std::size_t(i)]) << x << ", " << y;
            moved +=
                h.validity.data()[i] == kReprojectionValid && a.x != h.planes(history).load(i).x;
        }
    EXPECT_GT(moved, 0);  // object 1 was sampled elsewhere: its matrices were used
}

// The GPU's one-pass temporal stage (ReprojectAccumulate: the history in registers, the slopes
// computed) gives what the geometry pass, the reprojection and the modulated accumulation give
// as three passes, with two objects moving differently (valid, off-screen and other-object
// history), varying depth slopes and normals, and background.
TEST(Reproject, OnePassWithTheAccumulationGivesTheTwoPassResult) {
    const int w = 24, hgt = 10;
    Harness h(w, hgt, 4);
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x)
            h.ids.data()[h.layout.index(x, y)] = x == 3 && y == 4 ? -1 : x < 11 ? 0 : 1;
    UnitRandom next{17u};
    DeviceBuffer<float> history = h.buffer(3), derivatives = h.buffer(3), albedo = h.buffer(3),
                        reprojected = h.buffer(3), twoPass = h.buffer(3), onePass = h.buffer(3);
    h.fillRandom(h.planes(history), next);
    h.fillRandom(h.planes(h.a), next);  // this frame, filtered
    h.fillRandom(h.planes(albedo), next, 0.5f);
    // Depth slopes and normals that vary, for the slopes the one-pass form computes itself.
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            h.depth.data()[i] = 5.0f + 0.01f * float(x) + 0.004f * float(y * y);
            h.planes(h.normal).store(
                i, normalize(make3(0.1f * (next() - 0.5f), 0.1f * (next() - 0.5f), -1.0f)));
        }
    // Object 1 moved 2.6 pixels right and 0.7 up since the previous frame (its left edge then
    // samples object 0).
    const auto wall = wallObjectsWithSecondMoved(2.6f, -0.7f);
    const ObjectReprojection* objects = wall.data();
    PreviousGeometry previous{h.ids.data(), h.depth.data(), h.planes(h.normal)};
    std::vector<std::uint8_t> codes(std::size_t(h.layout.planeSize), 0);
    std::vector<float> rgbTwo(3 * w * hgt), rgbOne(3 * w * hgt, -1.0f);
    auto reproject = [&](Planes3 out, std::uint8_t* validity) {
        return ReprojectKernel{h.gbuffer(),
                               previous,
                               objects,
                               2,
                               h.planeSet(derivatives),
                               HistoryTest{1, 10.0f, 16.0f},
                               h.planes(history),
                               out,
                               validity,
                               1};
    };
    auto accumulate = [&](Planes3 out, float* rgb) {
        return AccumulateModulatedKernel{h.gbuffer(),
                                         h.sumPlanes(),
                                         h.planes(h.a),
                                         h.planes(reprojected),
                                         h.validity.data(),
                                         out,
                                         0.2f,
                                         1.0f,
                                         2,
                                         h.planes(albedo),
                                         rgb};
    };
    h.device->launch(GeometryDerivativesKernel{h.gbuffer(), h.planeSet(derivatives)}, w, hgt);
    h.device->launch(ColorRowSumsKernel{h.gbuffer(), h.planes(h.a), h.sumPlanes(), 2}, w, hgt);
    h.device->launch(reproject(h.planes(reprojected), h.validity.data()), w, hgt);
    h.device->launch(accumulate(h.planes(twoPass), rgbTwo.data()), w, hgt);
    // Without the derivative planes: it computes the slopes.
    ReprojectKernel noDerivatives = reproject({}, codes.data());
    noDerivatives.derivatives = {};
    const ReprojectAccumulateKernel fused{noDerivatives,
                                          accumulate(h.planes(onePass), rgbOne.data())};
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) fused(x, y);
    int valid = 0, invalid = 0;
    for (int y = 0; y < hgt; ++y)
        for (int x = 0; x < w; ++x) {
            auto i = h.layout.index(x, y);
            ASSERT_EQ(codes[std::size_t(i)], h.validity.data()[i]) << x << ", " << y;
            Float3 a = h.planes(twoPass).load(i), b = h.planes(onePass).load(i);
            // Vectorised against scalar: FMA contraction may differ in the last bits.
            EXPECT_NEAR(b.x, a.x, 1e-6f * std::fabs(a.x) + 1e-7f) << x << ", " << y;
            EXPECT_NEAR(b.y, a.y, 1e-6f * std::fabs(a.y) + 1e-7f) << x << ", " << y;
            EXPECT_NEAR(b.z, a.z, 1e-6f * std::fabs(a.z) + 1e-7f) << x << ", " << y;
            valid += codes[std::size_t(i)] == kReprojectionValid;
            invalid += codes[std::size_t(i)] != kReprojectionValid;
        }
    for (std::size_t k = 0; k < rgbTwo.size(); ++k)
        ASSERT_NEAR(rgbOne[k], rgbTwo[k], 1e-6f * std::fabs(rgbTwo[k]) + 1e-7f) << k;
    EXPECT_GT(valid, 0);    // histories blended in
    EXPECT_GT(invalid, 0);  // and refused (off screen, other object, background)
}

// Records how each pixel was run: 1 with its known key, 2 without.
struct RecordKeyedRuns {
    int width;
    const std::int32_t* keys;
    std::uint8_t* how;
    std::int32_t runKey(int x, int y) const { return keys[y * width + x]; }
    template <bool KnownKey>
    void pixel(int x, int y, std::int32_t key) const {
        // A known key is the pixel's own (else mark 9, which the test rejects).
        how[y * width + x] = KnownKey ? (key == keys[y * width + x] ? 1 : 9) : 2;
    }
    void operator()(int x, int y) const { pixel<false>(x, y, 0); }
};

TEST(CpuLauncher, RunsOfOneKeyGetItKnownOthersRunPerPixel) {
    const int w = 70, h = 5;  // 4 runs of 16 and a short one per row
    std::vector<std::int32_t> keys(w * h, 3);
    std::vector<std::uint8_t> how(w * h, 0);
    keys[2 * w + 20] = 4;                               // row 2, run [16, 32): mixed
    keys[4 * w + 66] = -1;                              // row 4, the short run [64, 70): mixed
    for (int x = 32; x < 48; ++x) keys[3 * w + x] = 7;  // row 3, run [32, 48): one other key
    static_assert(KeyedRuns<RecordKeyedRuns>);
    parallelFor2D(w, h, RecordKeyedRuns{w, keys.data(), how.data()});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool mixed = (y == 2 && x >= 16 && x < 32) || (y == 4 && x >= 64);
            EXPECT_EQ(how[std::size_t(y * w + x)], mixed ? 2 : 1) << x << ", " << y;
        }
}

// WhereKeyed (the split signal's specular passes): a keyed kernel's runs without a key >= 0
// are skipped; the others run keyed as before, the skipped key's pixels in them included.
TEST(CpuLauncher, WhereKeyedSkipsRunsWithoutAKeyAndKeepsTheKeyedRuns) {
    const int w = 70, h = 4;  // 4 runs of 16 and a short one per row
    std::vector<std::int32_t> keys(w * h, 3), mask(w * h, -1);
    std::vector<std::uint8_t> how(w * h, 0);
    for (int x = 16; x < 32; ++x) mask[1 * w + x] = 3;  // row 1, run [16, 32): all keyed
    mask[2 * w + 40] = 3;                               // row 2, run [32, 48): one pixel keyed
    keys[3 * w + 66] = 5;                               // row 3, the short run: mixed IDs,
    mask[3 * w + 65] = 3;                               // one pixel keyed
    using Masked = WhereKeyed<RecordKeyedRuns>;
    static_assert(KeyedRuns<Masked> && BlockSparse<Masked>);
    const Layout unpadded{w, h, w, 0, 0, w * h};
    parallelFor2D(w, h, Masked{RecordKeyedRuns{w, keys.data(), how.data()}, unpadded, mask.data()});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int expected = (y == 1 && x >= 16 && x < 32) || (y == 2 && x >= 32 && x < 48) ? 1
                           : y == 3 && x >= 64                                            ? 2
                                                                                          : 0;
            EXPECT_EQ(how[std::size_t(y * w + x)], expected) << x << ", " << y;
        }
}

}  // namespace
}  // namespace rtd
