// Values a renderer really writes that used to give a wrong image without an error: radiance
// near the float maximum, normals that are short, long or zero, sigmas at the edge of their
// range. Every method, the CPU's instruction sets; the result must be finite and not darkened.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>

#include "test_support.h"
#include "tuning.h"

namespace rtd {
namespace {

using test::makeFrame;
using test::SceneDescription;

const Method kEveryMethod[] = {Method::Jbf,  Method::Atrous, Method::Temporal,
                               Method::Svgf, Method::Detail, Method::Learned};

DenoiserSettings settingsFor(Method method) {
    DenoiserSettings s = test::cpuSettings(method);
    s.jbf.radius = 6;  // small frames
    return s;
}

// 32x24, two objects at different depths, a background strip, a textured noisy colour: every
// filter has edges, object pixels and background to get right.
SceneDescription texturedScene() {
    SceneDescription d;
    d.width = 32;
    d.height = 24;
    d.objectCount = 2;
    d.id = [](int x, int y) { return y < 2 ? -1 : (x < 16 ? 0 : 1); };
    d.depth = [](int x, int) { return x < 16 ? 4.0f : 6.0f; };
    d.colour = [](int x, int y) {
        return std::array<float, 3>{0.2f + 0.02f * float((x * 7 + y * 3) % 11), 0.4f,
                                    0.3f + 0.01f * float(y % 5)};
    };
    return d;
}

std::size_t nonFiniteCount(const Image& image) {
    std::size_t n = 0;
    for (float v : image.pixels) n += std::isfinite(v) ? 0 : 1;
    return n;
}

double meanOver(const Image& image, int x0, int y0, int x1, int y1) {
    double sum = 0.0;
    int n = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c, ++n) sum += image.at(x, y, c);
    return sum / n;
}

double maxRelative(const Image& a, const Image& b) {
    double m = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        m = std::max(m, double(std::abs(a.pixels[i] - b.pixels[i])) /
                            std::max(1e-3, double(std::abs(b.pixels[i]))));
    return m;
}

// One pixel of radiance near the float maximum used to overflow the filters' sums (a 16x16 block
// of NaN/Inf). Any finite input must give a finite output, on every instruction set.
TEST(BadValues, HugeFiniteRadianceGivesAFiniteResult) {
    for (float huge : {FLT_MAX, 3.4e38f, 3.0e38f, 1e30f, 1e19f}) {
        for (CpuIsa isa : {CpuIsa::Scalar, CpuIsa::Auto}) {
            for (Method method : kEveryMethod) {
                for (bool outlier : {true, false}) {
                    DenoiserSettings s = settingsFor(method);
                    s.outlier.enabled = outlier;
                    Denoiser denoiser = makeTunedDenoiser(s, {isa});
                    for (int frame = 0; frame < 3; ++frame) {
                        Frame f = makeFrame(texturedScene());
                        test::addNoise(f, 0.1f, unsigned(frame));
                        for (int c = 0; c < 3; ++c) f.beauty.at(10, 10, c) = huge;
                        f.beauty.at(20, 12, 1) = huge;  // on the other object, one channel
                        f.beauty.at(5, 0, 2) = huge;    // background
                        Image out = denoiser.processFrame(f);
                        ASSERT_EQ(nonFiniteCount(out), 0u)
                            << huge << " " << toString(method) << " " << toString(isa)
                            << (outlier ? "" : " without firefly removal") << ", frame " << frame;
                        EXPECT_EQ(denoiser.lastFrameStats().radianceClamped,
                                  huge > kMaxRadiance ? 5 : 0)
                            << huge << " " << toString(method);
                    }
                }
            }
        }
    }
}

// The split signal: lobes kept apart and merged pixel by pixel (every run of the specular passes
// mixed, so their skipped pixels lie beside the filtered ones), with NaN, Inf, negative and huge
// values in the specular colour, roughness and hit distance. The result must stay finite.
TEST(BadValues, SplitSignalWithMixedLobesAndBadValuesGivesAFiniteResult) {
    const float bad[] = {std::nanf(""), INFINITY, -INFINITY, -1.0f, FLT_MAX, 0.0f};
    for (CpuIsa isa : {CpuIsa::Scalar, CpuIsa::Auto}) {
        Denoiser denoiser = makeTunedDenoiser(settingsFor(Method::Detail), {isa});
        for (int frame = 0; frame < 5; ++frame) {
            Frame f = makeFrame(texturedScene());
            test::addNoise(f, 0.1f, unsigned(frame));
            const int w = f.width(), h = f.height();
            f.specular = Image(w, h, 3);
            f.roughness = Image(w, h, 1);
            f.hitDistance = Image(w, h, 1);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const int k = x * 5 + y * 3 + frame;
                    for (int c = 0; c < 3; ++c)
                        f.specular->at(x, y, c) =
                            k % 7 == 0 ? bad[(k + c) % 6] : 0.3f * f.beauty.at(x, y, c);
                    f.roughness->at(x, y, 0) = k % 11 == 0 ? bad[k % 6] : (x + y) % 2 ? 0.1f : 0.9f;
                    f.hitDistance->at(x, y, 0) = k % 13 == 0 ? bad[k % 6] : 2.0f + 0.1f * float(x);
                }
            Image out = denoiser.processFrame(f);
            ASSERT_EQ(nonFiniteCount(out), 0u) << toString(isa) << ", frame " << frame;
        }
    }
}

