// The C API (rtdenoise/rtdenoise.h, the shared library rtdenoise_c): a C translation unit
// denoises a rendered scene and matches the C++ API; every error path returns a code and a
// message without crashing; settings have the command line's names.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "c_api/denoise_in_c.h"
#include "rtdenoise/rtdenoise.h"
#include "test_support.h"

namespace rtd::test {
namespace {

// The last error of `device` (NULL: this thread's), cleared: its code and message.
struct LastError {
    RTDError code;
    std::string message;
};
LastError takeError(RTDDevice device = nullptr) {
    const char* message = nullptr;
    RTDError code = rtdGetDeviceError(device, &message);
    return {code, message ? message : ""};
}

std::vector<float> flatMatrices(const Frame& f) {
    std::vector<float> m;
    for (const Matrix4& o : f.objectToWorld)
        for (const auto& row : o.m) m.insert(m.end(), row.begin(), row.end());
    return m;
}
std::vector<float> flat(const Matrix4& matrix) {
    std::vector<float> m;
    for (const auto& row : matrix.m) m.insert(m.end(), row.begin(), row.end());
    return m;
}

class CApi : public ::testing::Test {
  protected:
    static void SetUpTestSuite() { frames_ = renderSmallSequence("moving-objects", 64, 48, 4); }
    static std::vector<Frame> frames_;

