// What renderers hand the denoiser: motion vectors instead of matrices, and buffers in other
// layouts (half, RGBA, strides, float IDs, ray distances), each against the packed float path.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/math.h"
#include "input_helpers.h"
#include "kernels/convert.h"
#include "metrics/metrics.h"
#include "render/render_sequence.h"
#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"
#include "test_support.h"
#include "tuning.h"

namespace rtd {
namespace {

using test::halfRounded;
using test::motionFromMatrices;
using test::strided;
using test::Strided;
using test::toMat4;
using test::withMotion;

const std::vector<Frame>& cameraPanFrames() {
    static const std::vector<Frame> frames = test::renderSmallSequence("camera-pan", 96, 64, 4);
    return frames;
}

// NRD's convention, previous = current + motion: with the motion the matrices imply (camera
// motion here; the objects do not rotate), every temporal method gives the matrix path's result.
// Frame 1 is refused, by the sequence check of 2 frames and by reading it, with `message`.
void expectRefusedWhenReadAndChecked(const Sequence& sequence, const std::string& message) {
    for (int pass = 0; pass < 2; ++pass) {
        try {
            if (pass == 0)
                sequence.checkFrames(2);
            else
                sequence.readFrame(1);
            ADD_FAILURE() << "accepted frame 1, expected: " << message;
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    }
}

// Writes frame 1's `file` as RGB (R varied, G 1) and reads frame 1 back: a 1-channel input
// takes the file's R channel.
Frame expectRedChannelRead(const Sequence& sequence, const std::filesystem::path& file,
                           std::optional<Image> Frame::*input) {
    const Frame base = sequence.readFrame(0);
    Image rgb(base.width(), base.height(), 3, 0.0f);
    for (std::size_t p = 0; p < rgb.pixelCount(); ++p) {
        rgb.pixels[3 * p] = float(p % 7) / 7.0f;
        rgb.pixels[3 * p + 1] = 1.0f;
    }
    writeExr(file, rgb);
    Frame read = sequence.readFrame(1);
    EXPECT_TRUE((read.*input).has_value());
    if (!(read.*input)) return read;
    EXPECT_EQ((read.*input)->channels, 1);
    for (std::size_t p = 0; p < rgb.pixelCount(); ++p)
        EXPECT_EQ((read.*input)->pixels[p], rgb.pixels[3 * p]) << p;
    return read;
}

TEST(MotionVectors, FromTheMatricesGiveTheMatrixPathsResult) {
    const std::vector<Frame>& frames = cameraPanFrames();
    std::vector<Frame> moving = withMotion(frames);
    // The scalar kernels round as this file does (no fused multiply-adds): within 1e-4 (6.8e-5
    // measured). The vector kernels fuse the matrix product, which moves the previous pixel by an
    // ulp more (1.16e-4 at one value in a debug build): 1e-3 there.
    // (The single-frame methods ignore the motion: the same result too.)
    for (auto [isa, tolerance] : {std::pair{CpuIsa::Scalar, 1e-4}, std::pair{CpuIsa::Auto, 1e-3}})
        for (Method method :
             {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf, Method::Detail}) {
            const DenoiserSettings s = test::cpuSettings(method);
            Denoiser matrices = makeTunedDenoiser(s, {isa, TilePasses::Auto});
            Denoiser motion = makeTunedDenoiser(s, {isa, TilePasses::Auto});
            for (std::size_t i = 0; i < frames.size(); ++i) {
                Image expected = matrices.processFrame(frames[i]);
                Image got = motion.processFrame(moving[i]);
                EXPECT_LE(test::maxRelativeDifference(expected, got), tolerance)
                    << toString(method) << " " << toString(isa) << " frame " << i;
            }
        }
}

// Other conventions through the settings: UV units (scale by the size), y up (negative scale),
// current - previous (the flag): each gives the pixel convention's result.
TEST(MotionVectors, ScaleAndSignSettingsCoverOtherConventions) {
    const std::vector<Frame>& frames = cameraPanFrames();
    std::vector<Frame> pixels = withMotion(frames);
    const float w = float(frames[0].width()), h = float(frames[0].height());
    std::vector<Frame> uvUp = pixels, reversed = pixels;
    for (std::size_t i = 0; i < frames.size(); ++i)
        for (std::size_t p = 0; p < pixels[i].motion->pixelCount(); ++p) {
            float* uv = &uvUp[i].motion->pixels[3 * p];
            uv[0] /= w;
            uv[1] /= -h;
            float* back = &reversed[i].motion->pixels[3 * p];
            for (int c = 0; c < 3; ++c) back[c] = -back[c];
        }
    DenoiserSettings s = test::cpuSettings(Method::Svgf);
    DenoiserSettings uvSettings = s, reversedSettings = s;
    uvSettings.motion.scaleX = w;
    uvSettings.motion.scaleY = -h;
    reversedSettings.motion.currentMinusPrevious = true;
    Denoiser a(s), b(uvSettings), c(reversedSettings);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        Image expected = a.processFrame(pixels[i]);
        EXPECT_LE(test::maxRelativeDifference(expected, b.processFrame(uvUp[i])), 1e-4) << i;
        EXPECT_LE(test::maxRelativeDifference(expected, c.processFrame(reversed[i])), 1e-6) << i;
    }
}

// A sign flipped by mistake (the vectors read as current - previous) is caught by the quality it
// costs against a converged reference, and 2-channel motion (no depth change) costs little.
TEST(MotionVectors, AFlippedSignMeasuresWorse) {
    test::TempFolder dir("motion-sign");
    render::RenderSettings r;
    r.width = 96;
    r.height = 64;
    r.frames = 8;
    r.referenceSpp = 64;
    render::renderSequence("camera-pan", r, dir.path());
    Sequence sequence(dir.path());
    std::vector<Frame> frames;
    for (int i = 0; i < sequence.frameCount(); ++i) frames.push_back(sequence.readFrame(i));
    std::vector<Frame> moving = withMotion(frames), flat = withMotion(frames, 2);
    // The temporal method: its result leans on the history most (SVGF's spatial filter hides
    // much of a misplaced history on this scene, docs/inputs.md).
    DenoiserSettings s = test::cpuSettings(Method::Temporal), flipped = s;
    flipped.motion.currentMinusPrevious = true;
    Denoiser right(s), wrong(flipped), twoChannels(s);
    double rightError = 0, wrongError = 0, twoChannelError = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        Image reference = readExr(dir.path() / "reference" / fmt::format("reference_{}.exr", i),
                                  {{"R"}, {"G"}, {"B"}});
        rightError += metrics::relMse(right.processFrame(moving[i]), reference);
        wrongError += metrics::relMse(wrong.processFrame(moving[i]), reference);
        twoChannelError += metrics::relMse(twoChannels.processFrame(flat[i]), reference);
    }
    EXPECT_GT(wrongError, 1.2 * rightError) << rightError << " vs " << wrongError;
    EXPECT_LT(twoChannelError, 1.05 * rightError) << rightError << " vs " << twoChannelError;
}

// ---- buffer layouts ----

TEST(Half, ConversionRoundsToNearestEvenAndKeepsSpecialValues) {
    EXPECT_EQ(floatToHalf(1.0f), 0x3c00);
    EXPECT_EQ(floatToHalf(-2.0f), 0xc000);
    EXPECT_EQ(floatToHalf(65504.0f), 0x7bff);
    EXPECT_EQ(floatToHalf(65520.0f), 0x7c00);               // rounds past the largest: infinity
    EXPECT_EQ(floatToHalf(1.0f + 1.0f / 2048.0f), 0x3c00);  // a tie: to even
    EXPECT_EQ(floatToHalf(1.0f + 3.0f / 2048.0f), 0x3c02);  // a tie: to even (up)
    EXPECT_EQ(floatToHalf(5.9604645e-8f), 0x0001);          // the smallest subnormal
    EXPECT_EQ(floatToHalf(1e-9f), 0x0000);
    EXPECT_TRUE(std::isnan(halfToFloat(floatToHalf(NAN))));
    EXPECT_EQ(halfToFloat(0x7c00), INFINITY);
    EXPECT_EQ(halfToFloat(0x0001), 5.9604645e-8f);
    EXPECT_EQ(halfToFloat(0x3555), 0.333251953125f);
    // Every finite half survives the round trip.
    for (std::uint32_t h = 0; h < 0x10000; ++h)
        if ((h & 0x7c00) != 0x7c00) EXPECT_EQ(floatToHalf(halfToFloat(std::uint16_t(h))), h);
}

// RGBA half buffers with pixel and row padding, float IDs, float RGBA, strided motion: each gives
// the result of the packed float path on the same values (the half ones rounded), bit for bit.
TEST(FrameLayouts, EachFormatGivesThePackedFloatResult) {
    // With 2-channel motion vectors in place of the matrices, as an engine passes them.
    const std::vector<Frame> frames = withMotion(cameraPanFrames(), 2);
    const int w = frames[0].width(), h = frames[0].height();
    for (DataType type : {DataType::Float32, DataType::Float16}) {
        Denoiser packed(test::cpuSettings(Method::Svgf)), laidOut(test::cpuSettings(Method::Svgf));
        for (const Frame& original : frames) {
            Frame f = original;
            if (type == DataType::Float16)
                for (Image* image : {&f.beauty, &f.normal, &f.position, &f.depth, &*f.motion})
                    image->pixels = halfRounded(image->pixels);
            f.albedo = f.beauty;  // any positive image: the demodulation path runs
            for (float& v : f.albedo->pixels) v = 0.25f + 0.5f * std::fabs(v) / (1.0f + v);
            if (type == DataType::Float16) f.albedo->pixels = halfRounded(f.albedo->pixels);
            Image expected = packed.processFrame(f);

            Strided beauty = strided(f.beauty.pixels, w, h, 3, type, 4, 0, 32);
            Strided normal = strided(f.normal.pixels, w, h, 3, type, 4, 4, 0);
            Strided position = strided(f.position.pixels, w, h, 3, type, 3, 2, 6);
            Strided depth = strided(f.depth.pixels, w, h, 1, type, 1, 0, 0);
            Strided albedo = strided(f.albedo->pixels, w, h, 3, type, 4, 0, 0);
            std::vector<float> ids(f.objectId.begin(), f.objectId.end());
            Strided idFloats = strided(ids, w, h, 1, DataType::Float32, 1, 4, 0);
            Strided motion = strided(f.motion->pixels, w, h, 2, type, 2, 4, 8);
            FrameView v = viewOf(f);
            v.motion = motion.view;
            v.beauty = beauty.view;
            v.normal = normal.view;
            v.position = position.view;
            v.depth = depth.view;
            v.albedo = albedo.view;
            v.objectId = idFloats.view;
            std::vector<float> got(3 * std::size_t(w) * h);
            laidOut.processFrame(v, got.data());
            EXPECT_EQ(got, expected.pixels) << (type == DataType::Float16 ? "half" : "float");
        }
    }
}

// The result in half RGBA with a row pitch, or in RGB floats inside RGBA pixels (the caller's
// alpha kept): the float result, rounded where half, the padding untouched.
TEST(FrameLayouts, OutputsInOtherLayouts) {
    const Frame& f = cameraPanFrames()[0];
    const int w = f.width(), h = f.height();
    Denoiser a(test::cpuSettings(Method::Atrous));
    Image expected = a.processFrame(f);
    const std::size_t halfRow = w * 8 + 16;
    std::vector<unsigned char> half(halfRow * h, 0xCD);
    OutputView halfOut{half.data(), DataType::Float16, 4, 8, halfRow};
    a.processFrame(viewOf(f), halfOut);
    std::vector<float> rgba(4 * std::size_t(w) * h, -3.0f);
    OutputView keepAlpha{rgba.data(), DataType::Float32, 3, 16, 0};
    a.processFrame(viewOf(f), keepAlpha);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            for (int c = 0; c < 4; ++c) {
                std::uint16_t v;
                std::memcpy(&v, &half[y * halfRow + x * 8 + 2 * c], 2);
                float want = c < 3 ? expected.at(x, y, c) : 1.0f;
                ASSERT_EQ(v, floatToHalf(want)) << x << "," << y << "," << c;
                float got = rgba[(std::size_t(y) * w + x) * 4 + c];
                ASSERT_EQ(got, c < 3 ? expected.at(x, y, c) : -3.0f) << x << "," << y;
            }
        }
        for (std::size_t b = w * 8; b < halfRow; ++b) ASSERT_EQ(half[y * halfRow + b], 0xCD);
    }
}