// A demodulated colour divides by the albedo: a tiny albedo (or epsilon) must not overflow it,
// and a huge albedo multiplied back must not either.
TEST(BadValues, ExtremeAlbedoGivesAFiniteResult) {
    for (float albedo : {1e-30f, 0.0f, 3e38f}) {
        for (Method method : kEveryMethod) {
            DenoiserSettings s = settingsFor(method);
            s.albedo.epsilon = 1e-30f;
            Denoiser denoiser(s);
            for (int frame = 0; frame < 2; ++frame) {
                Frame f = makeFrame(texturedScene());
                test::addNoise(f, 0.1f, unsigned(frame));
                f.albedo = Image(f.width(), f.height(), 3, 0.5f);
                for (int y = 8; y < 12; ++y)
                    for (int x = 8; x < 12; ++x)
                        for (int c = 0; c < 3; ++c) f.albedo->at(x, y, c) = albedo;
                f.beauty.at(9, 9, 0) = 3e38f;
                Image out = denoiser.processFrame(f);
                ASSERT_EQ(nonFiniteCount(out), 0u) << albedo << " " << toString(method);
            }
        }
    }
}

// The firefly clamp (luminance to mean + k sigma of its window) used to do nothing from 1e19 up,
// where the sum of squares overflows: it must scale a lone firefly by the same factor at every
// magnitude the ingest keeps, and bring a larger one down too.
TEST(BadValues, FireflyClampWorksAtAnyMagnitude) {
    DenoiserSettings s = settingsFor(Method::Jbf);
    s.jbf.radius = 0;  // the filter keeps each pixel: what is left is the firefly removal's
    const auto fireflyAfterClamp = [&](float value) {
        SceneDescription d;  // flat grey wall
        Frame f = makeFrame(d);
        for (int c = 0; c < 3; ++c) f.beauty.at(16, 16, c) = value;
        Denoiser denoiser(s);
        return denoiser.processFrame(f).at(16, 16, 0);
    };
    // On the flat 0.5 wall the window less the firefly has no spread: it comes out at the wall's
    // level (the energy restoration's lift aside). Far above the others, the float sums keep
    // their rounding of it: a looser limit, still under 1e-3 of it.
    EXPECT_NEAR(fireflyAfterClamp(1e3f), 0.5f, 0.1f);
    for (float value : {1e5f, 1e8f, 1e12f, 1e15f}) {
        const float ratio = fireflyAfterClamp(value) / value;
        EXPECT_LT(ratio, 1e-3f) << value;
    }
    for (float value : {1e19f, 1e30f, FLT_MAX}) {
        const float out = fireflyAfterClamp(value);
        EXPECT_TRUE(std::isfinite(out)) << value;
        EXPECT_LT(out, 0.5f * kMaxRadiance) << value;
    }
}