    void SetUp() override {
        takeError();
        device_ = rtdNewDevice(RTD_DEVICE_CPU);
        ASSERT_NE(device_, nullptr) << takeError().message;
        denoiser_ = rtdNewDenoiser(device_, "svgf");
        ASSERT_NE(denoiser_, nullptr) << takeError(device_).message;
    }
    void TearDown() override {
        rtdReleaseDenoiser(denoiser_);
        rtdReleaseDevice(device_);
    }
    // Binds frame i's buffers and an output of the frame's size.
    void bind(const Frame& f, std::vector<float>& output) {
        const std::size_t w = std::size_t(f.width()), h = std::size_t(f.height());
        output.assign(w * h * 3, 0.0f);
        ASSERT_EQ(
            rtdSetImage(denoiser_, "color", f.beauty.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0),
            RTD_ERROR_NONE);
        rtdSetImage(denoiser_, "normal", f.normal.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(denoiser_, "position", f.position.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(denoiser_, "depth", f.depth.pixels.data(), RTD_FORMAT_FLOAT, w, h, 0, 0);
        rtdSetImage(denoiser_, "ids", f.objectId.data(), RTD_FORMAT_INT, w, h, 0, 0);
        rtdSetImage(denoiser_, "albedo", f.albedo ? f.albedo->pixels.data() : nullptr,
                    RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(denoiser_, "output", output.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        matrices_ = flatMatrices(f);
        camera_ = flat(f.worldToCamera);
        screen_ = flat(f.worldToScreen);
        ASSERT_EQ(rtdSetMatrices(denoiser_, matrices_.data(), int(f.objectToWorld.size()),
                                 camera_.data(), screen_.data()),
                  RTD_ERROR_NONE);
    }

    RTDDevice device_ = nullptr;
    RTDDenoiser denoiser_ = nullptr;
    std::vector<float> matrices_, camera_, screen_;
};
std::vector<Frame> CApi::frames_;

TEST_F(CApi, TheCFileIsCompiledAsC) {
    EXPECT_EQ(compiledAsC(), 1);
}

TEST_F(CApi, VersionIsTheHeaders) {
    EXPECT_EQ(rtdGetVersion(), RTD_VERSION);
    EXPECT_EQ(RTD_VERSION, RTD_VERSION_MAJOR * 10000 + RTD_VERSION_MINOR * 100 + RTD_VERSION_PATCH);
}

// The same rendered frames through C (denoise_in_c.c) and through rtd::Denoiser: the same
// result, every method (max relative difference <= 1e-6; the same code runs, so in fact 0).
TEST_F(CApi, CProgramMatchesTheCppApiOnARenderedScene) {
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        SCOPED_TRACE(toString(method));
        std::vector<CFrame> cFrames(frames_.size());
        std::vector<std::vector<float>> matrices(frames_.size()), cameras(frames_.size()),
            screens(frames_.size()), outputs(frames_.size());
        std::vector<float*> outputPointers;
        for (std::size_t i = 0; i < frames_.size(); ++i) {
            const Frame& f = frames_[i];
            matrices[i] = flatMatrices(f);
            cameras[i] = flat(f.worldToCamera);
            screens[i] = flat(f.worldToScreen);
            outputs[i].assign(f.beauty.pixels.size(), -1.0f);
            outputPointers.push_back(outputs[i].data());
            cFrames[i] = CFrame{f.width(),
                                f.height(),
                                f.beauty.pixels.data(),
                                f.normal.pixels.data(),
                                f.position.pixels.data(),
                                f.depth.pixels.data(),
                                f.albedo ? f.albedo->pixels.data() : nullptr,
                                f.objectId.data(),
                                int(f.objectToWorld.size()),
                                matrices[i].data(),
                                cameras[i].data(),
                                screens[i].data()};
        }
        char message[512] = {};
        ASSERT_EQ(denoiseInC(toString(method), cFrames.data(), int(cFrames.size()),
                             outputPointers.data(), message, int(sizeof message)),
                  0)
            << message;
        Denoiser cpp(cpuSettings(method));
        for (std::size_t i = 0; i < frames_.size(); ++i) {
            Image expected = cpp.processFrame(frames_[i]);
            Image got(expected.width, expected.height, 3);
            got.pixels = outputs[i];
            EXPECT_LE(maxRelativeDifference(expected, got), 1e-6) << "frame " << i;
        }
    }
}

// Two denoisers on one device keep their own histories: interleaved, each gives what a
// denoiser alone gives.
TEST_F(CApi, DenoisersSharingADeviceKeepTheirOwnHistory) {
    RTDDenoiser second = rtdNewDenoiser(device_, "temporal");
    ASSERT_NE(second, nullptr);
    Denoiser svgf(cpuSettings(Method::Svgf)), temporal(cpuSettings(Method::Temporal));
    for (const Frame& f : frames_) {
        std::vector<float> out1, out2;
        bind(f, out1);
        ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
        std::swap(denoiser_, second);
        bind(f, out2);
        ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
        std::swap(denoiser_, second);
        Image a = svgf.processFrame(f), b = temporal.processFrame(f);
        EXPECT_EQ(a.pixels, out1);
        EXPECT_EQ(b.pixels, out2);
    }
    EXPECT_EQ(rtdSynchronize(device_), RTD_ERROR_NONE);
    rtdReleaseDenoiser(second);
}

// A setting changed after frames starts a new history: the next frame is what a fresh
// denoiser with that setting gives.
TEST_F(CApi, ChangingASettingStartsANewHistory) {
    std::vector<float> out;
    bind(frames_[0], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetFloat(denoiser_, "svgf-sigma-luminance", 2.0f), RTD_ERROR_NONE);
    EXPECT_FLOAT_EQ(rtdGetFloat(denoiser_, "svgf-sigma-luminance"), 2.0f);
    bind(frames_[1], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    DenoiserSettings s = cpuSettings(Method::Svgf);
    s.svgf.sigmaLuminance = 2.0f;
    EXPECT_EQ(Denoiser(s).processFrame(frames_[1]).pixels, out);
    // rtdReset: the same.
    bind(frames_[2], out);
    ASSERT_EQ(rtdReset(denoiser_), RTD_ERROR_NONE);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    EXPECT_EQ(Denoiser(s).processFrame(frames_[2]).pixels, out);
}

// Half RGBA colour with a row pitch gives what the packed float colour gives, to half precision.
TEST_F(CApi, HalfRgbaWithARowPitchIsRead) {
    const Frame& f = frames_[0];
    const int w = f.width(), h = f.height();
    const std::size_t pitch = std::size_t(w) * 8 + 64;
    std::vector<unsigned char> rgba(pitch * std::size_t(h), 0);
    Frame rounded = f;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                // float -> half by the bits: these radiances are normal halves (or 0).
                float v = f.beauty.at(x, y, c);
                std::uint32_t bits;
                std::memcpy(&bits, &v, 4);
                std::uint16_t half = 0;
                if (v >= 6.2e-5f)
                    half = std::uint16_t(((bits >> 16) & 0x8000) |
                                         ((((bits >> 23) & 0xff) - 112) << 10) |
                                         ((bits >> 13) & 0x3ff));
                std::memcpy(&rgba[std::size_t(y) * pitch + std::size_t(x) * 8 + std::size_t(c) * 2],
                            &half, 2);
                std::uint32_t back = half == 0
                                         ? 0
                                         : ((std::uint32_t(half & 0x8000) << 16) |
                                            (((std::uint32_t(half >> 10) & 0x1f) + 112) << 23) |
                                            (std::uint32_t(half & 0x3ff) << 13));
                std::memcpy(&rounded.beauty.at(x, y, c), &back, 4);
            }
    std::vector<float> out;
    bind(f, out);
    ASSERT_EQ(rtdSetImage(denoiser_, "color", rgba.data(), RTD_FORMAT_HALF4, std::size_t(w),
                          std::size_t(h), 8, pitch),
              RTD_ERROR_NONE);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
    Image expected = Denoiser(cpuSettings(Method::Svgf)).processFrame(rounded);
    Image got(w, h, 3);
    got.pixels = out;
    EXPECT_LE(maxRelativeDifference(expected, got), 1e-6);
}

// ---- errors: a code and a message naming the problem, never a crash ----

TEST_F(CApi, BadDeviceTypeAndNullHandles) {
    EXPECT_EQ(rtdNewDevice(RTDDeviceType(99)), nullptr);
    LastError e = takeError();
    EXPECT_EQ(e.code, RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(e.message.find("99"), std::string::npos) << e.message;

    EXPECT_EQ(rtdNewDenoiser(nullptr, "svgf"), nullptr);
    EXPECT_EQ(takeError().code, RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetFloat(nullptr, "sigma-color", 1.0f), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError();
    EXPECT_NE(e.message.find("NULL"), std::string::npos) << e.message;
    EXPECT_EQ(rtdExecute(nullptr), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetImage(nullptr, "color", nullptr, RTD_FORMAT_FLOAT3, 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSynchronize(nullptr), RTD_ERROR_INVALID_ARGUMENT);
    rtdReleaseDenoiser(nullptr);
    rtdReleaseDevice(nullptr);
    rtdRetainDevice(nullptr);
    EXPECT_STREQ(rtdGetDeviceName(nullptr), "");
    EXPECT_EQ(takeError().code, RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(takeError().code, RTD_ERROR_NONE);  // read once, then cleared
    EXPECT_EQ(rtdGetDeviceError(nullptr, nullptr), RTD_ERROR_NONE);
}

TEST_F(CApi, CudaWithoutAGpuIsUnsupported) {
    if (!gpuName().empty()) GTEST_SKIP() << "a GPU is present: " << gpuName();
    EXPECT_EQ(rtdNewDevice(RTD_DEVICE_CUDA), nullptr);
    EXPECT_EQ(takeError().code, RTD_ERROR_UNSUPPORTED_DEVICE);
    EXPECT_EQ(rtdNewCUDADevice(nullptr), nullptr);
    LastError e = takeError();
    EXPECT_EQ(e.code, RTD_ERROR_UNSUPPORTED_DEVICE);
    EXPECT_NE(e.message.find("cuda"), std::string::npos) << e.message;
    RTDDevice fallback = rtdNewDevice(RTD_DEVICE_DEFAULT);  // the CPU, then
    ASSERT_NE(fallback, nullptr);
    EXPECT_EQ(std::string(rtdGetDeviceName(fallback)).rfind("cpu", 0), 0u);
    rtdReleaseDevice(fallback);
}

TEST_F(CApi, BadMethodAndSettings) {
    EXPECT_EQ(rtdNewDenoiser(device_, "magic"), nullptr);
    LastError e = takeError(device_);
    EXPECT_EQ(e.code, RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(e.message.find("'magic' is not one of jbf, atrous, temporal, svgf"),
              std::string::npos)
        << e.message;

    EXPECT_EQ(rtdSetFloat(denoiser_, "sigma-colour", 1.0f), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("unknown setting 'sigma-colour'"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find("sigma-color"), std::string::npos) << "lists the names";

    EXPECT_EQ(rtdSetFloat(denoiser_, "sigma-color", -1.0f), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("sigma-color must be >= 1e-06"), std::string::npos) << e.message;
    EXPECT_FLOAT_EQ(rtdGetFloat(denoiser_, "sigma-color"), 0.6f) << "a refused value is not kept";
    EXPECT_EQ(rtdSetFloat(denoiser_, "alpha", std::nanf("")), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("not finite"), std::string::npos);
    EXPECT_EQ(rtdSetInt(denoiser_, "svgf-iterations", 11), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("svgf-iterations must be in [1, 10]"),
              std::string::npos);
    EXPECT_EQ(rtdGetInt(denoiser_, "svgf-iterations"), 5);
    EXPECT_EQ(rtdGetInt(denoiser_, "detail-specular-iterations"), 1);
    EXPECT_EQ(rtdSetInt(denoiser_, "detail-specular-iterations", 0), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("detail-specular-iterations must be in [1, 10]"),
              std::string::npos);
    EXPECT_EQ(rtdSetInt(denoiser_, "detail-specular-iterations", 3), RTD_ERROR_NONE);
    EXPECT_EQ(rtdSetBool(denoiser_, "sigma-color", true), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("'sigma-color' is a float setting, not a bool one"), std::string::npos)
        << e.message;
    EXPECT_EQ(rtdSetFloat(denoiser_, "radius", 3.5f), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetString(denoiser_, "method", "svgf2"), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetString(denoiser_, "depth-kind", "z"), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetFloat(denoiser_, nullptr, 1.0f), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetString(denoiser_, "method", nullptr), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdGetInt(denoiser_, "nothing"), 0);
    EXPECT_EQ(rtdGetString(denoiser_, "sigma-color"), nullptr);
    takeError(device_);

    // What is accepted.
    EXPECT_EQ(rtdSetInt(denoiser_, "sigma-color", 2), RTD_ERROR_NONE);  // an int into a float
    EXPECT_FLOAT_EQ(rtdGetFloat(denoiser_, "sigma-color"), 2.0f);
    EXPECT_EQ(rtdSetBool(denoiser_, "outlier", false), RTD_ERROR_NONE);
    EXPECT_FALSE(rtdGetBool(denoiser_, "outlier"));
    EXPECT_EQ(rtdSetString(denoiser_, "method", "atrous"), RTD_ERROR_NONE);
    EXPECT_STREQ(rtdGetString(denoiser_, "method"), "atrous");
    EXPECT_EQ(rtdSetString(denoiser_, "depth-kind", "ray-distance"), RTD_ERROR_NONE);
    EXPECT_STREQ(rtdGetString(denoiser_, "depth-kind"), "ray-distance");
    EXPECT_EQ(takeError(device_).code, RTD_ERROR_NONE);
}

TEST_F(CApi, BadImages) {
    float pixel[4] = {};
    EXPECT_EQ(rtdSetImage(denoiser_, "colour", pixel, RTD_FORMAT_FLOAT3, 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    LastError e = takeError(device_);
    EXPECT_NE(e.message.find("unknown image 'colour'"), std::string::npos) << e.message;
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixel, RTD_FORMAT_FLOAT2, 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("color: format 2 does not fit"), std::string::npos) << e.message;
    EXPECT_EQ(rtdSetImage(denoiser_, "ids", pixel, RTD_FORMAT_HALF, 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("ids: format 5 does not fit"), std::string::npos);
    EXPECT_EQ(rtdSetImage(denoiser_, "normal", pixel, RTD_FORMAT_INT, 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("normal: format 9 does not fit"), std::string::npos);
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixel, RTDFormat(42), 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("format 42 is not an RTDFormat"), std::string::npos);
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixel, RTD_FORMAT_FLOAT3, 0, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("size 0x1"), std::string::npos);
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixel, RTD_FORMAT_FLOAT3, 4, 1, 8, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(takeError(device_).message.find("too small"), std::string::npos);
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixel, RTD_FORMAT_FLOAT3, 4, 2, 12, 40),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetImage(denoiser_, nullptr, pixel, RTD_FORMAT_FLOAT3, 1, 1, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetMatrices(denoiser_, nullptr, 2, pixel, pixel), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetMatrices(denoiser_, nullptr, 0, nullptr, nullptr), RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetObjectCount(denoiser_, -1), RTD_ERROR_INVALID_ARGUMENT);
    takeError(device_);
}

TEST_F(CApi, CallsInTheWrongOrder) {
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_OPERATION);
    LastError e = takeError(device_);
    EXPECT_NE(e.message.find("rtdExecute: the image 'color' is not set"), std::string::npos)
        << e.message;

    const Frame& f = frames_[0];
    std::vector<float> out;
    bind(f, out);
    // An output of another size.
    std::vector<float> small(3 * 4 * 4);
    rtdSetImage(denoiser_, "output", small.data(), RTD_FORMAT_FLOAT3, 4, 4, 0, 0);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("'output' is 4x4, but 'color' is 64x48"), std::string::npos)
        << e.message;
    // An image unset again.
    bind(f, out);
    rtdSetImage(denoiser_, "depth", nullptr, RTD_FORMAT_UNDEFINED, 0, 0, 0, 0);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_OPERATION);
    EXPECT_NE(takeError(device_).message.find("'depth' is not set"), std::string::npos);

    // svgf without matrices or motion vectors.
    RTDDenoiser fresh = rtdNewDenoiser(device_, nullptr);
    std::swap(fresh, denoiser_);
    bind(f, out);
    RTDDenoiser noMatrices = rtdNewDenoiser(device_, "svgf");
    const std::size_t w = 64, h = 48;
    for (const char* name : {"color", "normal", "position"})
        rtdSetImage(noMatrices, name, f.beauty.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(noMatrices, "depth", f.depth.pixels.data(), RTD_FORMAT_FLOAT, w, h, 0, 0);
    rtdSetImage(noMatrices, "ids", f.objectId.data(), RTD_FORMAT_INT, w, h, 0, 0);
    rtdSetImage(noMatrices, "output", out.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    EXPECT_EQ(rtdExecute(noMatrices), RTD_ERROR_INVALID_OPERATION);
    e = takeError(device_);
    EXPECT_NE(e.message.find("set the matrices (rtdSetMatrices) or a 'motion' image"),
              std::string::npos)
        << e.message;
    rtdReleaseDenoiser(noMatrices);
    std::swap(fresh, denoiser_);
    rtdReleaseDenoiser(fresh);
}

// The single-frame methods need no matrices: the object count alone bounds the IDs.
TEST_F(CApi, AtrousNeedsNoMatrices) {
    const Frame& f = frames_[0];
    RTDDenoiser atrous = rtdNewDenoiser(device_, "atrous");
    const std::size_t w = 64, h = 48;
    std::vector<float> out(3 * w * h);
    rtdSetImage(atrous, "color", f.beauty.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(atrous, "normal", f.normal.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(atrous, "position", f.position.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(atrous, "depth", f.depth.pixels.data(), RTD_FORMAT_FLOAT, w, h, 0, 0);
    rtdSetImage(atrous, "ids", f.objectId.data(), RTD_FORMAT_INT, w, h, 0, 0);
    rtdSetImage(atrous, "output", out.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    ASSERT_EQ(rtdSetObjectCount(atrous, int(f.objectToWorld.size())), RTD_ERROR_NONE);
    ASSERT_EQ(rtdExecute(atrous), RTD_ERROR_NONE) << takeError(device_).message;
    Frame withoutAlbedo = f;
    withoutAlbedo.albedo.reset();
    EXPECT_EQ(Denoiser(cpuSettings(Method::Atrous)).processFrame(withoutAlbedo).pixels, out);
    rtdReleaseDenoiser(atrous);
}

TEST_F(CApi, AnObjectIdOutOfRangeIsInvalidInputAndKeepsTheHistory) {
    const Frame& f = frames_[0];
    std::vector<float> out;
    bind(f, out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    std::vector<float> good = out;
    std::vector<std::int32_t> ids = f.objectId;
    ids[5] = 1000;
    rtdSetImage(denoiser_, "ids", ids.data(), RTD_FORMAT_INT, 64, 48, 0, 0);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_INPUT);
    LastError e = takeError(device_);
    EXPECT_NE(e.message.find("object ID 1000 at pixel (5, 0)"), std::string::npos) << e.message;
}

// The optional history confidence: 1 float or half value a pixel, the frame's size.
TEST_F(CApi, ConfidenceIsAnOptionalOneChannelImage) {
    const Frame& f = frames_[0];
    const std::size_t w = 64, h = 48;
    std::vector<float> out;
    bind(f, out);
    std::vector<float> confidence(w * h, 0.25f);
    std::vector<std::uint16_t> halfConfidence(w * h, 0x3400);  // 0.25
    EXPECT_EQ(
        rtdSetImage(denoiser_, "confidence", confidence.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0),
        RTD_ERROR_INVALID_ARGUMENT);
    LastError e = takeError(device_);
    EXPECT_NE(e.message.find("confidence: format 3 does not fit, expected 1 float or half"),
              std::string::npos)
        << e.message;
    ASSERT_EQ(
        rtdSetImage(denoiser_, "confidence", halfConfidence.data(), RTD_FORMAT_HALF, w, h, 0, 0),
        RTD_ERROR_NONE);
    ASSERT_EQ(
        rtdSetImage(denoiser_, "confidence", confidence.data(), RTD_FORMAT_FLOAT, w / 2, h, 0, 0),
        RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("the image 'confidence' is 32x48, but 'color' is 64x48"),
              std::string::npos)
        << e.message;
    ASSERT_EQ(rtdSetImage(denoiser_, "confidence", confidence.data(), RTD_FORMAT_FLOAT, w, h, 0, 0),
              RTD_ERROR_NONE);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
    for (float v : out) ASSERT_TRUE(std::isfinite(v));
}

// The optional split signal (read by detail): "specular" as color, "roughness" and
// "hit_distance" 1 float or half value a pixel; roughness goes with specular and back.
TEST_F(CApi, TheSplitSignalIsOptionalAndRoughnessGoesWithSpecular) {
    const Frame& f = frames_[0];
    const std::size_t w = 64, h = 48;
    RTDDenoiser detail = rtdNewDenoiser(device_, "detail");
    ASSERT_NE(detail, nullptr) << takeError(device_).message;
    std::swap(denoiser_, detail);  // bind() binds denoiser_
    std::vector<float> out;
    bind(f, out);
    std::vector<float> specular(w * h * 3), roughness(w * h, 0.5f), hitDistance(w * h, 2.0f);
    for (std::size_t i = 0; i < specular.size(); ++i) specular[i] = 0.25f * f.beauty.pixels[i];
    std::vector<std::uint16_t> halfRoughness(w * h, 0x3800);  // 0.5
    EXPECT_EQ(rtdSetImage(denoiser_, "roughness", roughness.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    LastError e = takeError(device_);
    EXPECT_NE(e.message.find("roughness: format 3 does not fit, expected 1 float or half"),
              std::string::npos)
        << e.message;
    EXPECT_EQ(rtdSetImage(denoiser_, "specular", specular.data(), RTD_FORMAT_FLOAT, w, h, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    takeError(device_);
    // Specular without roughness.
    ASSERT_EQ(rtdSetImage(denoiser_, "specular", specular.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0),
              RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_INPUT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("specular is given without roughness"), std::string::npos)
        << e.message;
    // Roughness (and the hit distance) without specular.
    ASSERT_EQ(rtdSetImage(denoiser_, "specular", nullptr, RTD_FORMAT_FLOAT3, w, h, 0, 0),
              RTD_ERROR_NONE);
    ASSERT_EQ(
        rtdSetImage(denoiser_, "roughness", halfRoughness.data(), RTD_FORMAT_HALF, w, h, 0, 0),
        RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_INPUT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("roughness is given without specular"), std::string::npos)
        << e.message;
    // Another size.
    ASSERT_EQ(rtdSetImage(denoiser_, "specular", specular.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0),
              RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetImage(denoiser_, "hit_distance", hitDistance.data(), RTD_FORMAT_FLOAT, w, h / 2,
                          0, 0),
              RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("the image 'hit_distance' is 64x24, but 'color' is 64x48"),
              std::string::npos)
        << e.message;
    // All three: a finite result, for a few frames (the history too).
    ASSERT_EQ(
        rtdSetImage(denoiser_, "hit_distance", hitDistance.data(), RTD_FORMAT_FLOAT, w, h, 0, 0),
        RTD_ERROR_NONE);
    for (int frame = 0; frame < 2; ++frame) {
        ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
        for (float v : out) ASSERT_TRUE(std::isfinite(v));
    }
    // An unknown name lists them.
    EXPECT_EQ(rtdSetImage(denoiser_, "gloss", specular.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("confidence, specular, roughness, hit_distance, output"),
              std::string::npos)
        << e.message;
    std::swap(denoiser_, detail);
    rtdReleaseDenoiser(detail);
}

TEST_F(CApi, ErrorsReachTheCallbackAndTheFirstIsKept) {
    struct Heard {
        int calls = 0;
        RTDError last = RTD_ERROR_NONE;
        std::string message;
    } heard;
    rtdSetDeviceErrorFunction(
        device_,
        [](void* user, RTDError code, const char* message) {
            auto* h = static_cast<Heard*>(user);
            ++h->calls;
            h->last = code;
            h->message = message;
        },
        &heard);
    rtdSetFloat(denoiser_, "nothing", 1.0f);
    rtdExecute(denoiser_);
    EXPECT_EQ(heard.calls, 2);
    EXPECT_EQ(heard.last, RTD_ERROR_INVALID_OPERATION);
    LastError e = takeError(device_);
    EXPECT_EQ(e.code, RTD_ERROR_INVALID_ARGUMENT) << "the first error is kept until read";
    EXPECT_NE(e.message.find("rtdSetFloat: unknown setting 'nothing'"), std::string::npos);
    EXPECT_EQ(takeError(device_).code, RTD_ERROR_NONE);
    rtdSetDeviceErrorFunction(device_, nullptr, nullptr);
}

// Every setting of `rtdenoise denoise --help` is a C API setting of the same name.
TEST_F(CApi, SettingsHaveTheCommandLinesNames) {
    CliResult help = runCli("denoise --help");
    ASSERT_EQ(help.exitCode, 0) << help.output;
    const std::set<std::string> notSettings = {"help",  "config",      "view-layer",  "output",
                                               "png",   "compression", "half",        "exposure",
                                               "video", "fps",         "debug",       "frames",
                                               "quiet", "device",      "motion-scale"};
    std::regex option(R"(--([a-z][a-z0-9-]+))");
    int checked = 0;
    for (std::sregex_iterator it(help.output.begin(), help.output.end(), option), end; it != end;
         ++it) {
        std::string name = (*it)[1];
        if (notSettings.count(name) || name.rfind("no-", 0) == 0) continue;
        takeError(device_);
        rtdGetFloat(denoiser_, name.c_str());
        if (takeError(device_).code == RTD_ERROR_NONE) {
            ++checked;
            continue;
        }
        rtdGetBool(denoiser_, name.c_str());
        if (takeError(device_).code == RTD_ERROR_NONE) {
            ++checked;
            continue;
        }
        rtdGetString(denoiser_, name.c_str());
        EXPECT_EQ(takeError(device_).code, RTD_ERROR_NONE) << "--" << name << " is no C setting";
        ++checked;
    }
    EXPECT_GE(checked, 30);
    // --motion-scale X,Y is two settings.
    EXPECT_FLOAT_EQ(rtdGetFloat(denoiser_, "motion-scale-x"), 1.0f);
    EXPECT_FLOAT_EQ(rtdGetFloat(denoiser_, "motion-scale-y"), 1.0f);
}

}  // namespace
}  // namespace rtd::test
