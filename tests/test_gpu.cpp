// CPU and CUDA back ends agree (CTest label `gpu`): every method, on a rendered scene and on the
// course scene. Skips, saying why, where the build has no CUDA back end or no GPU is present.
// On a GPU machine: ctest --preset release -L gpu --output-on-failure
#include <gtest/gtest.h>

#include <cmath>

#include "render/render_sequence.h"
#include "test_support.h"

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

// max |gpu - cpu| / max(|cpu|, 1e-2) over all values.
double maxRelativeDifference(const Image& cpu, const Image& gpu) {
    double worst = 0.0;
    for (std::size_t i = 0; i < cpu.pixels.size(); ++i)
        worst = std::max(worst, std::abs(double(gpu.pixels[i]) - cpu.pixels[i]) /
                                    std::max(std::abs(double(cpu.pixels[i])), 1e-2));
    return worst;
}

void expectBackEndsAgree(const std::vector<Frame>& frames, const char* what) {
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        DenoiserSettings s;
        s.method = method;
        s.device = DeviceType::Cpu;
        Denoiser cpu(s);
        s.device = DeviceType::Cuda;
        Denoiser gpu(s);
        for (std::size_t i = 0; i < frames.size(); ++i) {
            Image a = cpu.processFrame(frames[i]), b = gpu.processFrame(frames[i]);
            double difference = maxRelativeDifference(a, b);
            EXPECT_LE(difference, 1e-3) << what << ", " << toString(method) << ", frame " << i;
        }
    }
}

TEST(Gpu, CpuAndCudaAgreeOnARenderedScene) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    test::TempFolder dir("gpu-scene");
    render::RenderSettings r;
    r.width = 96;
    r.height = 64;
    r.frames = 4;
    r.gbufferOnly = true;
    render::renderSequence("moving-objects", r, dir.path());
    Sequence sequence(dir.path());
    std::vector<Frame> frames;
    for (int i = 0; i < sequence.frameCount(); ++i) frames.push_back(sequence.readFrame(i));
    expectBackEndsAgree(frames, "moving-objects");
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

}  // namespace
}  // namespace rtd
