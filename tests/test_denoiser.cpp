// The Denoiser through its public API, on synthetic frames with known answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "devices/device.h"
#include "methods/method.h"
#include "test_support.h"
#include "tuning.h"

namespace rtd {
namespace {

using test::makeFrame;
using test::SceneDescription;

const Method kAllMethods[] = {Method::Jbf, Method::Atrous, Method::Temporal};

DenoiserSettings settingsFor(Method method, SpatialFilter filter = SpatialFilter::Atrous) {
    DenoiserSettings s = test::cpuSettings(method);
    s.temporal.spatialFilter = filter;
    s.jbf.radius = 6;  // small synthetic frames
    return s;
}

// Two flat walls meeting in a vertical line at x = 16, with different colours.
SceneDescription twoHalves() {
    SceneDescription d;
    d.colour = [](int x, int) {
        return x < 16 ? std::array<float, 3>{1.0f, 0.2f, 0.2f}
                      : std::array<float, 3>{0.2f, 0.2f, 1.0f};
    };
    return d;
}

float maxAbsDifference(const Image& a, const Image& b) {
    float m = 0.0f;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        m = std::max(m, std::abs(a.pixels[i] - b.pixels[i]));
    return m;
}

TEST(Denoiser, ConstantImageIsUnchangedByEveryMethod) {
    SceneDescription d;
    d.width = 40;
    d.height = 24;
    d.objectCount = 2;
    // Varied geometry: two objects at different depths, a tilted normal region, background.
    d.id = [](int x, int y) { return y < 2 ? -1 : (x < 20 ? 0 : 1); };
    d.depth = [](int x, int) { return x < 20 ? 4.0f : 6.0f; };
    d.colour = [](int, int) { return std::array<float, 3>{0.25f, 0.5f, 0.75f}; };
    Frame frame = makeFrame(d);
    for (Method method : kAllMethods)
        for (SpatialFilter filter : {SpatialFilter::Jbf, SpatialFilter::Atrous}) {
            Denoiser denoiser(settingsFor(method, filter));
            for (int i = 0; i < 3; ++i) {  // temporal: history too
                Image out = denoiser.processFrame(frame);
                EXPECT_LT(maxAbsDifference(out, frame.beauty), 1e-5f)
                    << toString(method) << "/" << toString(filter) << " frame " << i;
            }
        }
}

// Everything a denoiser holds on its device is allocated by the first frame: later frames of the
// same size allocate nothing (the CPU's A-Trous scratch included).
TEST(Denoiser, LaterFramesAllocateNothing) {
    SceneDescription d;
    d.width = 40;
    d.height = 24;
    Frame frame = makeFrame(d);
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf,
                          Method::Detail, Method::Learned})
        for (SpatialFilter filter : {SpatialFilter::Jbf, SpatialFilter::Atrous}) {
            Denoiser denoiser(settingsFor(method, filter));
            denoiser.processFrame(frame);
            const std::size_t first = denoiser.deviceMemoryBytes();
            EXPECT_GT(first, 0u);
            for (int i = 0; i < 2; ++i) {
                denoiser.processFrame(frame);
                EXPECT_EQ(denoiser.deviceMemoryBytes(), first)
                    << toString(method) << "/" << toString(filter) << " frame " << i + 2;
            }
        }
}

// Left and right halves differ in colour and in exactly one other way; the filtered left half
// must not pick up the right half's colour.
void expectEdgeKept(const SceneDescription& d, const char* what) {
    Frame frame = makeFrame(d);
    for (Method method : kAllMethods) {
        DenoiserSettings s = settingsFor(method);
        s.edges.sigmaColor = 100.0f;  // colour alone would not stop the blur
        Denoiser denoiser(s);
        Image out = denoiser.processFrame(frame);
        for (int y = 0; y < d.height; ++y) {
            EXPECT_NEAR(out.at(15, y, 2), 0.2f, 1e-3f) << what << ", " << toString(method);
            EXPECT_NEAR(out.at(16, y, 0), 0.2f, 1e-3f) << what << ", " << toString(method);
        }
    }
}

TEST(Denoiser, StepEdgeBetweenObjectIdsIsNotBlurred) {
    SceneDescription d = twoHalves();
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 16 ? 0 : 1; };
    expectEdgeKept(d, "object IDs");
}

