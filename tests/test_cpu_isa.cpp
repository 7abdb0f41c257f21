// The CPU kernels built for each instruction set (run-time dispatch, cpu_kernels.h) give the
// scalar kernels' results: every method, on a rendered scene. Sets this processor lacks are
// skipped, saying so.
#include <gtest/gtest.h>

#include <cmath>

#include "render/render_sequence.h"
#include "test_support.h"

namespace rtd {
namespace {

// max |a - b| / max(|a|, 1e-2) over all values (the GPU test's measure).
double maxRelativeDifference(const Image& a, const Image& b) {
    double worst = 0.0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i)
        worst = std::max(worst, std::abs(double(b.pixels[i]) - a.pixels[i]) /
                                    std::max(std::abs(double(a.pixels[i])), 1e-2));
    return worst;
}

const std::vector<Frame>& renderedFrames() {
    static const std::vector<Frame> frames = [] {
        test::TempFolder dir("cpu-isa-scene");
        render::RenderSettings r;
        r.width = 96;
        r.height = 64;
        r.frames = 4;
        r.gbufferOnly = true;
        render::renderSequence("moving-objects", r, dir.path());
        Sequence sequence(dir.path());
        std::vector<Frame> all;
        for (int i = 0; i < sequence.frameCount(); ++i) all.push_back(sequence.readFrame(i));
        return all;
    }();
    return frames;
}

class CpuIsaTest : public testing::TestWithParam<CpuIsa> {};

TEST_P(CpuIsaTest, AgreesWithTheScalarKernels) {
    CpuIsa isa = GetParam();
    if (int(isa) > int(bestCpuInstructionSet()))
        GTEST_SKIP() << toString(isa) << ": not supported by this processor or build (best: "
                     << toString(bestCpuInstructionSet()) << ")";
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        DenoiserSettings s;
        s.method = method;
        s.device = DeviceType::Cpu;
        s.cpuIsa = CpuIsa::Scalar;
        Denoiser scalar(s);
        s.cpuIsa = isa;
        Denoiser vector(s);
        EXPECT_NE(vector.deviceName().find(toString(isa)), std::string::npos)
            << vector.deviceName();
        for (std::size_t i = 0; i < renderedFrames().size(); ++i) {
            Image a = scalar.processFrame(renderedFrames()[i]);
            Image b = vector.processFrame(renderedFrames()[i]);
            EXPECT_LE(maxRelativeDifference(a, b), 1e-3)
                << toString(isa) << ", " << toString(method) << ", frame " << i;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(EverySet, CpuIsaTest,
                         testing::Values(CpuIsa::Sse2, CpuIsa::Avx2, CpuIsa::Avx512),
                         [](const testing::TestParamInfo<CpuIsa>& info) {
                             return std::string(toString(info.param));
                         });

TEST(CpuIsa, AutoPicksAVectorSetOnX86) {
#if defined(__x86_64__)
    EXPECT_GE(int(bestCpuInstructionSet()), int(CpuIsa::Sse2));
    DenoiserSettings s;
    s.device = DeviceType::Cpu;
    Denoiser d(s);
    EXPECT_NE(d.deviceName().find(toString(bestCpuInstructionSet())), std::string::npos)
        << d.deviceName();
#else
    GTEST_SKIP() << "not an x86-64 build";
#endif
}

}  // namespace
}  // namespace rtd
