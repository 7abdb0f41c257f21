// The CPU kernels built for each instruction set (run-time dispatch, cpu_kernels.h) give the
// scalar kernels' results: every method, on a rendered scene. Sets this processor lacks are
// skipped, saying so.
#include <gtest/gtest.h>

#include <cmath>

#include "test_support.h"
#include "tuning.h"

namespace rtd {
namespace {

const std::vector<Frame>& renderedFrames() {
    static const std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
    return frames;
}

class CpuIsaTest : public testing::TestWithParam<CpuIsa> {};

TEST_P(CpuIsaTest, AgreesWithTheScalarKernels) {
    CpuIsa isa = GetParam();
    if (int(isa) > int(bestCpuInstructionSet()))
        GTEST_SKIP() << toString(isa) << ": not supported by this processor or build (best: "
                     << toString(bestCpuInstructionSet()) << ")";
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf,
                          Method::Detail, Method::Learned}) {
        DenoiserSettings s;
        s.method = method;
        s.device = DeviceType::Cpu;
        Denoiser scalar = makeTunedDenoiser(s, {CpuIsa::Scalar});
        Denoiser vector = makeTunedDenoiser(s, {isa});
        EXPECT_NE(vector.deviceName().find(toString(isa)), std::string::npos)
            << vector.deviceName();
        for (std::size_t i = 0; i < renderedFrames().size(); ++i) {
            Image a = scalar.processFrame(renderedFrames()[i]);
            Image b = vector.processFrame(renderedFrames()[i]);
            EXPECT_LE(test::maxRelativeDifference(a, b), test::backEndTolerance(method))
                << toString(isa) << ", " << toString(method) << ", frame " << i;
        }
    }
}

// The split signal's kernels (DetailSplit, the specular reprojection with its virtual motion) on
// the reflection scene rendered with the split inputs.
TEST_P(CpuIsaTest, AgreesWithTheScalarKernelsOnTheSplitSignal) {
    CpuIsa isa = GetParam();
    if (int(isa) > int(bestCpuInstructionSet()))
        GTEST_SKIP() << toString(isa) << ": not supported by this processor or build (best: "
                     << toString(bestCpuInstructionSet()) << ")";
    static const std::vector<Frame> frames =
        test::renderSmallSequence("reflections", 96, 64, 4, true);
    ASSERT_TRUE(frames[0].specular && frames[0].roughness && frames[0].hitDistance);
    DenoiserSettings s;
    s.method = Method::Detail;
    s.device = DeviceType::Cpu;
    Denoiser scalar = makeTunedDenoiser(s, {CpuIsa::Scalar});
    Denoiser vector = makeTunedDenoiser(s, {isa});
    for (std::size_t i = 0; i < frames.size(); ++i) {
        Image a = scalar.processFrame(frames[i]);
        Image b = vector.processFrame(frames[i]);
        EXPECT_LE(test::maxRelativeDifference(a, b), 1e-3) << toString(isa) << ", frame " << i;
    }
}

INSTANTIATE_TEST_SUITE_P(EverySet, CpuIsaTest,
                         testing::Values(CpuIsa::Sse2, CpuIsa::Avx2, CpuIsa::Avx512),
                         [](const testing::TestParamInfo<CpuIsa>& info) {
                             return std::string(toString(info.param));
                         });

TEST(CpuIsa, AutoPicksTheWidestSetThisProcessorSupports) {
    CpuIsa best = bestCpuInstructionSet();
    DenoiserSettings s;
    s.device = DeviceType::Cpu;
    Denoiser automatic(s);
    Denoiser chosen = makeTunedDenoiser(s, {best});
    EXPECT_EQ(automatic.deviceName(), chosen.deviceName());
    EXPECT_NE(automatic.deviceName().find(toString(best)), std::string::npos)
        << automatic.deviceName();
    // A wider set than the processor has is refused, naming it (not testable on AVX-512).
    if (best != CpuIsa::Avx512) {
        const CpuIsa wider = CpuIsa(int(best) + 1);
        try {
            Denoiser refused = makeTunedDenoiser(s, {wider});
            ADD_FAILURE() << toString(wider) << " was accepted";
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(toString(wider)), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace rtd