TEST(Denoiser, StepEdgeBetweenNormalsIsNotBlurred) {
    SceneDescription d = twoHalves();
    d.normal = [](int x, int) {
        return x < 16 ? std::array<float, 3>{0.0f, 0.0f, -1.0f}
                      : std::array<float, 3>{-1.0f, 0.0f, 0.0f};
    };
    expectEdgeKept(d, "normals");
}

TEST(Denoiser, StepEdgeBetweenParallelPlanesIsNotBlurred) {
    SceneDescription d = twoHalves();
    d.depth = [](int x, int) { return x < 16 ? 4.0f : 5.0f; };  // same normal, 1 unit apart
    expectEdgeKept(d, "parallel planes");
}

TEST(Denoiser, WithoutObjectSeparationTheIdEdgeIsBlurred) {
    // The control for the ID test above: the same frame does blur when IDs are ignored.
    SceneDescription d = twoHalves();
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 16 ? 0 : 1; };
    DenoiserSettings s = settingsFor(Method::Jbf);
    s.edges.sigmaColor = 100.0f;
    s.edges.separateObjects = false;
    Denoiser denoiser(s);
    Image out = denoiser.processFrame(makeFrame(d));
    EXPECT_GT(out.at(15, 10, 2), 0.3f);
}

// Without object separation the filters' tap keys (GBufferView::filterKey) are 0 on every
// object and -1 on background: the two objects mix, the background beside them still does not.
TEST(Denoiser, WithoutObjectSeparationObjectsMixButBackgroundStaysOut) {
    SceneDescription d;
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 8 ? -1 : x < 16 ? 0 : 1; };
    d.colour = [](int x, int) {
        return x < 8    ? std::array<float, 3>{50.0f, 50.0f, 50.0f}
               : x < 16 ? std::array<float, 3>{1.0f, 0.2f, 0.2f}
                        : std::array<float, 3>{0.2f, 0.2f, 1.0f};
    };
    Frame frame = makeFrame(d);
    // The background's geometry as the objects' (one plane): only its ID can keep it out.
    SceneDescription plane = d;
    plane.id = [](int, int) { return 0; };
    Frame geometry = makeFrame(plane);
    frame.normal = geometry.normal;
    frame.position = geometry.position;
    frame.depth = geometry.depth;
    for (Method method : kAllMethods) {
        DenoiserSettings s = settingsFor(method);
        s.edges.sigmaColor = 100.0f;
        s.edges.separateObjects = false;
        // The filter alone: the energy restoration's tile gain would lift object 0 by the light
        // object 1's blue took from its tile.
        s.energy.keep = false;
        Denoiser denoiser(s);
        Image out = denoiser.processFrame(frame);
        for (int y = 0; y < d.height; ++y) {
            EXPECT_GT(out.at(15, y, 2), 0.3f) << toString(method);  // object 1 mixed in
            for (int c = 0; c < 3; ++c)  // no background (50) in object 0
                EXPECT_LT(out.at(8, y, c), 1.01f) << toString(method);
        }
    }
}

TEST(Denoiser, BackgroundPassesThrough) {
    SceneDescription d;
    d.id = [](int x, int) { return x < 8 ? -1 : 0; };
    d.colour = [](int x, int y) { return std::array<float, 3>{float(x % 3), float(y % 5), 0.5f}; };
    Frame frame = makeFrame(d);
    for (Method method : kAllMethods) {
        Denoiser denoiser(settingsFor(method));
        Image out = denoiser.processFrame(frame);
        for (int y = 0; y < d.height; ++y)
            for (int x = 0; x < 8; ++x)
                for (int c = 0; c < 3; ++c)
                    EXPECT_EQ(out.at(x, y, c), frame.beauty.at(x, y, c)) << toString(method);
    }
}

