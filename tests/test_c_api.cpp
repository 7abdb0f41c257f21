// The C API (rtdenoise/rtdenoise.h, the shared library rtdenoise_c): a C translation unit
// denoises a rendered scene and matches the C++ API; every error path returns a code and a
// message without crashing; settings have the command line's names.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <thread>
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

// Binds frame f's colour, G-buffer and IDs (no albedo, no matrices) and `output` on `d`.
void bindWithoutMatrices(RTDDenoiser d, const Frame& f, std::vector<float>& output) {
    const std::size_t w = std::size_t(f.width()), h = std::size_t(f.height());
    output.assign(3 * w * h, 0.0f);
    rtdSetImage(d, "color", f.beauty.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(d, "normal", f.normal.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(d, "position", f.position.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
    rtdSetImage(d, "depth", f.depth.pixels.data(), RTD_FORMAT_FLOAT, w, h, 0, 0);
    rtdSetImage(d, "ids", f.objectId.data(), RTD_FORMAT_INT, w, h, 0, 0);
    rtdSetImage(d, "output", output.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
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

// An engine that sets its parameters before every frame: setting a value it already has keeps
// the history, so every frame is the normal run's (issue 37: each frame was a first frame).
TEST_F(CApi, SettingAValueAgainKeepsTheHistory) {
    Denoiser reference(cpuSettings(Method::Svgf));
    for (const Frame& f : frames_) {
        std::vector<float> out;
        ASSERT_EQ(rtdSetFloat(denoiser_, "sigma-color", 0.6f), RTD_ERROR_NONE);
        ASSERT_EQ(rtdSetFloat(denoiser_, "svgf-sigma-luminance", 4.0f), RTD_ERROR_NONE);
        ASSERT_EQ(rtdSetInt(denoiser_, "svgf-iterations", 5), RTD_ERROR_NONE);
        ASSERT_EQ(rtdSetString(denoiser_, "method", "svgf"), RTD_ERROR_NONE);
        bind(f, out);
        ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
        EXPECT_EQ(reference.processFrame(f).pixels, out);
    }
}

// A value a pass merely reads (a sigma) takes effect at the next frame, over the history kept:
// what a denoiser that changed it between the same frames gives, not a fresh denoiser's first
// frame. A value that changes the passes (the iteration count) starts a new history.
TEST_F(CApi, ASigmaTakesEffectAtTheNextFrameOverTheKeptHistory) {
    std::vector<float> out;
    bind(frames_[0], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetFloat(denoiser_, "svgf-sigma-luminance", 2.0f), RTD_ERROR_NONE);
    EXPECT_FLOAT_EQ(rtdGetFloat(denoiser_, "svgf-sigma-luminance"), 2.0f);
    bind(frames_[1], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    DenoiserSettings s = cpuSettings(Method::Svgf);
    Denoiser changed(s);
    changed.processFrame(frames_[0]);
    s.svgf.sigmaLuminance = 2.0f;
    EXPECT_TRUE(changed.changeSettings(s));
    EXPECT_EQ(changed.processFrame(frames_[1]).pixels, out);
    EXPECT_NE(Denoiser(s).processFrame(frames_[1]).pixels, out);  // the history was used

    ASSERT_EQ(rtdSetInt(denoiser_, "svgf-iterations", 3), RTD_ERROR_NONE);
    bind(frames_[2], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    s.svgf.iterations = 3;
    EXPECT_FALSE(changed.changeSettings(s));
    EXPECT_EQ(Denoiser(s).processFrame(frames_[2]).pixels, out);
    // rtdReset: a first frame too.
    bind(frames_[3], out);
    ASSERT_EQ(rtdReset(denoiser_), RTD_ERROR_NONE);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    EXPECT_EQ(Denoiser(s).processFrame(frames_[3]).pixels, out);
}

// A refused value leaves the settings and the history as they were.
TEST_F(CApi, ARefusedSettingKeepsTheHistory) {
    Denoiser reference(cpuSettings(Method::Svgf));
    for (const Frame& f : frames_) {
        std::vector<float> out;
        EXPECT_EQ(rtdSetFloat(denoiser_, "svgf-alpha", 2.0f), RTD_ERROR_INVALID_ARGUMENT);
        takeError(device_);
        bind(f, out);
        ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
        EXPECT_EQ(reference.processFrame(f).pixels, out);
    }
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
    EXPECT_EQ(rtdSetMatrices(denoiser_, nullptr, 0, nullptr, pixel), RTD_ERROR_INVALID_ARGUMENT);
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
    std::vector<float> out;
    bindWithoutMatrices(atrous, f, out);
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
    const std::set<std::string> notSettings = {
        "help",  "config",   "view-layer",   "output", "png",    "compression",
        "half",  "exposure", "video",        "fps",    "debug",  "frames",
        "quiet", "device",   "motion-scale", "warmup", "dry-run"};
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

// ---- issue 37: sizes, strides, object counts, threads, memory, IDs, broken passes ----

// Binds every input of a w x h frame to `pixels` (zeros read as ID 0 and depth 0) and the
// output to `output`, on `d`: for calls that must be refused before any pixel is read.
void bindAll(RTDDenoiser d, const void* pixels, void* output, std::size_t w, std::size_t h) {
    for (const char* name : {"color", "normal", "position"})
        ASSERT_EQ(rtdSetImage(d, name, pixels, RTD_FORMAT_FLOAT3, w, h, 0, 0), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetImage(d, "depth", pixels, RTD_FORMAT_FLOAT, w, h, 0, 0), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetImage(d, "ids", pixels, RTD_FORMAT_INT, w, h, 0, 0), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetImage(d, "output", output, RTD_FORMAT_FLOAT3, w, h, 0, 0), RTD_ERROR_NONE);
}

// (width - 1) * stride used to wrap around to a small span that passed the check (then a
// segfault in rtdExecute); a width of INT_MAX overflowed the planes' pitch ("out of memory").
TEST_F(CApi, StridesAndSizesThatOverflowAreInvalidArguments) {
    std::vector<float> pixels(16 * 3);
    const std::size_t huge = std::size_t(1) << 63;
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixels.data(), RTD_FORMAT_FLOAT3, 3, 3, huge, 16),
              RTD_ERROR_INVALID_ARGUMENT);
    LastError e = takeError(device_);
    EXPECT_NE(e.message.find("color: strides of"), std::string::npos) << e.message;
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixels.data(), RTD_FORMAT_FLOAT3, 3, 3, 12, huge),
              RTD_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(rtdSetImage(denoiser_, "color", pixels.data(), RTD_FORMAT_FLOAT3, 2, 2,
                          SIZE_MAX / 2 + 1, 0),
              RTD_ERROR_INVALID_ARGUMENT);
    takeError(device_);

    // Nothing is read: the size is refused first.
    std::vector<float> output(3);
    bindAll(denoiser_, pixels.data(), output.data(), INT_MAX, 1);
    ASSERT_EQ(rtdSetObjectCount(denoiser_, 1), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetImage(denoiser_, "motion", pixels.data(), RTD_FORMAT_FLOAT2, INT_MAX, 1, 0, 0),
              RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_ARGUMENT);
    e = takeError(device_);
    EXPECT_NE(e.message.find("too large"), std::string::npos) << e.message;
}

// The same hole in the C++ FrameView's check.
TEST(FrameViewChecks, AStrideThatOverflowsIsRefusedNamingTheImage) {
    // An odd width: (5 - 1) * 2^63 wraps to 0, which the old check took for a small span.
    const std::vector<Frame> frames = renderSmallSequence("moving-objects", 5, 4, 1);
    Denoiser denoiser(cpuSettings(Method::Atrous));
    FrameView view = viewOf(frames[0]);
    view.normal = ImageView(view.normal.data, DataType::Float32, 3, std::size_t(1) << 63, 64);
    std::vector<float> out(5 * 4 * 3);
    try {
        denoiser.processFrame(view, out.data());
        FAIL() << "a stride of 2^63 was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
        EXPECT_NE(std::string(e.what()).find("normal: strides of"), std::string::npos) << e.what();
    }
    view = viewOf(frames[0]);
    view.depth = ImageView(view.depth.data, DataType::Float32, 1, 4, std::size_t(1) << 62);
    EXPECT_THROW(denoiser.processFrame(view, out.data()), Error);
}

// The peak resident memory of this process, in MiB.
double peakResidentMiB() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / 1024.0;
}

// A single-frame method reads no matrices: 30 million objects cost nothing (issue 37: 5.7 GB of
// identity matrices for a 64x48 frame).
TEST_F(CApi, AnObjectCountCostsNothingWithoutMatrices) {
    const Frame& f = frames_[0];
    RTDDenoiser jbf = rtdNewDenoiser(device_, "jbf");
    std::vector<float> out;
    bindWithoutMatrices(jbf, f, out);
    ASSERT_EQ(rtdSetObjectCount(jbf, 30000000), RTD_ERROR_NONE);
    const double before = peakResidentMiB();
    ASSERT_EQ(rtdExecute(jbf), RTD_ERROR_NONE) << takeError(device_).message;
    EXPECT_LT(peakResidentMiB() - before, 200.0);
    Frame withoutAlbedo = f;
    withoutAlbedo.albedo.reset();
    EXPECT_EQ(Denoiser(cpuSettings(Method::Jbf)).processFrame(withoutAlbedo).pixels, out);
    rtdReleaseDenoiser(jbf);
}

// A call repeated while another thread holds the denoiser (INVALID_OPERATION); its final code.
template <class Call>
RTDError whenFree(RTDDevice device, Call&& call) {
    RTDError code;
    while ((code = call()) == RTD_ERROR_INVALID_OPERATION) takeError(device);
    return code;
}

// One denoiser from two threads at once (documented as not allowed) was a heap-use-after-free:
// while one thread's call runs, another thread's calls on that denoiser are refused with
// INVALID_OPERATION, and the first thread's frames are what they would be alone.
TEST_F(CApi, ASecondThreadIsRefusedWhileACallRuns) {
    std::atomic<bool> done{false};
    std::atomic<int> refused{0}, accepted{0};
    // Its codes alone: a device's error message is valid until that device's next
    // rtdGetDeviceError, so only this (the first) thread reads them.
    std::thread second([&] {
        while (!done.load()) {
            const RTDError code = rtdSetFloat(denoiser_, "svgf-alpha", 0.2f);  // the value it has
            if (code == RTD_ERROR_INVALID_OPERATION)
                refused.fetch_add(1);
            else if (code == RTD_ERROR_NONE)
                accepted.fetch_add(1);
            // Leaves the first thread room to take the denoiser between two of these.
            std::this_thread::sleep_for(std::chrono::microseconds(100));
        }
    });
    Denoiser reference(cpuSettings(Method::Svgf));
    int frames = 0;
    for (int round = 0; round < 20 && (refused.load() == 0 || frames < 8); ++round)
        for (const Frame& f : frames_) {
            const std::size_t w = std::size_t(f.width()), h = std::size_t(f.height());
            std::vector<float> out(w * h * 3);
            const std::vector<float> matrices = flatMatrices(f), camera = flat(f.worldToCamera),
                                     screen = flat(f.worldToScreen);
            auto image = [&](const char* name, const void* data, RTDFormat format) {
                ASSERT_EQ(
                    whenFree(
                        device_,
                        [&] { return rtdSetImage(denoiser_, name, data, format, w, h, 0, 0); }),
                    RTD_ERROR_NONE);
            };
            image("color", f.beauty.pixels.data(), RTD_FORMAT_FLOAT3);
            image("normal", f.normal.pixels.data(), RTD_FORMAT_FLOAT3);
            image("position", f.position.pixels.data(), RTD_FORMAT_FLOAT3);
            image("depth", f.depth.pixels.data(), RTD_FORMAT_FLOAT);
            image("ids", f.objectId.data(), RTD_FORMAT_INT);
            image("albedo", f.albedo ? f.albedo->pixels.data() : nullptr, RTD_FORMAT_FLOAT3);
            image("output", out.data(), RTD_FORMAT_FLOAT3);
            ASSERT_EQ(whenFree(device_,
                               [&] {
                                   return rtdSetMatrices(denoiser_, matrices.data(),
                                                         int(f.objectToWorld.size()), camera.data(),
                                                         screen.data());
                               }),
                      RTD_ERROR_NONE);
            ASSERT_EQ(whenFree(device_, [&] { return rtdExecute(denoiser_); }), RTD_ERROR_NONE);
            EXPECT_EQ(reference.processFrame(f).pixels, out);
            ++frames;
        }
    done = true;
    second.join();
    EXPECT_GT(refused.load(), 0);
    EXPECT_GT(accepted.load(), 0);  // between two calls the other thread's run
}

#if defined(__SANITIZE_ADDRESS__)
#define RTD_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RTD_UNDER_ASAN 1
#endif
#endif

#ifndef RTD_UNDER_ASAN
// Denoises a 2048x2048 svgf frame with the address space capped a little above what the process
// holds before the denoiser's images (about 600 MB) are allocated; prints the error message and
// returns the code.
int denoiseWithCappedMemory() {
    RTDDevice device = rtdNewDevice(RTD_DEVICE_CPU);
    RTDDenoiser d = rtdNewDenoiser(device, "svgf");
    const std::size_t w = 2048, h = 2048;
    std::vector<float> pixels(3 * w * h), output(3 * w * h);
    const std::vector<float> identity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    bindAll(d, pixels.data(), output.data(), w, h);
    rtdSetMatrices(d, identity.data(), 1, identity.data(), identity.data());
    std::ifstream status("/proc/self/status");
    std::string line;
    long long kib = 0;
    while (std::getline(status, line))
        if (line.rfind("VmSize:", 0) == 0) kib = std::stoll(line.substr(7));
    rlimit cap{};
    cap.rlim_cur = cap.rlim_max = rlim_t(kib + 150 * 1024) * 1024;
    setrlimit(RLIMIT_AS, &cap);
    const RTDError code = rtdExecute(d);
    const char* message = nullptr;
    rtdGetDeviceError(device, &message);
    std::fprintf(stderr, "%s\n", message ? message : "");
    return int(code);
}
#endif

// A failed CPU allocation is RTD_ERROR_OUT_OF_MEMORY (was DEVICE_FAILURE), in a child process.
TEST(CApiMemory, AFailedAllocationIsOutOfMemory) {
#ifdef RTD_UNDER_ASAN
    GTEST_SKIP() << "AddressSanitizer reserves terabytes of address space: no cap can be set";
#else
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(std::exit(denoiseWithCappedMemory()),
                ::testing::ExitedWithCode(RTD_ERROR_OUT_OF_MEMORY),
                "rtdExecute: cpu: out of memory");
#endif
}

// All NULL unsets the matrices: a temporal method then needs them or motion again, and the
// object count bounds a single-frame method's IDs.
TEST_F(CApi, MatricesCanBeUnset) {
    std::vector<float> out;
    bind(frames_[0], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetMatrices(denoiser_, nullptr, 0, nullptr, nullptr), RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_OPERATION);
    EXPECT_NE(takeError(device_).message.find("set the matrices"), std::string::npos);
    ASSERT_EQ(rtdSetString(denoiser_, "method", "atrous"), RTD_ERROR_NONE);
    ASSERT_EQ(rtdSetObjectCount(denoiser_, int(frames_[0].objectToWorld.size())), RTD_ERROR_NONE);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE) << takeError(device_).message;
}

// An int32 ID of INT_MIN is out of range, not "not an integer" (the float IDs' mark).
TEST_F(CApi, AnIdOfIntMinIsOutOfRange) {
    std::vector<float> out;
    bind(frames_[0], out);
    std::vector<std::int32_t> ids = frames_[0].objectId;
    ids[3] = INT_MIN;
    rtdSetImage(denoiser_, "ids", ids.data(), RTD_FORMAT_INT, 64, 48, 0, 0);
    EXPECT_EQ(rtdExecute(denoiser_), RTD_ERROR_INVALID_INPUT);
    const LastError e = takeError(device_);
    EXPECT_NE(e.message.find("object ID -2147483648 at pixel (3, 0) is outside -1.."),
              std::string::npos)
        << e.message;
}

// A frame with no usable geometry (depth all NaN, every ID -1) is passed through as it came:
// rtdExecute succeeds, and rtdGetFrameWarning says why; a normal frame has no warning.
TEST_F(CApi, AFrameWithoutUsableGeometryIsReported) {
    std::vector<float> out;
    bind(frames_[0], out);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    EXPECT_STREQ(rtdGetFrameWarning(denoiser_), "");
    const Frame& f = frames_[1];
    std::vector<float> nanDepth(f.depth.pixels.size(), std::nanf(""));
    bind(f, out);
    rtdSetImage(denoiser_, "depth", nanDepth.data(), RTD_FORMAT_FLOAT, 64, 48, 0, 0);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    std::string warning = rtdGetFrameWarning(denoiser_);
    EXPECT_NE(warning.find("NaN or Inf depth or position"), std::string::npos) << warning;
    std::vector<std::int32_t> background(f.objectId.size(), -1);
    bind(f, out);
    rtdSetImage(denoiser_, "ids", background.data(), RTD_FORMAT_INT, 64, 48, 0, 0);
    ASSERT_EQ(rtdExecute(denoiser_), RTD_ERROR_NONE);
    warning = rtdGetFrameWarning(denoiser_);
    EXPECT_NE(warning.find("100 % of the pixels are background"), std::string::npos) << warning;
    // Passed through: the input, demodulated and modulated back.
    for (std::size_t i = 0; i < out.size(); i += 97)
        EXPECT_NEAR(out[i], f.beauty.pixels[i], 1e-5f * std::max(1.0f, f.beauty.pixels[i]));
    EXPECT_EQ(rtdGetFrameWarning(nullptr), nullptr);
    takeError();
}

}  // namespace
}  // namespace rtd::test
