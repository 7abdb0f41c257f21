// The straightforward joint bilateral filter a user would write first (the course's code shape):
// interleaved RGB, std::exp and std::acos per tap, bounds tests in the inner loop; rows spread
// over `threads` cores. The baseline the benchmarks quote their speed-ups against.
#pragma once

#include <algorithm>
#include <cmath>

#include "rtdenoise/image.h"
#include "rtdenoise/settings.h"

namespace rtd::bench {

inline void baselineJbf(const Frame& f, const DenoiserSettings& s, Image& out, int threads) {
    const int w = f.width(), h = f.height(), r = s.jbf.radius;
    out = Image(w, h, 3);
    auto sq = [](float v) { return v * v; };
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const int idI = f.objectId[std::size_t(y) * w + x];
            if (idI < 0) {
                for (int c = 0; c < 3; ++c) out.at(x, y, c) = f.beauty.at(x, y, c);
                continue;
            }
            float sum[3] = {0, 0, 0}, sumW = 0;
            for (int py = y - r; py <= y + r; ++py) {
                for (int px = x - r; px <= x + r; ++px) {
                    if (px < 0 || py < 0 || px >= w || py >= h) continue;
                    if (f.objectId[std::size_t(py) * w + px] != idI) continue;
                    float dc2 = 0, dot = 0, dp2 = 0, along = 0;
                    for (int c = 0; c < 3; ++c) {
                        dc2 += sq(f.beauty.at(x, y, c) - f.beauty.at(px, py, c));
                        dot += f.normal.at(x, y, c) * f.normal.at(px, py, c);
                        float dp = f.position.at(px, py, c) - f.position.at(x, y, c);
                        dp2 += dp * dp;
                        along += f.normal.at(x, y, c) * dp;
                    }
                    float dNormal = std::acos(std::clamp(dot, -1.0f, 1.0f));
                    float dPlane = dp2 > 0 ? along / std::sqrt(dp2) : 0.0f;
                    float weight = std::exp(-float(sq(float(px - x)) + sq(float(py - y))) /
                                                (2 * sq(s.jbf.sigmaCoord)) -
                                            dc2 / (2 * sq(s.edges.sigmaColor)) -
                                            sq(dNormal) / (2 * sq(s.edges.sigmaNormal)) -
                                            sq(dPlane) / (2 * sq(s.edges.sigmaPlane)));
                    for (int c = 0; c < 3; ++c) sum[c] += weight * f.beauty.at(px, py, c);
                    sumW += weight;
                }
            }
            for (int c = 0; c < 3; ++c) out.at(x, y, c) = sum[c] / sumW;
        }
    }
}

}  // namespace rtd::bench