// The JBF formula evaluated directly, in double precision, with the standard library.
double referenceJbf(const Frame& f, int x, int y, int c, const DenoiserSettings& s) {
    auto at3 = [&](const Image& im, int px, int py) {
        return std::array<double, 3>{im.at(px, py, 0), im.at(px, py, 1), im.at(px, py, 2)};
    };
    int w = f.width(), h = f.height();
    int idI = f.objectId[std::size_t(y) * w + x];
    if (idI < 0) return f.beauty.at(x, y, c);
    auto ci = at3(f.beauty, x, y), ni = at3(f.normal, x, y), pi = at3(f.position, x, y);
    double sum = 0.0, sumW = 0.0;
    int r = s.jbf.radius;
    for (int py = std::max(0, y - r); py <= std::min(h - 1, y + r); ++py)
        for (int px = std::max(0, x - r); px <= std::min(w - 1, x + r); ++px) {
            if (f.objectId[std::size_t(py) * w + px] != idI) continue;
            auto cj = at3(f.beauty, px, py), nj = at3(f.normal, px, py),
                 pj = at3(f.position, px, py);
            double dc2 = 0, dot = 0, dp2 = 0, along = 0;
            for (int k = 0; k < 3; ++k) {
                dc2 += (ci[k] - cj[k]) * (ci[k] - cj[k]);
                dot += ni[k] * nj[k];
                dp2 += (pj[k] - pi[k]) * (pj[k] - pi[k]);
                along += ni[k] * (pj[k] - pi[k]);
            }
            double dNormal = std::acos(std::clamp(dot, -1.0, 1.0));
            double dPlane = dp2 > 0 ? along / std::sqrt(dp2) : 0.0;
            auto sq = [](double v) { return v * v; };
            double weight = std::exp(-(sq(px - x) + sq(py - y)) / (2 * sq(s.jbf.sigmaCoord)) -
                                     dc2 / (2 * sq(s.edges.sigmaColor)) -
                                     sq(dNormal) / (2 * sq(s.edges.sigmaNormal)) -
                                     sq(dPlane) / (2 * sq(s.edges.sigmaPlane)));
            sum += weight * cj[c];
            sumW += weight;
        }
    return sum / sumW;
}

TEST(Denoiser, JbfEqualsTheFormulaEvaluatedDirectly) {
    // A curved, noisy, multi-object scene so that every term matters.
    SceneDescription d;
    d.width = 48;
    d.height = 40;
    d.objectCount = 2;
    d.id = [](int x, int y) { return (x - 30) * (x - 30) + (y - 20) * (y - 20) < 100 ? 1 : 0; };
    d.depth = [](int x, int y) { return 4.0f + 0.02f * x + 0.01f * y * y / 40.0f; };
    d.normal = [](int x, int y) {
        float nx = 0.3f * std::sin(0.2f * x), ny = 0.2f * std::cos(0.15f * y);
        float len = std::sqrt(nx * nx + ny * ny + 1.0f);
        return std::array<float, 3>{nx / len, ny / len, -1.0f / len};
    };
    d.colour = [](int x, int y) {
        return std::array<float, 3>{0.5f + 0.4f * std::sin(0.7f * x), 0.4f, 0.3f + 0.01f * y};
    };
    Frame frame = makeFrame(d);
    test::addNoise(frame, 0.3f, 7);
    DenoiserSettings s = settingsFor(Method::Jbf);
    s.outlier.enabled = false;
    s.jbf.radius = 8;
    s.jbf.sigmaCoord = 4.0f;
    s.edges.sigmaNormal = 0.3f;
    s.edges.sigmaPlane = 0.3f;
    s.energy.keep = false;  // the filter alone
    Denoiser denoiser(s);
    Image out = denoiser.processFrame(frame);
    for (int y = 0; y < d.height; y += 3)
        for (int x = 0; x < d.width; x += 5)
            for (int c = 0; c < 3; ++c) {
                double expected = referenceJbf(frame, x, y, c, s);
                EXPECT_NEAR(out.at(x, y, c), expected, 1e-4 * std::max(1.0, std::abs(expected)))
                    << "pixel (" << x << ", " << y << ") channel " << c;
            }
}

// Temporal settings in which the output is exactly the reprojected history (alpha 0, no clamp,
// identity spatial filter): what the history holds shows where each pixel was sampled.
DenoiserSettings pureHistorySettings() {
    DenoiserSettings s = test::cpuSettings(Method::Temporal);
    s.temporal.spatialFilter = SpatialFilter::Jbf;
    s.jbf.radius = 0;
    s.outlier.enabled = false;
    s.temporal.alpha = 0.0f;
    s.temporal.clampK = 1e6f;
    s.energy.keep = false;  // its gain would scale the history's pixels
    return s;
}

std::array<float, 3> gradientColour(int x, int y) {
    return {float(x), float(y), float(x * 100 + y)};
}