// A depth given as distance along the ray gives, with matrices, the view depth's result (the
// view depth then comes from the position).
TEST(FrameLayouts, RayDistanceDepthGivesTheViewDepthResult) {
    const std::vector<Frame>& frames = cameraPanFrames();
    Denoiser viewZ(test::cpuSettings(Method::Svgf)), ray(test::cpuSettings(Method::Svgf));
    for (const Frame& f : frames) {
        Mat4 cameraToWorld;
        ASSERT_TRUE(invert(toMat4(f.worldToCamera), cameraToWorld));
        Float3 eye = make3(cameraToWorld.m[0][3], cameraToWorld.m[1][3], cameraToWorld.m[2][3]);
        Frame g = f;
        g.depthKind = DepthKind::RayDistance;
        for (int y = 0; y < f.height(); ++y)
            for (int x = 0; x < f.width(); ++x) {
                Float3 p =
                    make3(f.position.at(x, y, 0), f.position.at(x, y, 1), f.position.at(x, y, 2));
                Float3 d = p - eye;
                if (f.depth.at(x, y) > 0.0f) g.depth.at(x, y) = std::sqrt(dot(d, d));
            }
        EXPECT_LE(test::maxRelativeDifference(viewZ.processFrame(f), ray.processFrame(g)), 1e-3);
    }
}