// Renderers write unnormalised normals (normal maps, interpolation, half floats): the result must
// be the one of the unit normals.
TEST(BadValues, UnnormalisedNormalsGiveTheUnitNormalsResult) {
    for (float length : {0.7f, 0.95f, 1.3f}) {
        for (Method method : kEveryMethod) {
            Denoiser unit(settingsFor(method)), scaled(settingsFor(method));
            for (int frame = 0; frame < 3; ++frame) {
                Frame f = makeFrame(texturedScene());
                test::addNoise(f, 0.2f, unsigned(frame));
                Frame g = f;
                for (float& v : g.normal.pixels) v *= length;
                Image expected = unit.processFrame(f), out = scaled.processFrame(g);
                EXPECT_LT(maxRelative(out, expected), 1e-3)
                    << length << " " << toString(method) << " frame " << frame;
                EXPECT_EQ(scaled.lastFrameStats().missingNormals, 0);
            }
        }
    }
}

// Zero normals (emitters, hair, volumes) and non-finite ones on object pixels: they are filtered
// among themselves with a neutral normal term (not kept noisy), never darkened, and counted; the
// pixels with a normal around them do not take them in.
TEST(BadValues, ZeroOrNonFiniteNormalsDoNotDarkenAndAreCounted) {
    for (Method method : kEveryMethod) {
        Denoiser clean(settingsFor(method)), broken(settingsFor(method));
        for (int frame = 0; frame < 3; ++frame) {
            Frame f = makeFrame(texturedScene());
            test::addNoise(f, 0.2f, unsigned(frame));
            Frame g = f;
            for (int y = 6; y < 14; ++y)
                for (int x = 4; x < 12; ++x)
                    for (int c = 0; c < 3; ++c) g.normal.at(x, y, c) = 0.0f;
            g.normal.at(24, 10, 0) = std::nanf("");
            g.normal.at(25, 10, 2) = INFINITY;
            Image expected = clean.processFrame(f), out = broken.processFrame(g);
            ASSERT_EQ(nonFiniteCount(out), 0u) << toString(method);
            EXPECT_EQ(broken.lastFrameStats().missingNormals, 8 * 8 + 2) << toString(method);
            const double input = meanOver(f.beauty, 4, 6, 12, 14);
            const double result = meanOver(out, 4, 6, 12, 14);
            EXPECT_NEAR(result, input, 0.05 * input) << toString(method) << " frame " << frame;
            EXPECT_NEAR(result, meanOver(expected, 4, 6, 12, 14), 0.05 * input) << toString(method);
            // Lone pixels without a normal filter among themselves (here: the two of them).
            for (int x : {24, 25})
                EXPECT_GT(out.at(x, 10, 1), 0.5f * expected.at(x, 10, 1)) << toString(method);
            // Filtered, not passed through: the block is smoother than the noisy input.
            double inputSpread = 0.0, resultSpread = 0.0;
            for (int y = 7; y < 13; ++y)
                for (int x = 5; x < 11; ++x) {
                    inputSpread += std::abs(f.beauty.at(x, y, 1) - f.beauty.at(x + 1, y, 1));
                    resultSpread += std::abs(out.at(x, y, 1) - out.at(x + 1, y, 1));
                }
            EXPECT_LT(resultSpread, 0.5 * inputSpread) << toString(method);
        }
    }
}