TEST(Reprojection, EqualMatricesMapEveryPixelToItself) {
    SceneDescription d;
    d.depth = [](int x, int y) { return 3.0f + 0.05f * x + 0.03f * y; };
    d.colour = gradientColour;
    Frame frame = makeFrame(d);
    Denoiser denoiser(pureHistorySettings());
    Image first = denoiser.processFrame(frame);
    EXPECT_LT(maxAbsDifference(first, frame.beauty), 1e-3f);  // colours up to 3200
    Frame second = frame;
    // The current frame must not show (alpha 0); it varies so that the clamp window is wide.
    for (float& v : second.beauty.pixels) v = -v;
    Image out = denoiser.processFrame(second);
    EXPECT_LT(maxAbsDifference(out, frame.beauty), 1e-3f);
    Image debug = denoiser.reprojectionDebugImage();
    for (int y = 0; y < d.height; ++y)
        for (int x = 0; x < d.width; ++x) EXPECT_EQ(debug.at(x, y, 1), 1.0f);  // green: valid
}

TEST(Reprojection, KnownObjectTranslationFetchesTheShiftedPixel) {
    // Object 0 (x in [8, 20)) moves 3 pixels right over a static wall (object 1).
    const int shift = 3;
    const float z = 4.0f;
    auto scene = [&](int offset) {
        SceneDescription d;
        d.objectCount = 2;
        d.id = [offset](int x, int) { return x >= 8 + offset && x < 20 + offset ? 0 : 1; };
        d.depth = [z](int, int) { return z; };
        d.colour = gradientColour;
        return d;
    };
    Frame previous = makeFrame(scene(0));
    Frame current = makeFrame(scene(shift));
    current.objectToWorld[0] = test::translation(test::worldShiftForPixels(shift, z), 0, 0);
    Denoiser denoiser(pureHistorySettings());
    denoiser.processFrame(previous);
    Image out = denoiser.processFrame(current);
    Image debug = denoiser.reprojectionDebugImage();
    for (int y = 0; y < 32; ++y) {
        for (int x = 8 + shift; x < 20 + shift; ++x) {  // on the object: from x - shift
            EXPECT_NEAR(out.at(x, y, 0), float(x - shift), 1e-3f) << x << "," << y;
            EXPECT_EQ(debug.at(x, y, 1), 1.0f);
        }
        for (int x = 8; x < 8 + shift; ++x) {    // wall uncovered: last frame held the object
            EXPECT_EQ(debug.at(x, y, 0), 1.0f);  // yellow: other object
            EXPECT_EQ(debug.at(x, y, 1), 1.0f);
            EXPECT_EQ(debug.at(x, y, 2), 0.0f);
        }
    }
}

TEST(Reprojection, ObjectMovingOverBackgroundLeavesInvalidHistoryBehind) {
    // Object 0 over background moves 4 pixels left: the pixels it leaves are background now
    // (no history: blue), every pixel of the object finds itself in the last frame (green).
    const float z = 4.0f;
    auto scene = [&](int left) {
        SceneDescription d;
        d.id = [left](int x, int) { return x >= left && x < left + 10 ? 0 : -1; };
        d.depth = [z](int, int) { return z; };
        d.colour = gradientColour;
        return d;
    };
    Frame previous = makeFrame(scene(14));
    Frame current = makeFrame(scene(10));
    current.objectToWorld[0] = test::translation(test::worldShiftForPixels(-4, z), 0, 0);
    DenoiserSettings s = pureHistorySettings();
    Denoiser denoiser(s);
    denoiser.processFrame(previous);
    denoiser.processFrame(current);
    Image debug = denoiser.reprojectionDebugImage();
    for (int x = 20; x < 24; ++x) {  // uncovered: background now
        EXPECT_EQ(debug.at(x, 5, 2), 1.0f);
        EXPECT_EQ(debug.at(x, 5, 1), 0.0f);
    }
    for (int x = 10; x < 20; ++x) EXPECT_EQ(debug.at(x, 5, 1), 1.0f);  // object: valid
    // Outside the screen: shift the camera so that history falls off the left edge.
    Frame moved = current;
    moved.objectToWorld[0] = test::translation(test::worldShiftForPixels(-40, z), 0, 0);
    denoiser.processFrame(moved);
    debug = denoiser.reprojectionDebugImage();
    EXPECT_EQ(debug.at(12, 5, 0), 1.0f);  // red: outside the screen
    EXPECT_EQ(debug.at(12, 5, 1), 0.0f);
}

