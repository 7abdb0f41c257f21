// The learned method (issue 39): its weights files are checked, its kernel equals the PyTorch
// forward pass on a committed known answer (training/infer.py wrote it) on every CPU instruction
// set, its output is a weighted average of its candidates whatever the weights, and its mix sits
// in detail's passes where detail's last level was.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "devices/device.h"
#include "learned_known_answer.h"
#include "methods/learned_weights.h"
#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"
#include "test_support.h"
#include "tuning.h"

#ifndef RTD_SOURCE_DIR
#error "RTD_SOURCE_DIR: the repository, for tests/data"
#endif

namespace rtd {
namespace {

namespace fs = std::filesystem;

void writeText(const fs::path& file, const std::string& text) {
    std::ofstream(file, std::ios::binary) << text;
}

// `body` (every line before the checksum's) with a correct checksum line.
std::string withChecksum(const std::string& body) {
    char line[32];
    std::snprintf(line, sizeof line, "fnv1a32 %08x\n", learnedWeightsChecksum(body));
    return body + line;
}
std::string bodyOf(const std::string& file) {
    return file.substr(0, file.rfind("fnv1a32 "));
}

// The error parseLearnedWeights gives `text`, or "" where it parses.
std::string refusal(const std::string& text) {
    try {
        parseLearnedWeights(text, "w.txt");
        return "";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidInput);
        return e.what();
    }
}

TEST(LearnedWeights, TheBuiltInWeightsParse) {
    EXPECT_EQ(refusal(std::string(builtInLearnedWeights())), "");
}

TEST(LearnedWeights, BadFilesAreRefusedNamingTheProblem) {
    const std::string good(builtInLearnedWeights());
    EXPECT_NE(refusal(good.substr(0, good.size() / 2)).find("truncated"), std::string::npos);
    std::string edited = good;
    edited[good.find("w1 ") + 3] = edited[good.find("w1 ") + 3] == '1' ? '2' : '1';
    EXPECT_NE(refusal(edited).find("checksum"), std::string::npos);
    std::string body = bodyOf(good);
    std::string shape = body;
    shape.replace(shape.find("14 16 16 6"), 10, "14 32 32 6");
    EXPECT_NE(refusal(withChecksum(shape)).find("line 2"), std::string::npos);
    std::string missing = body;
    missing.erase(missing.rfind(' '));  // b3's last value
    missing += "\n";
    EXPECT_NE(refusal(withChecksum(missing)).find("block 'b3' has 5 values, not 6"),
              std::string::npos)
        << refusal(withChecksum(missing));
    std::string infinite = body;
    infinite.insert(infinite.find("b1 ") + 3, "inf ");
    EXPECT_NE(refusal(withChecksum(infinite)).find("not a finite number"), std::string::npos);
    std::string huge = body;
    huge.insert(huge.find("b1 ") + 3, "1e99 ");
    EXPECT_NE(refusal(withChecksum(huge)).find("'1e99' in block 'b1' is not a finite number"),
              std::string::npos)
        << refusal(withChecksum(huge));
    // A value below a float's range reads as a denormal or 0, not as an error.
    std::string tiny = body;
    const std::size_t first = tiny.find("b1 ") + 3;
    tiny.replace(first, tiny.find(' ', first) - first, "1e-42");
    EXPECT_EQ(refusal(withChecksum(tiny)), "");
    // A network trained for another range, and format 1, which did not say which range.
    std::string range = body;
    range.replace(range.find("l0-margin 2"), 11, "l0-margin 1");
    EXPECT_NE(refusal(withChecksum(range)).find("line 3 is 'range l0-margin 1'"), std::string::npos)
        << refusal(withChecksum(range));
    std::string format1 = body;
    format1.replace(0, 19, "rtdenoise-weights 1");
    format1.erase(format1.find("range l0-margin 2\n"), 18);
    EXPECT_NE(refusal(withChecksum(format1)).find("format 1"), std::string::npos)
        << refusal(withChecksum(format1));
    EXPECT_NE(refusal("hello\n").find("first line"), std::string::npos);
    EXPECT_EQ(refusal(withChecksum(body)), "");  // the round trip
}

TEST(LearnedWeights, ADenoiserRefusesABadFileBeforeAnyFrame) {
    test::TempFolder dir("learned-weights");
    const fs::path truncated = dir.path() / "truncated.txt";
    const std::string good(builtInLearnedWeights());
    writeText(truncated, good.substr(0, good.size() - 20));
    DenoiserSettings s = test::cpuSettings(Method::Learned);
    s.learned.weights = truncated.string();
    try {
        Denoiser denoiser(s);
        FAIL() << "a truncated weights file was accepted";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(truncated.string()), std::string::npos) << e.what();
    }
    s.learned.weights = (dir.path() / "absent.txt").string();
    try {
        Denoiser denoiser(s);
        FAIL() << "a missing weights file was accepted";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::MissingFile);
        EXPECT_NE(std::string(e.what()).find("absent.txt"), std::string::npos) << e.what();
    }
}

