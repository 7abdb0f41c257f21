// The learned method's known answer (tests/data/learned_known_answer.txt, written by
// training/infer.py known_answer: 29 inputs, the 14 features and the 3 outputs PyTorch computed
// per pixel, with the weights file beside it), and its pixels run through the mix kernel on a
// device: test_learned (the CPU's instruction sets) and test_gpu (CUDA).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "devices/device.h"
#include "methods/learned_weights.h"

namespace rtd::test {

struct KnownAnswer {
    std::vector<std::vector<float>> inputs, features, outputs;
};

inline std::filesystem::path knownAnswerFolder() {
    return std::filesystem::path(RTD_SOURCE_DIR) / "tests/data";
}

inline KnownAnswer readKnownAnswer() {
    KnownAnswer k;
    std::ifstream in(knownAnswerFolder() / "learned_known_answer.txt");
    std::string line;
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream values(line);
        std::vector<float> all;
        for (float v; values >> v;) all.push_back(v);
        EXPECT_EQ(all.size(), 29u + kLearnedFeatures + 3u) << line;
        if (all.size() != 29u + kLearnedFeatures + 3u) continue;
        k.inputs.emplace_back(all.begin(), all.begin() + 29);
        k.features.emplace_back(all.begin() + 29, all.begin() + 29 + kLearnedFeatures);
        k.outputs.emplace_back(all.end() - 3, all.end());
    }
    return k;
}

inline LearnedNetwork knownAnswerNetwork() {
    return learnedNetwork((knownAnswerFolder() / "learned_known_answer_weights.txt").string());
}

// The tolerance: 1e-4 relative (and 1e-6 absolute for values near 0).
inline bool nearKnownAnswer(float got, float want) {
    return std::fabs(got - want) <= 1e-4f * std::fabs(want) + 1e-6f;
}

// The pixels as one row of planar images in `device`'s memory, through its LearnedMixStep;
// returns the interleaved RGB output.
inline std::vector<float> mixOnDevice(const KnownAnswer& k, const LearnedNetwork& network,
                                      Device& device) {
    const int n = int(k.inputs.size());
    constexpr int kPlanes = 4 * kLearnedCandidates + 4;  // candidates, history, albedo
    std::vector<float> planes(std::size_t(n) * kPlanes);
    std::vector<std::int32_t> keys(static_cast<std::size_t>(n));
    for (int x = 0; x < n; ++x) {
        const std::vector<float>& in = k.inputs[std::size_t(x)];
        for (int c = 0; c < kPlanes; ++c) planes[std::size_t(c) * n + x] = in[std::size_t(c)];
        keys[std::size_t(x)] = in[28] > 0.5f ? 0 : -1;
    }
    const std::size_t planeBytes = planes.size() * sizeof(float);
    const std::size_t keyBytes = keys.size() * sizeof(std::int32_t);
    const std::size_t outBytes = std::size_t(3) * n * sizeof(float);
    auto* devicePlanes = static_cast<float*>(device.allocate(planeBytes));
    auto* deviceKeys = static_cast<std::int32_t*>(device.allocate(keyBytes));
    auto* deviceOut = static_cast<float*>(device.allocate(outBytes));
    device.copyToDevice(devicePlanes, planes.data(), planeBytes);
    device.copyToDevice(deviceKeys, keys.data(), keyBytes);
    const auto plane = [&](int p) { return devicePlanes + std::size_t(p) * n; };
    Layout layout{n, 1, n, 0, 0, n};
    GBufferView g{};
    g.layout = layout;
    g.filterKey = deviceKeys;
    LearnedMixKernel mix{g, {}, plane(24), {deviceOut, n}, network};
    for (int c = 0; c < kLearnedCandidates; ++c) mix.candidates[c] = {plane(4 * c), n};
    device.prepare(layout, {StepKind::LearnedMix});
    device.run(LearnedMixStep{mix});
    device.synchronize();
    std::vector<float> out(std::size_t(3) * n);
    device.copyToHost(out.data(), deviceOut, outBytes);
    // The kernel writes the mix demodulated (planar); the known answer is times the albedo.
    std::vector<float> modulated(out.size());
    for (int x = 0; x < n; ++x)
        for (int c = 0; c < 3; ++c)
            modulated[std::size_t(3 * x + c)] =
                out[std::size_t(c * n + x)] * k.inputs[std::size_t(x)][std::size_t(25 + c)];
    out = modulated;
    device.release(devicePlanes);
    device.release(deviceKeys);
    device.release(deviceOut);
    return out;
}

}  // namespace rtd::test