TEST(Denoiser, NonFiniteRadianceIsReplacedAndCounted) {
    SceneDescription d;
    Frame frame = makeFrame(d);
    frame.beauty.at(3, 4, 0) = std::nanf("");
    frame.beauty.at(5, 6, 1) = INFINITY;
    frame.beauty.at(7, 8, 2) = -INFINITY;
    for (Method method : kAllMethods) {
        Denoiser denoiser(settingsFor(method));
        Image out = denoiser.processFrame(frame);
        EXPECT_EQ(denoiser.lastFrameStats().nonFiniteReplaced, 3);
        for (float v : out.pixels) ASSERT_TRUE(std::isfinite(v)) << toString(method);
    }
}

// A renderer's G-buffer can hold NaN or Inf too (degenerate geometry). A pixel whose position or
// depth is not finite is taken as background: its radiance passes through, no filter or history
// test reads its geometry, so the result is the frame's with those pixels marked background, and
// finite over several frames.
TEST(Denoiser, NonFiniteGeometryMakesAPixelBackground) {
    SceneDescription d;
    d.colour = [](int x, int y) {
        return std::array<float, 3>{0.2f + 0.01f * float((x * 7 + y * 3) % 13), 0.4f, 0.3f};
    };
    const Frame clean = makeFrame(d);
    Frame broken = clean, background = clean;
    // (A non-finite normal leaves the pixel an object's, without a normal: test_bad_values.)
    const int pixels[4][2] = {{5, 6}, {12, 20}, {7, 8}, {20, 3}};
    broken.position.at(5, 6, 1) = std::nanf("");
    broken.position.at(12, 20, 0) = -INFINITY;
    broken.depth.at(7, 8, 0) = std::nanf("");
    broken.depth.at(20, 3, 0) = INFINITY;
    for (const auto& p : pixels) background.objectId[std::size_t(p[1]) * d.width + p[0]] = -1;
    for (Method method : kAllMethods) {
        Denoiser a(settingsFor(method)), b(settingsFor(method));
        for (int frame = 0; frame < 3; ++frame) {
            Image out = a.processFrame(broken), expected = b.processFrame(background);
            for (std::size_t k = 0; k < out.pixels.size(); ++k) {
                ASSERT_TRUE(std::isfinite(out.pixels[k])) << toString(method) << " " << frame;
                ASSERT_EQ(out.pixels[k], expected.pixels[k]) << toString(method) << " " << k;
            }
            for (const auto& p : pixels)
                for (int c = 0; c < 3; ++c)
                    EXPECT_EQ(out.at(p[0], p[1], c), clean.beauty.at(p[0], p[1], c));
        }
    }
}

