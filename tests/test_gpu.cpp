// CPU and CUDA back ends agree (CTest label `gpu`): every method, on a rendered scene and on the
// course scene. Skips, saying why, where the build has no CUDA back end or no GPU is present.
// On a GPU machine: ctest --preset release -L gpu --output-on-failure
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <initializer_list>

#if RTD_TEST_CUDA
#include <cuda_runtime.h>
#endif

#include "input_helpers.h"
#include "learned_known_answer.h"
#include "rtdenoise/rtdenoise.h"
#include "test_support.h"
#include "tuning.h"

namespace rtd {
namespace {

// Why CUDA cannot run here, or empty if it can.
std::string cudaUnavailableReason() {
    try {
        DenoiserSettings s;
        s.device = DeviceType::Cuda;
        Denoiser probe(s);
        return "";
    } catch (const Error& e) {
        return e.what();
    }
}

// gpuTilePasses: the CUDA denoiser's (the CPU's runs its default).
void expectBackEndsAgree(const std::vector<Frame>& frames, const char* what,
                         std::initializer_list<Method> methods = {Method::Jbf, Method::Atrous,
                                                                  Method::Temporal, Method::Svgf,
                                                                  Method::Detail, Method::Learned},
                         TilePasses gpuTilePasses = TilePasses::Auto) {
    for (Method method : methods) {
        DenoiserSettings s;
        s.method = method;
        s.device = DeviceType::Cpu;
        Denoiser cpu(s);
        s.device = DeviceType::Cuda;
        Denoiser gpu = makeTunedDenoiser(s, {CpuIsa::Auto, gpuTilePasses});
        for (std::size_t i = 0; i < frames.size(); ++i) {
            Image a = cpu.processFrame(frames[i]), b = gpu.processFrame(frames[i]);
            double difference = test::maxRelativeDifference(a, b);
            EXPECT_LE(difference, test::backEndTolerance(method))
                << what << ", " << toString(method) << ", frame " << i;
        }
    }
}

// The learned method's network on CUDA equals the PyTorch forward pass (the committed known
// answer; test_learned checks the CPU's instruction sets).
TEST(Gpu, LearnedKernelEqualsThePyTorchForwardPass) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    const test::KnownAnswer k = test::readKnownAnswer();
    ASSERT_GE(k.inputs.size(), 8u);
    std::unique_ptr<Device> device = createDevice(DeviceType::Cuda);
    const std::vector<float> out = test::mixOnDevice(k, test::knownAnswerNetwork(), *device);
    for (std::size_t p = 0; p < k.inputs.size(); ++p)
        for (int c = 0; c < 3; ++c)
            EXPECT_TRUE(
                test::nearKnownAnswer(out[3 * p + std::size_t(c)], k.outputs[p][std::size_t(c)]))
                << "pixel " << p << ", channel " << c << ": " << out[3 * p + std::size_t(c)]
                << " against " << k.outputs[p][std::size_t(c)];
}

TEST(Gpu, CpuAndCudaAgreeOnARenderedScene) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
    expectBackEndsAgree(frames, "moving-objects");
}

// The split signal's passes (detail's specular histories, the reflection's reprojection).
TEST(Gpu, CpuAndCudaAgreeOnTheSplitSignal) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("reflections", 96, 64, 4, true);
    ASSERT_TRUE(frames[1].specular && frames[1].hitDistance);
    expectBackEndsAgree(frames, "reflections, split", {Method::Detail});
}

// The firefly removal's tile pass on the GPU (shared memory, a barrier between phases) gives
// the CPU's separate passes' result, whichever the GPU's default.
TEST(Gpu, CudaTilePassesAgreeWithTheCpu) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
    expectBackEndsAgree(frames, "moving-objects, tile passes on",
                        {Method::Atrous, Method::Temporal, Method::Svgf}, TilePasses::On);
    expectBackEndsAgree(frames, "moving-objects, tile passes off",
                        {Method::Atrous, Method::Temporal, Method::Svgf}, TilePasses::Off);
}

