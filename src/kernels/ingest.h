// Frame ingest: the renderer's interleaved RGB buffers into the denoiser's padded planar ones;
// NaN/Inf in the radiance become 0 and object IDs outside -1..objectCount-1 become background
// (-1), both flagged so the host can count them: the check runs on the device, in parallel, and
// no kernel ever indexes the object matrices with a bad ID (device-memory inputs included).
// Radiance beyond +-kMaxRadiance is clamped to it (flagged): the filters' sums of squares stay
// finite at any finite input. Normals are normalised; a zero or non-finite one is stored as 0 and
// flagged, and the pixel's filter key marks it (views.h: the pixels without a normal filter
// among themselves, their normal terms neutral). The ingest writes the filter keys. A
// pixel whose position or depth is not finite (degenerate geometry) becomes background, its
// geometry 0: it passes through and no filter or history test reads its NaN. With an albedo,
// object pixels are demodulated here (illumination = colour / clamp(albedo, epsilon,
// kMaxRadiance), itself within +-kMaxRadiance); the ModulateKernel multiplies the same factor
// back at the end.
#pragma once

#include "kernels/views.h"
#include "rtdenoise/image.h"

namespace rtd {

// InterleavedGuide: writes normal and depth interleaved (views.h: NormalDepth4) instead of their
// planes, the GPU's layout for SVGF: its passes then read them from there.
template <bool InterleavedGuide = false>
struct Ingest {
    Layout layout;
    const float* beautyRgb;    // interleaved, 3 floats per pixel, rows of `width` pixels
    const float* normalRgb;    // interleaved
    const float* positionRgb;  // interleaved
    const float* depthIn;      // 1 float per pixel
    const std::int32_t* idIn;  // 1 int per pixel
    int objectCount;           // valid IDs: -1 (background) .. objectCount - 1
    const float* albedoRgb;    // interleaved, or null: albedo 1 (no demodulation)
    float albedoEpsilon;
    Planes3 beauty, albedo, normal, position;
    float* depth;
    std::int32_t* objectId;
    // Per pixel (unpadded): bits 0-1 the radiance values replaced by 0, kBadObjectIdFlag, bits
    // 3-4 the radiance values clamped to +-kMaxRadiance, kMissingNormalFlag (an object pixel),
    // kNonFiniteGeometryFlag (an object pixel made background), kBackgroundFlag (passed through).
    std::uint8_t* inputFlags;
    NormalDepth4 normalDepth = {};      // InterleavedGuide only
    std::int32_t* filterKey = nullptr;  // GBufferView::filterKey
    int separateObjects = 1;            // keys by object ID (1) or one key for every object (0)
    static constexpr int kBadObjectIdFlag = 4;
    static constexpr int kClampedShift = 3;
    static constexpr int kMissingNormalFlag = 32;
    static constexpr int kNonFiniteGeometryFlag = 64;
    static constexpr int kBackgroundFlag = 128;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex s = PixelIndex(y) * layout.width + x;
        PixelIndex i = layout.index(x, y);
        int bad = 0, clamped = 0;
        float c[3];
        for (int k = 0; k < 3; ++k) {
            float v = beautyRgb[3 * s + k];
            bool finite = isFinite(v);
            bad += finite ? 0 : 1;
            clamped += finite && absf(v) > kMaxRadiance ? 1 : 0;
            c[k] = finite ? clampf(v, -kMaxRadiance, kMaxRadiance) : 0.0f;
        }
        // Background and non-finite albedo: factor 1 (nothing to demodulate, or untrustworthy).
        // Selects per component, not a branch choosing a whole vector: that would stop the CPU
        // vectorising the kernel. Without an albedo, the beauty is read in its place (unused).
        const float* albedoIn = albedoRgb ? albedoRgb : beautyRgb;
        float r = albedoIn[3 * s], gr = albedoIn[3 * s + 1], b = albedoIn[3 * s + 2];
        std::int32_t id = idIn[s];
        bool idValid = id >= -1 && id < objectCount;
        Float3 n = make3(normalRgb[3 * s], normalRgb[3 * s + 1], normalRgb[3 * s + 2]);
        Float3 p = make3(positionRgb[3 * s], positionRgb[3 * s + 1], positionRgb[3 * s + 2]);
        float z = depthIn[s];
        bool geometryFinite = isFinite(p.x) && isFinite(p.y) && isFinite(p.z) && isFinite(z);
        std::int32_t kept = idValid && geometryFinite ? id : -1;
        // A normal shorter than 1e-6 has no direction worth trusting (and 1 / |n| would overflow).
        float normalLength2 = dot(n, n);
        bool hasNormal = isFinite(normalLength2) && normalLength2 > 1e-12f;
        float inverseLength = hasNormal && kept >= 0 ? 1.0f / std::sqrt(normalLength2) : 0.0f;
        bool use = albedoRgb && kept >= 0 && isFinite(r) && isFinite(gr) && isFinite(b);
        Float3 a;
        a.x = use ? clampf(r, albedoEpsilon, kMaxRadiance) : 1.0f;
        a.y = use ? clampf(gr, albedoEpsilon, kMaxRadiance) : 1.0f;
        a.z = use ? clampf(b, albedoEpsilon, kMaxRadiance) : 1.0f;
        albedo.store(i, a);
        beauty.store(i, make3(clampf(c[0] / a.x, -kMaxRadiance, kMaxRadiance),
                              clampf(c[1] / a.y, -kMaxRadiance, kMaxRadiance),
                              clampf(c[2] / a.z, -kMaxRadiance, kMaxRadiance)));
        // Per component, as for the albedo above (a selected vector would stop vectorisation).
        auto finiteOrZero = [geometryFinite](float v) { return geometryFinite ? v : 0.0f; };
        // inverseLength 0 (background, no normal) times a non-finite component is NaN: zeroed.
        auto scaledOrZero = [inverseLength](float v) {
            return inverseLength > 0.0f ? v * inverseLength : 0.0f;
        };
        Float3 keptNormal = make3(scaledOrZero(n.x), scaledOrZero(n.y), scaledOrZero(n.z));
        position.store(i, make3(finiteOrZero(p.x), finiteOrZero(p.y), finiteOrZero(p.z)));
        if constexpr (InterleavedGuide) {
            normalDepth.store(i, keptNormal, finiteOrZero(z));
        } else {
            normal.store(i, keptNormal);
            depth[i] = finiteOrZero(z);
        }
        objectId[i] = kept;
        filterKey[i] =
            kept < 0 ? -1 : (separateObjects ? kept : 0) + (hasNormal ? 0 : kWithoutNormalKey);
        inputFlags[s] = std::uint8_t(
            bad + (idValid ? 0 : kBadObjectIdFlag) + (clamped << kClampedShift) +
            (kept >= 0 && !hasNormal ? kMissingNormalFlag : 0) +
            (idValid && id >= 0 && !geometryFinite ? kNonFiniteGeometryFlag : 0) +
            (kept < 0 ? kBackgroundFlag : 0));
    }
};
using IngestKernel = Ingest<false>;
using IngestInterleavedKernel = Ingest<true>;

}  // namespace rtd