TEST(Denoiser, InconsistentFramesAreRejectedWithAReason) {
    SceneDescription d;
    Frame good = makeFrame(d);
    Denoiser denoiser(settingsFor(Method::Temporal));
    Frame badSize = good;
    badSize.normal = Image(16, 16, 3);
    EXPECT_THROW(denoiser.processFrame(badSize), Error);
    Frame badId = good;
    badId.objectId[5] = 1;  // K = 1
    try {
        denoiser.processFrame(badId);
        FAIL() << "an ID outside 0..K-1 was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find("outside -1..0"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(denoiser.processFrame(good));
}

// The ingest finds a bad ID only after the frame's passes ran: the refused frame must still leave
// the history as it was, so the next frame's result is what it would have been without it.
TEST(Denoiser, ARefusedFrameLeavesTheHistoryAsItWas) {
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects", 48, 32, 3);
    Frame bad = frames[2];
    bad.objectId[40] = int(bad.objectToWorld.size());
    for (Method method : {Method::Temporal, Method::Svgf, Method::Detail}) {
        Denoiser plain(settingsFor(method)), interrupted(settingsFor(method));
        plain.processFrame(frames[0]);
        interrupted.processFrame(frames[0]);
        plain.processFrame(frames[1]);
        interrupted.processFrame(frames[1]);
        EXPECT_THROW(interrupted.processFrame(bad), Error);
        EXPECT_EQ(interrupted.processFrame(frames[2]).pixels, plain.processFrame(frames[2]).pixels)
            << toString(method);
    }
}

TEST(Denoiser, SettingsOutOfRangeAreRejected) {
    DenoiserSettings s = settingsFor(Method::Jbf);
    s.edges.sigmaColor = 0.0f;
    EXPECT_THROW(Denoiser{s}, Error);
    s = settingsFor(Method::Temporal);
    s.temporal.alpha = 1.5f;
    EXPECT_THROW(Denoiser{s}, Error);
}

TEST(Denoiser, PassesAreListedWithTheirBuffers) {
    Denoiser temporal(settingsFor(Method::Temporal));
    std::vector<std::string> names;
    for (const PassInfo& p : temporal.passes()) names.push_back(p.name);
    std::vector<std::string> expected{"ingest",  "energy-input", "outlier", "atrous0",  "atrous1",
                                      "atrous2", "atrous3",      "atrous4", "temporal", "energy"};
    EXPECT_EQ(names, expected);
    // The last level writes `filtered`, which the temporal stage reads with the last frame's
    // history; it writes this frame's history and the output, which the energy pass scales.
    EXPECT_EQ(temporal.passes()[7].outputs, (std::vector<std::string>{"filtered"}));
    const PassInfo& stage = temporal.passes()[8];
    for (const char* input : {"previous guide", "previous history", "matrices", "filtered"})
        EXPECT_NE(std::find(stage.inputs.begin(), stage.inputs.end(), input), stage.inputs.end())
            << input;
    EXPECT_EQ(stage.outputs,
              (std::vector<std::string>{"windowSums", "history", "validity", "output"}));
}

// A pass touches only what it declares: reading another resource, or a history's last copy it
// did not declare, is refused naming the pass and the resource.
TEST(Pipeline, APassCannotTouchWhatItDidNotDeclare) {
    std::unique_ptr<Device> device = createCpuDevice();
    Pipeline p;
    ResourceId a = p.declare(floatImage("a", 3));
    ResourceId h = p.declare(floatImage("h", 1, Lifetime::History));
    p.addPass("reads-a", StepKind::Modulate, {a}, {}, 0,
              [a](const PassContext& c) { c.planes(a); });
    p.addPass("reads-h", StepKind::Modulate, {h}, {}, 0,
              [h](const PassContext& c) { c.floats(previous(h)); });
    p.addPass("writes-output", StepKind::Modulate, {a}, {}, 0,
              [](const PassContext& c) { c.output(); });
    p.allocate(*device, 8, 4);
    FrameBinding frame;
    try {
        p.run(*device, frame);
        FAIL() << "reads-h read the last copy of h without declaring it";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  "pipeline: pass 'reads-h' reads 'previous h' without declaring it");
    }
    EXPECT_THROW(p.addPass("bad", StepKind::Modulate, {previous(a)}, {}, 0, {}), Error);
    Pipeline q;
    ResourceId b = q.declare(floatImage("b", 3));
    q.addPass("writes-output", StepKind::Modulate, {b}, {}, 0,
              [](const PassContext& c) { c.output(); });
    q.allocate(*device, 8, 4);
    EXPECT_THROW(q.run(*device, frame), Error);
    // ...and reads a resource as its own element type only.
    Pipeline t;
    ResourceId ids = t.declare({.name = "ids", .element = Element::Int32});
    t.addPass("ids-as-floats", StepKind::Modulate, {ids}, {}, 0,
              [ids](const PassContext& c) { c.floats(ids); });
    t.allocate(*device, 8, 4);
    EXPECT_THROW(t.run(*device, frame), Error);
    // The border covers the widest reach, rounded to whole cache lines.
    Pipeline r;
    r.addPass("wide", StepKind::Modulate, {}, {}, 17, [](const PassContext&) {});
    r.allocate(*device, 8, 4);
    EXPECT_EQ(r.layout().padding, 32);
}