// 1400x1000: each RGB input is 16.8 MB, over two of the pinned chunks that copies in and out
// of host memory go through.
TEST(Gpu, CpuAndCudaAgreeOnFramesLargerThanTheStagingChunks) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects", 1400, 1000, 2);
    expectBackEndsAgree(frames, "moving-objects 1400x1000",
                        {Method::Atrous, Method::Svgf, Method::Detail});
}

TEST(Gpu, CpuAndCudaAgreeOnTheCourseScene) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    if (!std::filesystem::exists(test::boxFolder() / "beauty_0.exr"))
        GTEST_SKIP() << "course data not found at " << test::boxFolder();
    Sequence sequence(test::boxFolder());
    std::vector<Frame> frames;
    for (int i = 0; i < 3; ++i) frames.push_back(sequence.readFrame(i));
    expectBackEndsAgree(frames, "box");
}

// Bad values a renderer writes (test_bad_values: radiance near the float maximum, zero,
// non-finite and short normals): the GPU's result is finite, counts what the CPU counts, and
// agrees with the CPU's, with the tile passes on and off. Within 3 pixels of a pixel clamped to
// kMaxRadiance (its firefly window) the bound is 1e-2: there the luminance weights' scale comes
// from that pixel's variance, and each A-Trous iteration multiplies a rounding difference of
// 1e-5 by 30-50 (svgf on an H200: 1.5e-5 after 3 iterations, 7e-4 after 4, 1.8e-3 after 5;
// docs/performance-gpu.md, 2026-12-04).
TEST(Gpu, CudaHandlesBadValuesAsTheCpuDoes) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    const int width = 64, height = 48;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects", width, height, 4);
    const int hugeAt[2][2] = {{10, 10}, {40, 30}};
    for (Frame& f : frames) {
        f.beauty.at(hugeAt[0][0], hugeAt[0][1], 0) = 3.4e38f;
        f.beauty.at(hugeAt[1][0], hugeAt[1][1], 1) = 1e20f;
        for (int y = 20; y < 28; ++y)
            for (int x = 20; x < 28; ++x)
                for (int c = 0; c < 3; ++c) f.normal.at(x, y, c) = 0.0f;
        f.normal.at(50, 12, 0) = NAN;
        for (float& v : f.normal.pixels) v *= 0.8f;
    }
    auto nearHugeValue = [&](std::size_t value) {
        int x = int(value / 3) % width, y = int(value / 3) / width;
        for (const auto& at : hugeAt)
            if (std::abs(x - at[0]) <= 3 && std::abs(y - at[1]) <= 3) return true;
        return false;
    };
    for (TilePasses tiles : {TilePasses::On, TilePasses::Off}) {
        for (Method method :
             {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf, Method::Detail}) {
            DenoiserSettings s;
            s.method = method;
            s.device = DeviceType::Cpu;
            Denoiser cpu(s);
            s.device = DeviceType::Cuda;
            Denoiser gpu = makeTunedDenoiser(s, {CpuIsa::Auto, tiles});
            for (std::size_t i = 0; i < frames.size(); ++i) {
                Image a = cpu.processFrame(frames[i]), b = gpu.processFrame(frames[i]);
                for (float v : b.pixels) ASSERT_TRUE(std::isfinite(v)) << toString(method);
                EXPECT_EQ(gpu.lastFrameStats().radianceClamped, 2);
                EXPECT_EQ(gpu.lastFrameStats().missingNormals, cpu.lastFrameStats().missingNormals);
                double far = 0.0, near = 0.0;
                for (std::size_t k = 0; k < a.pixels.size(); ++k) {
                    double d = std::abs(double(b.pixels[k]) - a.pixels[k]) /
                               std::max(std::abs(double(a.pixels[k])), 1e-2);
                    double& worst = nearHugeValue(k) ? near : far;
                    worst = std::max(worst, d);
                }
                EXPECT_LE(far, 1e-3) << toString(method) << ", frame " << i;
                EXPECT_LE(near, 1e-2) << toString(method) << ", frame " << i << ", near";
            }
        }
    }
}

