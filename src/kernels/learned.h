// The learned method's mix (docs/learned.md): per pixel, a small network over 14 features of six
// candidates (the accumulated illumination and detail's five A-Trous levels of it) gives softmax
// weights, and the output is the candidates' weighted sum. Every candidate is a
// weighted average of input radiance, so the output is one too: nothing the network does can
// make a finite input's output non-finite or brighter than what the filters saw.
// The same arithmetic, in float32, is training/features.py's and training/model.py's.
#pragma once

#include "kernels/modulate.h"
#include "kernels/views.h"

namespace rtd {

constexpr int kLearnedCandidates = 6;  // L0 (accumulated) and A-Trous levels 1..5
constexpr int kLearnedFeatures = 14;
constexpr int kLearnedHidden = 16;
constexpr float kLearnedMaxHistory = 32.0f;  // feature f1's cap, frames

// The network's parameters, [out][in] row-major (the weights file's order).
struct LearnedNetwork {
    float w1[kLearnedHidden][kLearnedFeatures];
    float b1[kLearnedHidden];
    float w2[kLearnedHidden][kLearnedHidden];
    float b2[kLearnedHidden];
    float w3[kLearnedCandidates][kLearnedHidden];
    float b3[kLearnedCandidates];
};

// log(1 + x) for x >= 0 (vectorises on the CPU).
RTD_HOST_DEVICE RTD_INLINE float log1pPositive(float x) {
    return log2Positive(1.0f + x) * 0.693147181f;
}
RTD_HOST_DEVICE RTD_INLINE float softsign(float x) {
    return x / (1.0f + absf(x));
}

// The 14 features of one pixel (docs/learned.md): the noise relative to the signal, the history,
// how far each level moved the luminance in units of the noise, and each level's remaining noise.
RTD_HOST_DEVICE RTD_INLINE void learnedFeatures(const Float3 (&c)[kLearnedCandidates],
                                                const float (&variance)[kLearnedCandidates],
                                                float history, float (&f)[kLearnedFeatures]) {
    float l[kLearnedCandidates];
    RTD_UNROLL
    for (int k = 0; k < kLearnedCandidates; ++k) l[k] = luminance(c[k]);
    const float ref = 0.5f * (absf(l[0]) + absf(l[kLearnedCandidates - 1])) + 1e-4f;
    const float inverseRef = 1.0f / ref;
    const float s0 = std::sqrt(maxf(variance[0], 0.0f));
    const float inverseNoise = 1.0f / (s0 + 0.1f * ref);
    f[0] = log1pPositive(s0 * inverseRef);
    f[1] = minf(history, kLearnedMaxHistory) * (1.0f / kLearnedMaxHistory);
    f[2] = 1.0f / maxf(history, 1.0f);
    RTD_UNROLL
    for (int j = 0; j < kLearnedCandidates - 1; ++j)
        f[3 + j] = softsign((l[j + 1] - l[j]) * inverseNoise);
    RTD_UNROLL
    for (int k = 0; k < kLearnedCandidates; ++k)
        f[3 + kLearnedCandidates - 1 + k] =
            log1pPositive(std::sqrt(maxf(variance[k], 0.0f)) * inverseRef);
}

// out = relu(w in + b): one hidden layer.
template <int Out, int In>
RTD_HOST_DEVICE RTD_INLINE void denseRelu(const float (&w)[Out][In], const float (&b)[Out],
                                          const float (&in)[In], float (&out)[Out]) {
    RTD_UNROLL
    for (int o = 0; o < Out; ++o) {
        float s = b[o];
        RTD_UNROLL
        for (int i = 0; i < In; ++i) s += w[o][i] * in[i];
        out[o] = maxf(s, 0.0f);
    }
}

// The softmax weights of the candidates.
RTD_HOST_DEVICE RTD_INLINE void learnedWeights(const LearnedNetwork& n,
                                               const float (&f)[kLearnedFeatures],
                                               float (&w)[kLearnedCandidates]) {
    float h1[kLearnedHidden], h2[kLearnedHidden];
    denseRelu(n.w1, n.b1, f, h1);
    denseRelu(n.w2, n.b2, h1, h2);
    float z[kLearnedCandidates];
    float top = -3.0e38f;
    RTD_UNROLL
    for (int o = 0; o < kLearnedCandidates; ++o) {
        float s = n.b3[o];
        RTD_UNROLL
        for (int i = 0; i < kLearnedHidden; ++i) s += n.w3[o][i] * h2[i];
        z[o] = s;
        top = maxf(top, s);
    }
    float sum = 0.0f;
    RTD_UNROLL
    for (int o = 0; o < kLearnedCandidates; ++o) {
        w[o] = exp2Negative((z[o] - top) * kLog2e);
        sum += w[o];
    }
    const float inverse = 1.0f / sum;  // >= 1: the largest term is 2^0
    RTD_UNROLL
    for (int o = 0; o < kLearnedCandidates; ++o) w[o] *= inverse;
}

// How many standard errors of L0's mean the range's L0 end is drawn towards L5 (learnedRangeEnd;
// chosen on held-out train sequences: docs/learned.md).
constexpr float kLearnedL0NoiseMargin = 2.0f;

// The unfiltered end of the mix's range: L0 drawn towards L5 by kLearnedL0NoiseMargin standard
// errors of L0's mean (its luminance variance v0), so that L0 moves the output from L5 only by
// what lies beyond its own noise. A history still holding a light that has moved on sits within
// its noise of L5, and the network had trusted it (docs/learned.md). Between L0 and L5.
RTD_HOST_DEVICE RTD_INLINE Float3 learnedRangeEnd(const Float3& l0, const Float3& l5, float v0) {
    const float gap = absf(luminance(l0) - luminance(l5));
    const float beyondNoise = maxf(gap - kLearnedL0NoiseMargin * std::sqrt(maxf(v0, 0.0f)), 0.0f);
    return l5 + (l0 - l5) * (beyondNoise / maxf(gap, 1e-20f));
}

// The mix, demodulated, into `out` (detail's stabilisation multiplies the albedo back).
// Background (a filter key below 0) passes the accumulated illumination through, as the
// A-Trous iterations do.
struct LearnedMixKernel {
    GBufferView g;
    PlaneSet candidates[kLearnedCandidates];  // rgb + variance each
    const float* historyLength;
    Planes3 out;
    LearnedNetwork network;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const PixelIndex i = g.layout.index(x, y);
        Float3 c[kLearnedCandidates];
        float variance[kLearnedCandidates];
        RTD_UNROLL
        for (int k = 0; k < kLearnedCandidates; ++k) {
            c[k] = candidates[k].rgb().load(i);
            variance[k] = candidates[k].at(3, i);
        }
        float f[kLearnedFeatures], w[kLearnedCandidates];
        learnedFeatures(c, variance, historyLength[i], f);
        learnedWeights(network, f, w);
        Float3 mix = c[0] * w[0];
        RTD_UNROLL
        for (int k = 1; k < kLearnedCandidates; ++k) mix += c[k] * w[k];
        // Kept between the most filtered candidate and the unfiltered one drawn towards it
        // (learnedRangeEnd), per channel (the box [e, e] grown to hold L5): beside a light or a
        // highlight the middle levels blur its radiance into the pixel beyond both, and the
        // network, which sees few such pixels, does not learn to avoid them (docs/learned.md).
        // Still a weighted average of the candidates.
        const Float3 end = learnedRangeEnd(c[0], c[kLearnedCandidates - 1], variance[0]);
        mix = clampToBoxHolding(mix, end, end, c[kLearnedCandidates - 1]);
        const bool foreground = g.filterKey[i] >= 0;
        // Per component (a selected vector would stop the CPU vectorising the kernel).
        out.store(i, make3(foreground ? mix.x : c[0].x, foreground ? mix.y : c[0].y,
                           foreground ? mix.z : c[0].z));
    }
};

}  // namespace rtd