// The firefly removal as one tile pass gives the separate passes' frames (every method, over
// frames where history builds up), and replaces their passes in the list: SVGF's history-clamp
// row sums come from it too.
TEST(Denoiser, TilePassesGiveTheSeparatePassesResult) {
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects", 70, 45, 3);
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        DenoiserSettings s = settingsFor(method);
        Denoiser separate = makeTunedDenoiser(s, {CpuIsa::Auto, TilePasses::Off});
        Denoiser tiled = makeTunedDenoiser(s, {CpuIsa::Auto, TilePasses::On});
        for (std::size_t i = 0; i < frames.size(); ++i) {
            Image a = separate.processFrame(frames[i]), b = tiled.processFrame(frames[i]);
            EXPECT_LE(test::maxRelativeDifference(a, b), 1e-5)
                << toString(method) << ", frame " << i;
        }
    }
    // A window wider than the tile's runs as separate passes, with the same result.
    std::vector<Frame> two(frames.begin(), frames.begin() + 2);
    DenoiserSettings s = settingsFor(Method::Svgf);
    s.outlier.radius = 4;
    Denoiser separate = makeTunedDenoiser(s, {CpuIsa::Auto, TilePasses::Off});
    Denoiser tiled = makeTunedDenoiser(s, {CpuIsa::Auto, TilePasses::On});
    for (const Frame& f : two)
        EXPECT_EQ(test::maxRelativeDifference(separate.processFrame(f), tiled.processFrame(f)),
                  0.0);
}

}  // namespace
}  // namespace rtd

namespace rtd {
namespace {

TEST(FrameViewApi, CallerOwnedHostBuffersGiveTheSameResult) {
    test::SceneDescription d;
    d.objectCount = 2;
    d.id = [](int x, int) { return x < 12 ? 0 : 1; };
    d.colour = [](int x, int y) { return std::array<float, 3>{0.1f * (x % 5), 0.3f, 0.02f * y}; };
    Frame frame = test::makeFrame(d);
    test::addNoise(frame, 0.2f, 5);
    for (Method method : {Method::Temporal, Method::Svgf}) {
        Denoiser a(test::cpuSettings(method)), b(test::cpuSettings(method));
        std::vector<float> out(frame.beauty.pixels.size());
        for (int i = 0; i < 2; ++i) {
            Image expected = a.processFrame(frame);
            b.processFrame(viewOf(frame), out.data());
            EXPECT_EQ(out, expected.pixels) << toString(method) << " frame " << i;
        }
    }
}

TEST(FrameViewApi, BadViewsAreRejected) {
    test::SceneDescription d;
    Frame frame = test::makeFrame(d);
    Denoiser denoiser(test::cpuSettings(Method::Atrous));
    std::vector<float> out(frame.beauty.pixels.size());
    FrameView onDevice = viewOf(frame);
    onDevice.space = MemorySpace::Device;  // a CPU denoiser cannot read GPU memory
    try {
        denoiser.processFrame(onDevice, out.data());
        FAIL() << "device memory accepted by a CPU denoiser";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
        EXPECT_NE(std::string(e.what()).find("GPU device"), std::string::npos) << e.what();
    }
    FrameView missing = viewOf(frame);
    missing.normal = nullptr;
    EXPECT_THROW(denoiser.processFrame(missing, out.data()), Error);
    FrameView badIds = viewOf(frame);
    badIds.objectCount = 0;  // every pixel holds ID 0
    EXPECT_THROW(denoiser.processFrame(badIds, out.data()), Error);
    EXPECT_NO_THROW(denoiser.processFrame(viewOf(frame), out.data()));
}

}  // namespace
}  // namespace rtd

namespace rtd {
namespace {

// A frame's result does not depend on which of the two history copies the frame lands in: after
// reset() (history forgotten) the same frames give the same results, bit for bit, whether the
// pipeline starts on its first copy or its second. Before the methods were declarations, SVGF
// with its feedback iteration last modulated the first copy on every frame (odd frames repeated
// the previous frame's result).
TEST(Denoiser, ResultsDoNotDependOnTheHistoryCopyInUse) {
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects", 40, 30, 3);
    DenoiserSettings feedbackLast = settingsFor(Method::Svgf);
    feedbackLast.svgf.feedbackIteration = feedbackLast.svgf.iterations - 1;
    std::vector<DenoiserSettings> cases = {settingsFor(Method::Temporal), settingsFor(Method::Svgf),
                                           feedbackLast};
    for (const DenoiserSettings& s : cases) {
        Denoiser even(s), odd(s);
        odd.processFrame(frames.back());
        odd.reset();
        for (std::size_t i = 0; i < frames.size(); ++i)
            EXPECT_EQ(test::maxRelativeDifference(even.processFrame(frames[i]),
                                                  odd.processFrame(frames[i])),
                      0.0)
                << toString(s.method) << " feedback " << s.svgf.feedbackIteration << ", frame "
                << i;
    }
}

}  // namespace
}  // namespace rtd