TEST(FrameLayouts, BadLayoutsAreRefusedNamingTheBuffer) {
    const Frame& f = cameraPanFrames()[0];
    Denoiser d(test::cpuSettings(Method::Svgf));
    std::vector<float> out(3 * f.beauty.pixelCount());
    auto refused = [&](FrameView v, const std::string& what, OutputView o = {}) {
        if (!o.data) o.data = out.data();
        try {
            d.processFrame(v, o);
            ADD_FAILURE() << "accepted: " << what;
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    FrameView v = viewOf(f);
    v.beauty = ImageView(f.beauty.pixels.data(), DataType::Int32, 3);
    refused(v, "beauty");
    v = viewOf(f);
    v.normal = ImageView(f.normal.pixels.data(), DataType::Float32, 2);
    refused(v, "normal has 2 channels");
    v = viewOf(f);
    v.position = ImageView(f.position.pixels.data(), DataType::Float32, 3, 8);
    refused(v, "position: strides");
    v = viewOf(f);
    v.depth = nullptr;
    refused(v, "depth buffer is missing");
    v = viewOf(f);
    v.motion = ImageView(f.depth.pixels.data(), DataType::Float32, 1);
    refused(v, "motion has 1 channels");
    refused(viewOf(f), "output must be", OutputView{out.data(), DataType::Int32, 3});
    refused(viewOf(f), "output must be", OutputView{out.data(), DataType::Float32, 2});
    v = viewOf(f);
    v.objectToWorld = nullptr;  // neither matrices nor motion
    refused(v, "objectToWorld is missing");
    std::vector<float> ids(f.objectId.begin(), f.objectId.end());
    ids[5 * f.width() + 3] = 0.5f;
    v = viewOf(f);
    v.objectId = ids.data();
    refused(v, "object ID at pixel (3, 5) is not an integer");
    // Still usable after every refusal.
    EXPECT_NO_THROW(d.processFrame(viewOf(f), out.data()));
}

// Non-finite motion means no history there (a first-frame pixel), never a NaN in the result.
TEST(MotionVectors, NonFiniteMotionGivesAFiniteResult) {
    std::vector<Frame> frames = withMotion(cameraPanFrames());
    for (Frame& f : frames)
        for (std::size_t p = 0; p < f.motion->pixelCount(); p += 7)
            f.motion->pixels[3 * p + p % 3] = p % 2 ? NAN : INFINITY;
    for (Method method : {Method::Temporal, Method::Svgf, Method::Detail}) {
        Denoiser d(test::cpuSettings(method));
        for (const Frame& f : frames)
            for (float v : d.processFrame(f).pixels) ASSERT_TRUE(std::isfinite(v));
    }
}

// The optional history confidence: the wrong size, channel count or type is refused naming it.
TEST(Confidence, AWrongSizeOrLayoutIsRefusedNamingIt) {
    const Frame& good = cameraPanFrames()[0];
    const int w = good.width(), h = good.height();
    for (Method method : {Method::Atrous, Method::Svgf}) {
        Denoiser d(test::cpuSettings(method));
        Frame f = good;
        f.confidence = Image(w - 1, h, 1, 1.0f);
        try {
            d.processFrame(f);
            ADD_FAILURE() << "accepted a confidence of the wrong size";
        } catch (const Error& e) {
            EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
            EXPECT_NE(std::string(e.what()).find(
                          fmt::format("confidence is {}x{}x1 ({} values), expected {}x{}x1", w - 1,
                                      h, (w - 1) * h, w, h)),
                      std::string::npos)
                << e.what();
        }
        f.confidence = Image(w, h, 3, 1.0f);
        EXPECT_THROW(d.processFrame(f), Error);
    }
    Denoiser d(test::cpuSettings(Method::Svgf));
    std::vector<float> out(3 * good.beauty.pixelCount());
    std::vector<std::int32_t> ids(good.beauty.pixelCount(), 0);
    FrameView v = viewOf(good);
    v.confidence = ImageView(ids.data(), DataType::Int32, 1);
    try {
        d.processFrame(v, out.data());
        ADD_FAILURE() << "accepted int32 confidence";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("confidence: int32 values are for object IDs only"),
                  std::string::npos)
            << e.what();
    }
    // Still usable; a confidence of the right size is taken by every method.
    Frame f = good;
    f.confidence = Image(w, h, 1, 0.5f);
    EXPECT_NO_THROW(d.processFrame(f));
    EXPECT_NO_THROW(Denoiser(test::cpuSettings(Method::Jbf)).processFrame(f));
}

// What the kernels read of it: clamped to [0, 1], NaN as 1 (as none), 1 where none is given.
TEST(Confidence, KernelsReadItClampedWithNaNAsOne) {
    const float values[] = {0.3f, -0.5f, 1.5f, NAN, -INFINITY, INFINITY, 0.0f, 1.0f};
    const float expected[] = {0.3f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f};
    InputSpan span{reinterpret_cast<const unsigned char*>(values), kSpanFloat32, 1, 4, 32};
    for (int x = 0; x < 8; ++x) EXPECT_EQ(loadConfidence(span, x, 0), expected[x]) << x;
    std::uint16_t halves[2] = {floatToHalf(0.25f), floatToHalf(2.0f)};
    InputSpan halfSpan{reinterpret_cast<const unsigned char*>(halves), kSpanFloat16, 1, 2, 4};
    EXPECT_EQ(loadConfidence(halfSpan, 0, 0), 0.25f);
    EXPECT_EQ(loadConfidence(halfSpan, 1, 0), 1.0f);
    EXPECT_EQ(loadConfidence(InputSpan{}, 3, 7), 1.0f);
}

// A folder with confidence_<i>.exr: read with its frame (1 channel; an RGB file's R), and a file
// of another size is refused naming it, by checkFrames before any pixel and by readFrame.
TEST(Confidence, SequenceFoldersReadConfidenceFiles) {
    test::TempFolder dir("confidence-sequence");
    render::RenderSettings r;
    r.width = 30;
    r.height = 21;
    r.frames = 2;
    r.gbufferOnly = true;
    r.confidence = true;
    render::renderSequence("switching-light", r, dir.path());
    ASSERT_TRUE(std::filesystem::exists(dir.path() / "confidence_1.exr"));
    Sequence sequence(dir.path());
    Frame first = sequence.readFrame(0);
    ASSERT_TRUE(first.confidence.has_value());
    EXPECT_EQ(first.confidence->width, 30);
    EXPECT_EQ(first.confidence->height, 21);
    EXPECT_EQ(first.confidence->channels, 1);
    for (float v : first.confidence->pixels) EXPECT_EQ(v, 1.0f);  // frame 0: no history to doubt
    // An RGB file: its R channel.
    Frame second =
        expectRedChannelRead(sequence, dir.path() / "confidence_1.exr", &Frame::confidence);
    // A denoiser takes the frames as read.
    Denoiser d(test::cpuSettings(Method::Svgf));
    EXPECT_NO_THROW(d.processFrame(first));
    EXPECT_NO_THROW(d.processFrame(second));
    // Another size.
    writeExr(dir.path() / "confidence_1.exr", Image(29, 21, 1, 1.0f));
    const std::string name = (dir.path() / "confidence_1.exr").string();
    expectRefusedWhenReadAndChecked(sequence, name + ": 29x21, but ");
    // Without --confidence a new render leaves none of the old files to be read as its own.
    r.confidence = false;
    render::renderSequence("switching-light", r, dir.path());
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "confidence_0.exr"));
    EXPECT_FALSE(Sequence(dir.path()).readFrame(0).confidence.has_value());
}