// A broken depth or position pass, or an ID pass of -1 everywhere, leaves the frame as noisy as it
// came: each is counted (FrameStats) and named by inputWarning; a normal frame warns of nothing.
TEST(BadValues, FramesWithoutUsableGeometryAreCountedAndWarnedOf) {
    for (Method method : kEveryMethod) {
        Denoiser denoiser(settingsFor(method));
        Frame f = makeFrame(texturedScene());
        const long long pixels = 32 * 24, background = 32 * 2;
        denoiser.processFrame(f);
        FrameStats s = denoiser.lastFrameStats();
        EXPECT_EQ(s.pixels, pixels);
        EXPECT_EQ(s.backgroundPixels, background) << toString(method);
        EXPECT_EQ(s.nonFiniteGeometry, 0);
        EXPECT_EQ(inputWarning(s), "");

        Frame depthNan = f;
        for (float& z : depthNan.depth.pixels) z = std::nanf("");
        Image out = denoiser.processFrame(depthNan);
        s = denoiser.lastFrameStats();
        EXPECT_EQ(s.nonFiniteGeometry, pixels - background) << toString(method);
        EXPECT_EQ(s.backgroundPixels, pixels);
        EXPECT_NE(inputWarning(s).find("92 % of the pixels have a NaN or Inf depth or position"),
                  std::string::npos)
            << inputWarning(s);
        EXPECT_LT(maxRelative(out, depthNan.beauty), 1e-5) << toString(method);  // passed through

        Frame positionInf = f;
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 20; ++x) positionInf.position.at(x, y, 1) = INFINITY;
        denoiser.processFrame(positionInf);
        s = denoiser.lastFrameStats();
        EXPECT_EQ(s.nonFiniteGeometry, 20 * 22) << toString(method);
        EXPECT_NE(inputWarning(s).find("57 % of the pixels have a NaN or Inf"), std::string::npos)
            << inputWarning(s);

        Frame noIds = f;
        for (std::int32_t& id : noIds.objectId) id = -1;
        denoiser.processFrame(noIds);
        s = denoiser.lastFrameStats();
        EXPECT_EQ(s.backgroundPixels, pixels);
        EXPECT_NE(inputWarning(s).find("100 % of the pixels are background"), std::string::npos)
            << inputWarning(s);

        Frame noNormals = f;
        for (float& n : noNormals.normal.pixels) n = 0.0f;
        denoiser.processFrame(noNormals);
        s = denoiser.lastFrameStats();
        EXPECT_EQ(s.missingNormals, pixels - background);
        EXPECT_NE(inputWarning(s).find("92 % of the pixels have a zero or non-finite normal"),
                  std::string::npos)
            << inputWarning(s);
    }
}

// A sigma so small that 1 / (2 sigma^2) overflows used to pass validation and blacken the image
// (0 * inf in the centre tap): it is refused, and the smallest accepted one keeps the image.
TEST(BadValues, TinySigmasAreRefusedOrKeepTheImage) {
    struct Case {
        const char* name;
        float* (*field)(DenoiserSettings&);
    };
    const Case cases[] = {
        {"sigma-color", [](DenoiserSettings& s) { return &s.edges.sigmaColor; }},
        {"sigma-normal", [](DenoiserSettings& s) { return &s.edges.sigmaNormal; }},
        {"sigma-plane", [](DenoiserSettings& s) { return &s.edges.sigmaPlane; }},
        {"sigma-coord", [](DenoiserSettings& s) { return &s.jbf.sigmaCoord; }},
        {"svgf-sigma-depth", [](DenoiserSettings& s) { return &s.svgf.sigmaDepth; }},
        {"svgf-sigma-normal", [](DenoiserSettings& s) { return &s.svgf.sigmaNormal; }},
        {"svgf-sigma-luminance", [](DenoiserSettings& s) { return &s.svgf.sigmaLuminance; }},
    };
    for (const Case& c : cases) {
        DenoiserSettings s;
        *c.field(s) = 1e-20f;
        try {
            validate(s);
            ADD_FAILURE() << c.name << " 1e-20 was accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(c.name), std::string::npos) << e.what();
        }
        for (Method method : kEveryMethod) {
            DenoiserSettings small = settingsFor(method);
            *c.field(small) = kMinSigma;
            ASSERT_NO_THROW(validate(small)) << c.name;
            Denoiser denoiser(small);
            Frame f = makeFrame(texturedScene());
            test::addNoise(f, 0.2f, 1u);
            Image out = denoiser.processFrame(f);
            ASSERT_EQ(nonFiniteCount(out), 0u) << c.name << " " << toString(method);
            const double input = meanOver(f.beauty, 0, 2, 32, 24);
            EXPECT_NEAR(meanOver(out, 0, 2, 32, 24), input, 0.05 * input)
                << c.name << " " << toString(method);
        }
    }
}

}  // namespace
}  // namespace rtd