// A network whose softmax puts all its weight on one candidate, as a weights file: every weight
// 0, the last layer's bias 80 for that candidate.
std::string pickingWeights(int candidate) {
    std::string body =
        "rtdenoise-weights 2\nnetwork learned-mix 14 16 16 6\nrange l0-margin 2\ntrained test\n";
    const auto block = [&](const char* name, int count, int hot) {
        body += name;
        for (int i = 0; i < count; ++i) body += i == hot ? " 80" : " 0";
        body += "\n";
    };
    block("w1", 14 * 16, -1);
    block("b1", 16, -1);
    block("w2", 16 * 16, -1);
    block("b2", 16, -1);
    block("w3", 16 * 6, -1);
    block("b3", 6, candidate);
    return withChecksum(body);
}

// The mix sits where detail's last A-Trous level was: weights that pick level 5 give detail's
// output (its levels are detail's, and the stabilisation and energy passes follow as in
// detail); weights that pick L0, the unfiltered accumulation, give another.
TEST(Learned, PickingTheLastLevelGivesDetailsOutput) {
    test::TempFolder dir("learned-pick");
    const std::vector<Frame> frames = test::renderSmallSequence("moving-objects");
    Denoiser detail(test::cpuSettings(Method::Detail));
    std::vector<Image> expected;
    for (const Frame& frame : frames) expected.push_back(detail.processFrame(frame));
    for (int candidate : {5, 0}) {
        const fs::path file = dir.path() / ("pick" + std::to_string(candidate) + ".txt");
        writeText(file, pickingWeights(candidate));
        DenoiserSettings s = test::cpuSettings(Method::Learned);
        s.learned.weights = file.string();
        Denoiser learned(s);
        for (std::size_t i = 0; i < frames.size(); ++i) {
            const double difference =
                test::maxRelativeDifference(expected[i], learned.processFrame(frames[i]));
            if (candidate == 5)
                EXPECT_LE(difference, 1e-5) << "frame " << i;
            else
                EXPECT_GE(difference, 0.05) << "frame " << i;
        }
    }
}

std::vector<float> mixOnCpu(const test::KnownAnswer& k, const LearnedNetwork& network, CpuIsa isa) {
    std::unique_ptr<Device> device = createCpuDevice(isa);
    return test::mixOnDevice(k, network, *device);
}

TEST(Learned, KernelEqualsThePyTorchForwardPassOnEveryInstructionSet) {
    const test::KnownAnswer k = test::readKnownAnswer();
    ASSERT_GE(k.inputs.size(), 8u);
    const LearnedNetwork network = test::knownAnswerNetwork();
    const auto near = test::nearKnownAnswer;
    for (std::size_t p = 0; p < k.inputs.size(); ++p) {
        const std::vector<float>& in = k.inputs[p];
        Float3 c[kLearnedCandidates];
        float variance[kLearnedCandidates], f[kLearnedFeatures];
        for (int j = 0; j < kLearnedCandidates; ++j) {
            c[j] = make3(in[4 * j], in[4 * j + 1], in[4 * j + 2]);
            variance[j] = in[4 * j + 3];
        }
        learnedFeatures(c, variance, in[24], f);
        for (int j = 0; j < kLearnedFeatures; ++j)
            EXPECT_TRUE(near(f[j], k.features[p][std::size_t(j)]))
                << "pixel " << p << ", feature " << j << ": " << f[j] << " against "
                << k.features[p][std::size_t(j)];
    }
    for (CpuIsa isa : {CpuIsa::Scalar, CpuIsa::Sse2, CpuIsa::Avx2, CpuIsa::Avx512}) {
        if (int(isa) > int(bestCpuInstructionSet())) continue;
        const std::vector<float> out = mixOnCpu(k, network, isa);
        for (std::size_t p = 0; p < k.inputs.size(); ++p)
            for (int c = 0; c < 3; ++c)
                EXPECT_TRUE(near(out[3 * p + std::size_t(c)], k.outputs[p][std::size_t(c)]))
                    << toString(isa) << ", pixel " << p << ", channel " << c << ": "
                    << out[3 * p + std::size_t(c)] << " against " << k.outputs[p][std::size_t(c)];
    }
}