// ---- the split signal (specular, roughness, hit distance: read by method detail only) ----

// A frame with a split signal of the frame's size: specular a part of beauty, varied values.
Frame withSplitSignal(const Frame& frame, bool hitDistance = true) {
    Frame f = frame;
    const int w = f.width(), h = f.height();
    f.specular = Image(w, h, 3);
    f.roughness = Image(w, h, 1);
    for (std::size_t p = 0; p < f.beauty.pixelCount(); ++p) {
        for (int c = 0; c < 3; ++c)
            f.specular->pixels[3 * p + c] = 0.25f * f.beauty.pixels[3 * p + c];
        f.roughness->pixels[p] = float(p % 11) / 10.0f;
    }
    if (hitDistance) {
        f.hitDistance = Image(w, h, 1);
        for (std::size_t p = 0; p < f.beauty.pixelCount(); ++p)
            f.hitDistance->pixels[p] = p % 5 == 0 ? 0.0f : 0.5f + float(p % 13);
    }
    return f;
}

void expectRefused(Denoiser& d, const Frame& f, const std::string& message) {
    try {
        d.processFrame(f);
        ADD_FAILURE() << "accepted a frame that should fail with: " << message;
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
}

void expectRefused(Denoiser& d, const FrameView& v, const std::string& message) {
    std::vector<float> out(3 * std::size_t(v.width) * v.height);
    try {
        d.processFrame(v, out.data());
        ADD_FAILURE() << "accepted a view that should fail with: " << message;
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
        EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
}

// Detail takes the split signal, with and without the hit distance; a finite result.
TEST(SplitSignal, DetailTakesItWithAFiniteResult) {
    for (bool hitDistance : {true, false}) {
        Denoiser d(test::cpuSettings(Method::Detail));
        for (const Frame& frame : cameraPanFrames()) {
            const Frame f = withSplitSignal(frame, hitDistance);
            Image out;
            ASSERT_NO_THROW(out = d.processFrame(f)) << hitDistance;
            for (float v : out.pixels) ASSERT_TRUE(std::isfinite(v));
            // A view of it too (half roughness, RGBA specular).
            const std::size_t n = f.beauty.pixelCount();
            std::vector<float> rgba(4 * n, 1.0f);
            std::vector<std::uint16_t> halfRoughness(n);
            for (std::size_t p = 0; p < n; ++p) {
                for (int c = 0; c < 3; ++c) rgba[4 * p + c] = f.specular->pixels[3 * p + c];
                halfRoughness[p] = floatToHalf(f.roughness->pixels[p]);
            }
            FrameView v = viewOf(f);
            v.specular = ImageView(rgba.data(), DataType::Float32, 4);
            v.roughness = ImageView(halfRoughness.data(), DataType::Float16, 1);
            std::vector<float> viewOut(3 * n);
            ASSERT_NO_THROW(d.processFrame(v, viewOut.data()));
            for (float value : viewOut) ASSERT_TRUE(std::isfinite(value));
        }
    }
}

// The other methods ignore it (as they ignore the inputs they do not read): the same result.
TEST(SplitSignal, OtherMethodsIgnoreIt) {
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        Denoiser plain(test::cpuSettings(method)), split(test::cpuSettings(method));
        for (const Frame& frame : cameraPanFrames())
            EXPECT_EQ(plain.processFrame(frame).pixels,
                      split.processFrame(withSplitSignal(frame)).pixels)
                << toString(method);
    }
}

// Roughness and the hit distance go with specular, and specular needs roughness: each missing
// partner is refused naming both, for a Frame and a FrameView, by every method.
TEST(SplitSignal, AMissingPartnerIsRefusedNamingIt) {
    const Frame good = withSplitSignal(cameraPanFrames()[0]);
    for (Method method : {Method::Detail, Method::Svgf}) {
        Denoiser d(test::cpuSettings(method));
        Frame f = good;
        f.roughness.reset();
        expectRefused(d, f, "specular is given without roughness");
        expectRefused(d, viewOf(f), "specular is given without roughness");
        f = good;
        f.specular.reset();
        f.hitDistance.reset();
        expectRefused(d, f, "roughness is given without specular");
        expectRefused(d, viewOf(f), "roughness is given without specular");
        f = good;
        f.specular.reset();
        f.roughness.reset();
        expectRefused(d, f, "hitDistance is given without specular");
        expectRefused(d, viewOf(f), "hitDistance is given without specular");
        // Still usable.
        EXPECT_NO_THROW(d.processFrame(good)) << toString(method);
    }
}

// The wrong size, channel count or type is refused naming the input.
TEST(SplitSignal, AWrongSizeOrLayoutIsRefusedNamingIt) {
    const Frame good = withSplitSignal(cameraPanFrames()[0]);
    const int w = good.width(), h = good.height();
    Denoiser d(test::cpuSettings(Method::Detail));
    Frame f = good;
    f.specular = Image(w, h - 1, 3, 0.0f);
    expectRefused(d, f,
                  fmt::format("specular is {}x{}x3 ({} values), expected {}x{}x3", w, h - 1,
                              w * (h - 1) * 3, w, h));
    f = good;
    f.roughness = Image(w, h, 3, 0.5f);
    expectRefused(d, f, "roughness is");
    f = good;
    f.hitDistance = Image(w - 1, h, 1, 1.0f);
    expectRefused(d, f, "hitDistance is");
    FrameView v = viewOf(good);
    v.specular = ImageView(good.roughness->pixels.data(), DataType::Float32, 1);
    expectRefused(d, v, "specular has 1 channels, expected 3 to 4");
    std::vector<std::int32_t> ids(good.beauty.pixelCount(), 0);
    v = viewOf(good);
    v.hitDistance = ImageView(ids.data(), DataType::Int32, 1);
    expectRefused(d, v, "hitDistance: int32 values are for object IDs only");
    EXPECT_NO_THROW(d.processFrame(good));
}

// A folder with specular_<i>.exr, roughness_<i>.exr and hit_distance_<i>.exr: written by
// writeFrame when the frame has them, read with their frame (roughness and hit distance 1
// channel; an RGB file's R), and a file of another size is refused naming it, by checkFrames
// before any pixel and by readFrame.
TEST(SplitSignal, SequenceFoldersReadTheSplitSignalFiles) {
    test::TempFolder dir("split-sequence");
    const std::vector<Frame>& frames = cameraPanFrames();
    std::vector<Frame> written;
    for (int i = 0; i < 2; ++i) {
        written.push_back(withSplitSignal(frames[std::size_t(i)]));
        writeFrame(dir.path(), i, written.back());
    }
    for (const char* stem : {"specular", "roughness", "hit_distance"})
        ASSERT_TRUE(std::filesystem::exists(dir.path() / fmt::format("{}_1.exr", stem))) << stem;
    Sequence sequence(dir.path());
    EXPECT_EQ(sequence.checkFrames(2).size(), 2u);
    Frame first = sequence.readFrame(0);
    ASSERT_TRUE(first.specular.has_value());
    ASSERT_TRUE(first.roughness.has_value());
    ASSERT_TRUE(first.hitDistance.has_value());
    EXPECT_EQ(first.specular->channels, 3);
    EXPECT_EQ(first.roughness->channels, 1);
    EXPECT_EQ(first.hitDistance->channels, 1);
    EXPECT_EQ(first.specular->width, first.width());
    EXPECT_EQ(first.specular->height, first.height());
    EXPECT_EQ(first.specular->pixels, written[0].specular->pixels);  // FLOAT files: exact
    EXPECT_EQ(first.roughness->pixels, written[0].roughness->pixels);
    EXPECT_EQ(first.hitDistance->pixels, written[0].hitDistance->pixels);
    // An RGB roughness file: its R channel.
    Frame second =
        expectRedChannelRead(sequence, dir.path() / "roughness_1.exr", &Frame::roughness);
    const int w = first.width(), h = first.height();
    // A denoiser takes the frames as read.
    Denoiser d(test::cpuSettings(Method::Detail));
    EXPECT_NO_THROW(d.processFrame(first));
    EXPECT_NO_THROW(d.processFrame(second));
    // Another size, for each file.
    for (const char* stem : {"specular", "roughness", "hit_distance"}) {
        const std::filesystem::path file = dir.path() / fmt::format("{}_1.exr", stem);
        const std::filesystem::path saved = dir.path() / "saved.exr";
        std::filesystem::copy_file(file, saved, std::filesystem::copy_options::overwrite_existing);
        writeExr(file, Image(w - 1, h, std::string(stem) == "specular" ? 3 : 1, 1.0f));
        expectRefusedWhenReadAndChecked(sequence,
                                        fmt::format("{}: {}x{}, but ", file.string(), w - 1, h));
        std::filesystem::rename(saved, file);
    }
    // Roughness without specular in a folder: read as it is, refused by the denoiser naming it.
    std::filesystem::remove(dir.path() / "specular_0.exr");
    Frame noSpecular = sequence.readFrame(0);
    EXPECT_FALSE(noSpecular.specular.has_value());
    EXPECT_TRUE(noSpecular.roughness.has_value());
    Denoiser fresh(test::cpuSettings(Method::Detail));
    expectRefused(fresh, noSpecular, "roughness is given without specular");
    // A frame without them writes none.
    test::TempFolder plain("split-plain");
    writeFrame(plain.path(), 0, frames[0]);
    EXPECT_FALSE(std::filesystem::exists(plain.path() / "specular_0.exr"));
    EXPECT_FALSE(Sequence(plain.path()).readFrame(0).specular.has_value());
}

// With motion vectors the kernels read one identity for every object: memory and time do not
// grow with the object count (issue 37: 4 million objects took 54 ms a frame, not 1.4).
TEST(MotionVectors, TheObjectCountCostsNothing) {
    const std::vector<Frame> frames = withMotion(cameraPanFrames());
    DenoiserSettings s = test::cpuSettings(Method::Detail);
    Denoiser few(s), many(s);
    for (const Frame& f : frames) {
        Frame wide = f;
        wide.objectCount = 4000000;
        const Image a = few.processFrame(f), b = many.processFrame(wide);
        EXPECT_EQ(a.pixels, b.pixels);
    }
    EXPECT_EQ(few.deviceMemoryBytes(), many.deviceMemoryBytes());
}

}  // namespace
}  // namespace rtd
