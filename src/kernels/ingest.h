// Frame ingest: the renderer's interleaved RGB buffers into the denoiser's padded planar ones;
// NaN/Inf in the radiance become 0 and are flagged so the host can count them. With an albedo,
// object pixels are demodulated here (illumination = colour / max(albedo, epsilon)); the
// ModulateKernel multiplies the same factor back at the end.
#pragma once

#include "kernels/views.h"

namespace rtd {

struct IngestKernel {
    Layout layout;
    const float* beautyRgb;    // interleaved, 3 floats per pixel, rows of `width` pixels
    const float* normalRgb;    // interleaved
    const float* positionRgb;  // interleaved
    const float* depthIn;      // 1 float per pixel
    const std::int32_t* idIn;  // 1 int per pixel
    const float* albedoRgb;    // interleaved, or null: albedo 1 (no demodulation)
    float albedoEpsilon;
    Planes3 beauty, albedo, normal, position;
    float* depth;
    std::int32_t* objectId;
    std::uint8_t* nonFiniteCount;  // per pixel (unpadded): radiance values replaced by 0

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex s = PixelIndex(y) * layout.width + x;
        PixelIndex i = layout.index(x, y);
        int bad = 0;
        float c[3];
        for (int k = 0; k < 3; ++k) {
            float v = beautyRgb[3 * s + k];
            bool finite = isFinite(v);
            bad += finite ? 0 : 1;
            c[k] = finite ? v : 0.0f;
        }
        // Background and non-finite albedo: factor 1 (nothing to demodulate, or untrustworthy).
        Float3 a = make3(1.0f, 1.0f, 1.0f);
        if (albedoRgb && idIn[s] >= 0) {
            float r = albedoRgb[3 * s], gr = albedoRgb[3 * s + 1], b = albedoRgb[3 * s + 2];
            bool finite = isFinite(r) && isFinite(gr) && isFinite(b);
            // Per component, not a choice between two vectors (which stops vectorisation).
            a.x = finite ? maxf(r, albedoEpsilon) : 1.0f;
            a.y = finite ? maxf(gr, albedoEpsilon) : 1.0f;
            a.z = finite ? maxf(b, albedoEpsilon) : 1.0f;
        }
        albedo.store(i, a);
        beauty.store(i, make3(c[0] / a.x, c[1] / a.y, c[2] / a.z));
        normal.store(i, make3(normalRgb[3 * s], normalRgb[3 * s + 1], normalRgb[3 * s + 2]));
        position.store(i,
                       make3(positionRgb[3 * s], positionRgb[3 * s + 1], positionRgb[3 * s + 2]));
        depth[i] = depthIn[s];
        objectId[i] = idIn[s];
        nonFiniteCount[s] = std::uint8_t(bad);
    }
};

// Planar RGB back to the caller's interleaved RGB.
struct PackKernel {
    Layout layout;
    Planes3 color;
    float* rgbOut;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex s = PixelIndex(y) * layout.width + x;
        Float3 c = color.load(layout.index(x, y));
        rgbOut[3 * s] = c.x;
        rgbOut[3 * s + 1] = c.y;
        rgbOut[3 * s + 2] = c.z;
    }
};

}  // namespace rtd