// Whatever the weights (large random ones here), each channel of the output lies between L0's and
// L5's (the unfiltered and the most filtered candidate), times the albedo: a weighted average,
// nothing invented, and no middle level's overshoot beside a light (docs/learned.md).
TEST(Learned, OutputLiesBetweenTheUnfilteredAndTheMostFilteredCandidateWhateverTheWeights) {
    const test::KnownAnswer k = test::readKnownAnswer();
    ASSERT_FALSE(k.inputs.empty());
    LearnedNetwork network{};
    std::uint32_t state = 7u;
    const auto next = [&] {
        state = state * 1664525u + 1013904223u;
        return 40.0f * (float(state >> 8) / float(1 << 24) - 0.5f);
    };
    for (auto& row : network.w1)
        for (float& v : row) v = next();
    for (auto& row : network.w2)
        for (float& v : row) v = next();
    for (auto& row : network.w3)
        for (float& v : row) v = next();
    for (float& v : network.b3) v = next();
    const std::vector<float> out = mixOnCpu(k, network, bestCpuInstructionSet());
    for (std::size_t p = 0; p < k.inputs.size(); ++p) {
        const std::vector<float>& in = k.inputs[p];
        for (int c = 0; c < 3; ++c) {
            const float last = in[std::size_t(4 * (kLearnedCandidates - 1) + c)];
            const float lo = std::min(in[std::size_t(c)], last);
            const float hi = std::max(in[std::size_t(c)], last);
            const float albedo = in[std::size_t(25 + c)];
            const float got = out[3 * p + std::size_t(c)];
            EXPECT_TRUE(std::isfinite(got));
            EXPECT_GE(got, lo * albedo - 1e-5f * std::fabs(lo * albedo)) << "pixel " << p;
            EXPECT_LE(got, hi * albedo + 1e-5f * std::fabs(hi * albedo)) << "pixel " << p;
        }
    }
}

// The network may move the output from L5 towards L0 only by how far L0 lies beyond its own
// noise (kLearnedL0NoiseMargin standard errors of its mean): a network that takes L0 alone gives
// L5 where L0 is within its noise of it, L0 where L0 is exact, and half-way where L0 lies twice
// the margin's standard errors from L5 (docs/learned.md).
TEST(Learned, TheUnfilteredCandidateMovesTheOutputOnlyByWhatLiesBeyondItsNoise) {
    LearnedNetwork takesL0{};
    takesL0.b3[0] = 60.0f;  // softmax weight of L0: 1 - 5e-26
    const Float3 l5 = make3(0.4f, 0.5f, 0.6f), l0 = make3(0.8f, 1.0f, 1.2f);
    const float gap = luminance(l0) - luminance(l5);
    // L0's standard error, in margins: twice the gap, none, half the gap; the expected share of
    // L0 - L5.
    const float margin = kLearnedL0NoiseMargin;
    const float errors[] = {2.0f * gap / margin, 0.0f, 0.5f * gap / margin},
                shares[] = {0.0f, 1.0f, 0.5f};
    test::KnownAnswer k;
    for (float e : errors) {
        std::vector<float> in(29, 0.0f);
        for (int j = 0; j < kLearnedCandidates; ++j) {
            const Float3 v = j == 0 ? l0 : l5;
            in[std::size_t(4 * j)] = v.x;
            in[std::size_t(4 * j + 1)] = v.y;
            in[std::size_t(4 * j + 2)] = v.z;
        }
        in[3] = e * e;
        in[24] = 8.0f;
        in[25] = in[26] = in[27] = 1.0f;
        in[28] = 1.0f;
        k.inputs.push_back(in);
    }
    const std::vector<float> out = mixOnCpu(k, takesL0, bestCpuInstructionSet());
    for (std::size_t p = 0; p < k.inputs.size(); ++p) {
        const Float3 expected = l5 + (l0 - l5) * shares[p];
        const float want[] = {expected.x, expected.y, expected.z};
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(out[3 * p + std::size_t(c)], want[c], 1e-5f)
                << "case " << p << ", channel " << c;
    }
}

}  // namespace
}  // namespace rtd
