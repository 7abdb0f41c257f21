// Frame ingest: the renderer's interleaved RGB buffers into the denoiser's planar ones; NaN/Inf in
// the radiance become 0 and are flagged so the host can count them.
#pragma once

#include "kernels/views.h"

namespace rtd {

struct IngestKernel {
    int width, height;
    const float* beautyRgb;     // interleaved, 3 floats per pixel
    const float* normalRgb;     // interleaved
    const float* positionRgb;   // interleaved
    const float* depthIn;       // 1 float per pixel
    const std::int32_t* idIn;   // 1 int per pixel
    Planes3 beauty, normal, position;
    float* depth;
    std::int32_t* objectId;
    std::uint8_t* nonFiniteCount;  // per pixel: how many of the 3 radiance values were replaced

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::size_t i = std::size_t(y) * width + x;
        std::uint8_t bad = 0;
        float c[3];
        for (int k = 0; k < 3; ++k) {
            float v = beautyRgb[3 * i + k];
            bool finite = isFinite(v);
            bad = std::uint8_t(bad + (finite ? 0 : 1));
            c[k] = finite ? v : 0.0f;
        }
        beauty.store(i, make3(c[0], c[1], c[2]));
        normal.store(i, make3(normalRgb[3 * i], normalRgb[3 * i + 1], normalRgb[3 * i + 2]));
        position.store(i,
                       make3(positionRgb[3 * i], positionRgb[3 * i + 1], positionRgb[3 * i + 2]));
        depth[i] = depthIn[i];
        objectId[i] = idIn[i];
        nonFiniteCount[i] = bad;
    }
};

// Planar RGB back to the caller's interleaved RGB.
struct PackKernel {
    int width, height;
    Planes3 color;
    float* rgbOut;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::size_t i = std::size_t(y) * width + x;
        Float3 c = color.load(i);
        rgbOut[3 * i] = c.x;
        rgbOut[3 * i + 1] = c.y;
        rgbOut[3 * i + 2] = c.z;
    }
};

}  // namespace rtd