#if RTD_TEST_CUDA
// A renderer's G-buffer already on the GPU: device pointers in, a device pointer out. Gives what
// the host path gives, and a bad object ID there is refused too (it is checked on the device).
TEST(Gpu, DevicePointersGiveTheHostPathsResult) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
    std::vector<void*> allocations;
    auto toDevice = [&](const void* host, std::size_t bytes) {
        void* p = nullptr;
        EXPECT_EQ(cudaMalloc(&p, bytes), cudaSuccess);
        EXPECT_EQ(cudaMemcpy(p, host, bytes, cudaMemcpyHostToDevice), cudaSuccess);
        allocations.push_back(p);
        return p;
    };
    DenoiserSettings s;
    s.method = Method::Svgf;
    s.device = DeviceType::Cuda;
    Denoiser fromHost(s), fromDevice(s);
    const int w = frames[0].width(), h = frames[0].height();
    const std::size_t n = std::size_t(w) * h;
    // A view of `f` whose buffers are copies in device memory.
    auto deviceView = [&](const Frame& f) {
        FrameView v = viewOf(f);
        v.space = MemorySpace::Device;
        v.beauty = static_cast<const float*>(toDevice(v.beauty.data, 3 * n * 4));
        v.normal = static_cast<const float*>(toDevice(v.normal.data, 3 * n * 4));
        v.position = static_cast<const float*>(toDevice(v.position.data, 3 * n * 4));
        v.depth = static_cast<const float*>(toDevice(v.depth.data, n * 4));
        v.objectId = static_cast<const std::int32_t*>(toDevice(v.objectId.data, n * 4));
        if (v.albedo) v.albedo = static_cast<const float*>(toDevice(v.albedo.data, 3 * n * 4));
        return v;
    };
    float* output = static_cast<float*>(toDevice(frames[0].beauty.pixels.data(), 3 * n * 4));
    for (const Frame& f : frames) {
        fromDevice.processFrame(deviceView(f), output);
        Image expected = fromHost.processFrame(f), got(w, h, 3);
        ASSERT_EQ(cudaMemcpy(got.pixels.data(), output, 3 * n * 4, cudaMemcpyDeviceToHost),
                  cudaSuccess);
        EXPECT_LE(test::maxRelativeDifference(expected, got), 1e-6);
    }
    // An ID one past the frame's objects: refused, naming the pixel.
    Frame bad = frames.back();
    const int badId = int(bad.objectToWorld.size());
    bad.objectId[5 * w + 3] = badId;
    try {
        fromDevice.processFrame(deviceView(bad), output);
        ADD_FAILURE() << "a bad object ID in device memory was accepted";
    } catch (const Error& e) {
        std::string expected = "object ID " + std::to_string(badId) + " at pixel (3, 5)";
        EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    for (void* p : allocations) cudaFree(p);
}
// A CUDA renderer's stream: two denoisers share one device on the caller's stream, their frames
// in device memory only queued (no host wait), through the C++ and the C API. After the waits,
// each result is the host path's; a bad object ID is reported at the wait.
TEST(Gpu, CallersStreamQueuesFramesForSeveralDenoisers) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
    const int w = frames[0].width(), h = frames[0].height();
    const std::size_t n = std::size_t(w) * h;
    cudaStream_t stream = nullptr;
    ASSERT_EQ(cudaStreamCreate(&stream), cudaSuccess);
    std::vector<void*> allocations;
    auto deviceBytes = [&](std::size_t bytes) {
        void* p = nullptr;
        EXPECT_EQ(cudaMalloc(&p, bytes), cudaSuccess);
        allocations.push_back(p);
        return p;
    };
    // The caller's upload, queued on its stream before the denoiser's work.
    auto upload = [&](const void* host, std::size_t bytes) {
        void* p = deviceBytes(bytes);
        EXPECT_EQ(cudaMemcpyAsync(p, host, bytes, cudaMemcpyHostToDevice, stream), cudaSuccess);
        return p;
    };
    auto deviceView = [&](const Frame& f) {
        FrameView v = viewOf(f);
        v.space = MemorySpace::Device;
        v.beauty = static_cast<const float*>(upload(v.beauty.data, 3 * n * 4));
        v.normal = static_cast<const float*>(upload(v.normal.data, 3 * n * 4));
        v.position = static_cast<const float*>(upload(v.position.data, 3 * n * 4));
        v.depth = static_cast<const float*>(upload(v.depth.data, n * 4));
        v.objectId = static_cast<const std::int32_t*>(upload(v.objectId.data, n * 4));
        if (v.albedo) v.albedo = static_cast<const float*>(upload(v.albedo.data, 3 * n * 4));
        return v;
    };
    ComputeDevice device = ComputeDevice::fromCudaStream(stream);
    DenoiserSettings s;
    s.method = Method::Svgf;
    Denoiser first(s, device), second(s, device);
    s.device = DeviceType::Cpu;
    Denoiser reference(s);
    for (const Frame& f : frames) {
        float* out1 = static_cast<float*>(deviceBytes(3 * n * 4));
        float* out2 = static_cast<float*>(deviceBytes(3 * n * 4));
        first.processFrame(deviceView(f), out1);
        second.processFrame(deviceView(f), out2);
        Image expected = reference.processFrame(f), got1(w, h, 3), got2(w, h, 3);
        // The caller's download, after the denoisers' work on its stream.
        ASSERT_EQ(
            cudaMemcpyAsync(got1.pixels.data(), out1, 3 * n * 4, cudaMemcpyDeviceToHost, stream),
            cudaSuccess);
        ASSERT_EQ(
            cudaMemcpyAsync(got2.pixels.data(), out2, 3 * n * 4, cudaMemcpyDeviceToHost, stream),
            cudaSuccess);
        device.synchronize();
        EXPECT_LE(test::maxRelativeDifference(expected, got1), 1e-3);
        EXPECT_LE(test::maxRelativeDifference(expected, got2), 1e-3);
    }
    first.synchronize();
    EXPECT_GT(first.lastFrameStats().deviceMilliseconds, 0.0);

    Frame bad = frames.back();
    bad.objectId[5 * w + 3] = int(bad.objectToWorld.size());
    first.processFrame(deviceView(bad), static_cast<float*>(deviceBytes(3 * n * 4)));
    try {
        first.synchronize();
        ADD_FAILURE() << "a queued frame's bad object ID was not reported";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("1 pixels of the last 1 queued frames"),
                  std::string::npos)
            << e.what();
    }

    // The C API on the same stream.
    RTDDevice cDevice = rtdNewCUDADevice(stream);
    ASSERT_NE(cDevice, nullptr);
    RTDDenoiser cDenoiser = rtdNewDenoiser(cDevice, "svgf");
    Denoiser cReference(s);
    for (const Frame& f : frames) {
        FrameView v = deviceView(f);
        float* out = static_cast<float*>(deviceBytes(3 * n * 4));
        rtdSetImage(cDenoiser, "color", v.beauty.data, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(cDenoiser, "normal", v.normal.data, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(cDenoiser, "position", v.position.data, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(cDenoiser, "depth", v.depth.data, RTD_FORMAT_FLOAT, w, h, 0, 0);
        rtdSetImage(cDenoiser, "ids", v.objectId.data, RTD_FORMAT_INT, w, h, 0, 0);
        rtdSetImage(cDenoiser, "albedo", v.albedo.data, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(cDenoiser, "output", out, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        std::vector<float> m;
        for (const Matrix4& o : f.objectToWorld)
            for (const auto& row : o.m) m.insert(m.end(), row.begin(), row.end());
        for (const Matrix4* o : {&f.worldToCamera, &f.worldToScreen})
            for (const auto& row : o->m) m.insert(m.end(), row.begin(), row.end());
        const int k = int(f.objectToWorld.size());
        rtdSetMatrices(cDenoiser, m.data(), k, m.data() + 16 * k, m.data() + 16 * k + 16);
        ASSERT_EQ(rtdExecute(cDenoiser), RTD_ERROR_NONE);
        Image expected = cReference.processFrame(f), got(w, h, 3);
        ASSERT_EQ(
            cudaMemcpyAsync(got.pixels.data(), out, 3 * n * 4, cudaMemcpyDeviceToHost, stream),
            cudaSuccess);
        ASSERT_EQ(rtdSynchronize(cDevice), RTD_ERROR_NONE);
        EXPECT_LE(test::maxRelativeDifference(expected, got), 1e-3);
    }
    rtdReleaseDenoiser(cDenoiser);
    rtdReleaseDevice(cDevice);
    for (void* p : allocations) cudaFree(p);
    cudaStreamDestroy(stream);
}

// An engine's buffers: RGBA half colour, normal and position with a row pitch, 2-channel float
// motion vectors and no matrices, half RGBA out; in device memory and in host memory. Gives the
// CPU's packed float result on the same (half-rounded) values, to half precision.
TEST(Gpu, HalfRgbaBuffersWithMotionVectors) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames =
        test::withMotion(test::renderSmallSequence("camera-pan", 96, 64, 4), 2);
    const int w = frames[0].width(), h = frames[0].height();
    std::vector<void*> allocations;
    auto toDevice = [&](const std::vector<unsigned char>& host) {
        void* p = nullptr;
        EXPECT_EQ(cudaMalloc(&p, host.size()), cudaSuccess);
        EXPECT_EQ(cudaMemcpy(p, host.data(), host.size(), cudaMemcpyHostToDevice), cudaSuccess);
        allocations.push_back(p);
        return p;
    };
    DenoiserSettings s;
    s.method = Method::Svgf;
    s.device = DeviceType::Cpu;
    Denoiser cpu(s);
    s.device = DeviceType::Cuda;
    Denoiser onDevice(s), fromHost(s);
    const std::size_t outRow = std::size_t(w) * 8 + 64;
    std::vector<unsigned char> out(outRow * h), outFromHost(outRow * h);
    void* deviceOut = toDevice(out);
    for (Frame& f : frames) {
        for (Image* image : {&f.beauty, &f.normal, &f.position})
            image->pixels = test::halfRounded(image->pixels);
        f.albedo.reset();
        Image expected = cpu.processFrame(f);
        auto rgba = [&](const Image& image) {
            return test::strided(image.pixels, w, h, 3, DataType::Float16, 4, 0, 64);
        };
        test::Strided beauty = rgba(f.beauty), normal = rgba(f.normal), position = rgba(f.position);
        FrameView host = viewOf(f);
        host.beauty = beauty.view;
        host.normal = normal.view;
        host.position = position.view;
        FrameView device = host;
        device.space = MemorySpace::Device;
        auto moved = [&](const ImageView& v, std::size_t bytes) {
            std::vector<unsigned char> copy(static_cast<const unsigned char*>(v.data),
                                            static_cast<const unsigned char*>(v.data) + bytes);
            ImageView d = v;
            d.data = toDevice(copy);
            return d;
        };
        const std::size_t n = std::size_t(w) * h;
        device.beauty = moved(beauty.view, beauty.bytes.size());
        device.normal = moved(normal.view, normal.bytes.size());
        device.position = moved(position.view, position.bytes.size());
        device.depth = moved(host.depth, n * 4);
        device.objectId = moved(host.objectId, n * 4);
        device.motion = moved(host.motion, n * 8);
        onDevice.processFrame(device, OutputView{deviceOut, DataType::Float16, 4, 8, outRow});
        fromHost.processFrame(host,
                              OutputView{outFromHost.data(), DataType::Float16, 4, 8, outRow});
        ASSERT_EQ(cudaMemcpy(out.data(), deviceOut, out.size(), cudaMemcpyDeviceToHost),
                  cudaSuccess);
        Image got(w, h, 3), gotFromHost(w, h, 3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    std::uint16_t a, b;
                    std::memcpy(&a, &out[y * outRow + x * 8 + 2 * c], 2);
                    std::memcpy(&b, &outFromHost[y * outRow + x * 8 + 2 * c], 2);
                    got.at(x, y, c) = halfToFloat(a);
                    gotFromHost.at(x, y, c) = halfToFloat(b);
                }
        EXPECT_LE(test::maxRelativeDifference(expected, got), 2e-3);
        EXPECT_EQ(got.pixels, gotFromHost.pixels);
    }
    for (void* p : allocations) cudaFree(p);
}
#endif

}  // namespace
}  // namespace rtd
