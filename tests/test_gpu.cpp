// CPU and CUDA back ends agree (CTest label `gpu`): every method, on a rendered scene and on the
// course scene. Skips, saying why, where the build has no CUDA back end or no GPU is present.
// On a GPU machine: ctest --preset release -L gpu --output-on-failure
#include <gtest/gtest.h>

#include <cmath>

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
            double difference = test::maxRelativeDifference(a, b);
            EXPECT_LE(difference, 1e-3) << what << ", " << toString(method) << ", frame " << i;
        }
    }
}

TEST(Gpu, CpuAndCudaAgreeOnARenderedScene) {
    std::string reason = cudaUnavailableReason();
    if (!reason.empty()) GTEST_SKIP() << "no CUDA: " << reason;
    std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
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
