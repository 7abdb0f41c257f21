#include "render/confidence.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace rtd::render {
namespace {

constexpr int kStratum = 3;  // A-SVGF's 3x3 pixel strata: one gradient sample each

std::uint64_t mix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// A stratum's gradient samples (those whose point now lies in it) and its G-buffer at its
// centre pixel (for the edge stops).
struct Stratum {
    float sumDelta = 0.0f;  // of |L_new - L_old|
    float sumMax = 0.0f;    // of max(L_new, L_old)
    Vec3 normal;            // (0, 0, 0) on background
    float depth = 0.0f;
};

// Whether two strata lie on one surface, so that their gradients may be pooled: a gradient seen
// on the floor says nothing of the wall beside it.
bool sameSurface(const Stratum& a, const Stratum& b) {
    if (dot(a.normal, b.normal) < 0.9f) return false;
    return std::abs(a.depth - b.depth) <= 0.1f * std::max(a.depth, b.depth);
}

}  // namespace

Image historyConfidence(const Scene& previous, const Scene& current, const Frame& gbuffer,
                        const TraceSettings& trace, const ConfidenceSettings& settings) {
    const int width = trace.width, height = trace.height;
    const int columns = (width + kStratum - 1) / kStratum;
    const int rows = (height + kStratum - 1) / kStratum;
    std::vector<PixelCoord> pixels(std::size_t(columns) * rows);
    for (int sy = 0; sy < rows; ++sy) {
        for (int sx = 0; sx < columns; ++sx) {
            // A new pixel per frame, so that over frames every pixel's lighting is probed.
            const int w = std::min(kStratum, width - sx * kStratum);
            const int h = std::min(kStratum, height - sy * kStratum);
            const std::uint64_t stratum = std::uint64_t(sy) * std::uint64_t(columns) + sx;
            std::uint64_t hash = mix((std::uint64_t(trace.seed) << 32) ^ 0x6772616469656e74ull);
            hash = mix(hash ^ std::uint64_t(std::uint32_t(trace.frameIndex)));
            const int pick = int(mix(hash ^ stratum) % std::uint64_t(w * h));
            pixels[stratum] = {sx * kStratum + pick % w, sy * kStratum + pick / w};
        }
    }
    // Last frame's beauty sample 0 (its random numbers), then and re-shaded now.
    TraceSettings last = trace;
    last.frameIndex = trace.frameIndex - 1;
    last.stream = kBeautyStream;
    const std::vector<GradientSample> samples =
        traceGradientSamples(previous, current, last, pixels);

    std::vector<Stratum> strata(pixels.size());
    for (int sy = 0; sy < rows; ++sy) {
        for (int sx = 0; sx < columns; ++sx) {
            const int x = std::min(width - 1, sx * kStratum + 1);
            const int y = std::min(height - 1, sy * kStratum + 1);
            Stratum& s = strata[std::size_t(sy) * columns + sx];
            s.normal = {gbuffer.normal.at(x, y, 0), gbuffer.normal.at(x, y, 1),
                        gbuffer.normal.at(x, y, 2)};
            s.depth = gbuffer.depth.at(x, y);
        }
    }
    for (const GradientSample& g : samples) {
        if (!g.valid) continue;
        const float lOld = std::max(0.0f, luminance(g.before));
        const float lNew = std::max(0.0f, luminance(g.now));
        Stratum& s = strata[std::size_t(g.pixel.y / kStratum) * columns + g.pixel.x / kStratum];
        s.sumDelta += std::abs(lNew - lOld);
        s.sumMax += std::max(lNew, lOld);
    }

    // The ratio of sums, not the mean of ratios: a dim sample's noisy ratio weighs as little as
    // its luminance (A-SVGF normalises its filtered gradient by the filtered maximum likewise).
    Image confidence(width, height, 1, 1.0f);
    const int r = std::clamp(settings.filterRadius, 0, 16);
#pragma omp parallel for schedule(monotonic : dynamic)
    for (int sy = 0; sy < rows; ++sy) {
        for (int sx = 0; sx < columns; ++sx) {
            const Stratum& centre = strata[std::size_t(sy) * columns + sx];
            double sumDelta = 0.0, sumMax = 0.0;
            for (int qy = std::max(0, sy - r); qy <= std::min(rows - 1, sy + r); ++qy) {
                for (int qx = std::max(0, sx - r); qx <= std::min(columns - 1, sx + r); ++qx) {
                    const Stratum& q = strata[std::size_t(qy) * columns + qx];
                    if (&q != &centre && !sameSurface(centre, q)) continue;
                    sumDelta += q.sumDelta;
                    sumMax += q.sumMax;
                }
            }
            const double lambda = sumMax > 0.0 ? sumDelta / sumMax : 0.0;
            const float value = float(std::clamp(1.0 - settings.gain * lambda, 0.0, 1.0));
            for (int y = sy * kStratum; y < std::min(height, (sy + 1) * kStratum); ++y)
                for (int x = sx * kStratum; x < std::min(width, (sx + 1) * kStratum); ++x)
                    confidence.at(x, y) = value;
        }
    }
    return confidence;
}

}  // namespace rtd::render
