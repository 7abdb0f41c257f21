// What kernels see of the buffers: raw pointers (host or device) into planar images, so that one
// channel of neighbouring pixels is contiguous (vector loads on the CPU, coalesced on the GPU).
//
// Every planar image has a border of `padding` pixels on each side whose object ID is -1
// (background) and whose values are 0. Filter taps up to `padding` pixels away therefore need no
// bounds test: a tap in the border simply has weight 0, which keeps the kernels branch-free.
#pragma once

#include <cstdint>
#include <cstring>
#include <utility>

#include "core/math.h"

namespace rtd {

// Where pixel (x, y) of a width x height image lies in a padded plane.
struct Layout {
    int width = 0;
    int height = 0;
    int pitch = 0;    // floats per padded row
    int origin = 0;   // index of pixel (0, 0)
    int padding = 0;  // border width in pixels
    int planeSize = 0;

    RTD_HOST_DEVICE RTD_INLINE PixelIndex index(int x, int y) const {
        return PixelIndex(origin) + PixelIndex(y) * pitch + x;
    }
    RTD_HOST_DEVICE RTD_INLINE PixelIndex offset(int dx, int dy) const {
        return PixelIndex(dy) * pitch + dx;
    }
};

// Three planes: x (or R), then y, then z, each `planeSize` floats.
struct Planes3 {
    float* data = nullptr;
    int planeSize = 0;

    RTD_HOST_DEVICE RTD_INLINE Float3 load(PixelIndex i) const {
        return {data[i], data[i + planeSize], data[i + 2 * planeSize]};
    }
    RTD_HOST_DEVICE RTD_INLINE void store(PixelIndex i, Float3 v) const {
        data[i] = v.x;
        data[i + planeSize] = v.y;
        data[i + 2 * planeSize] = v.z;
    }
};

// Any number of consecutive planes of one buffer.
struct PlaneSet {
    float* data = nullptr;
    int planeSize = 0;
    RTD_HOST_DEVICE RTD_INLINE float& at(int plane, PixelIndex i) const {
        return data[plane * planeSize + i];
    }
    // Planes first..first+2 as a colour.
    RTD_HOST_DEVICE RTD_INLINE Planes3 rgb(int first = 0) const {
        return {data + first * planeSize, planeSize};
    }
};

// Four consecutive floats p[0..3], p 16-byte aligned: one 16-byte load on the GPU.
RTD_HOST_DEVICE RTD_INLINE Float4 load4(const float* p) {
#if defined(__CUDA_ARCH__)
    float4 v = *reinterpret_cast<const float4*>(p);
    return {v.x, v.y, v.z, v.w};
#else
    return {p[0], p[1], p[2], p[3]};
#endif
}
RTD_HOST_DEVICE RTD_INLINE void store4(float* p, Float4 v) {
#if defined(__CUDA_ARCH__)
    *reinterpret_cast<float4*>(p) = make_float4(v.x, v.y, v.z, v.w);
#else
    p[0] = v.x;
    p[1] = v.y;
    p[2] = v.z;
    p[3] = v.w;
#endif
}

// Normal and depth interleaved, (n.x, n.y, n.z, depth) per pixel of the padded layout: the
// GPU's copy of the guide the SVGF filters read per tap (one 16-byte load where the planes
// take four; the timing: docs/performance-gpu.md). The CPU keeps the planes, which it loads as
// contiguous vectors.
struct NormalDepth4 {
    float* data = nullptr;
    RTD_HOST_DEVICE RTD_INLINE void load(PixelIndex i, Float3& normal, float& depth) const {
        Float4 v = load4(data + 4 * i);
        normal = {v.x, v.y, v.z};
        depth = v.w;
    }
    RTD_HOST_DEVICE RTD_INLINE void store(PixelIndex i, Float3 normal, float depth) const {
        store4(data + 4 * i, {normal.x, normal.y, normal.z, depth});
    }
};

// The noise-free geometry of one frame.
struct GBufferView {
    Layout layout;
    Planes3 normal;
    Planes3 position;
    const float* depth = nullptr;
    const std::int32_t* objectId = nullptr;  // -1: background and border
    NormalDepth4 normalDepth = {};  // the same memory as normal + depth: read where the device interleaves the guide (steps.h)
    // The edge-aware filters' tap test: a tap mixes in where its key equals the centre's, one
    // comparison per tap. Written by the ingest: -1 on background; on an object pixel its object
    // ID where objects are kept apart (the default), 0 otherwise, plus kWithoutNormalKey where
    // the pixel has no normal. So pixels without a normal filter among themselves, with their
    // normal terms neutral (guideNormalWeight), and the others never take them in.
    const std::int32_t* filterKey = nullptr;
};
constexpr std::int32_t kWithoutNormalKey = 1 << 30;

// Whether a pixel's guide normal (unit, or 0 without one: the ingest's) is one; a pixel
// without one weighs its taps' normals by 0 (a neutral normal term).
RTD_HOST_DEVICE RTD_INLINE float guideNormalWeight(Float3 normal) {
    return dot(normal, normal) > 0.25f ? 1.0f : 0.0f;
}

// Normal and depth at a tap: from the interleaved copy (Interleaved) or the planes.
template <bool Interleaved>
RTD_HOST_DEVICE RTD_INLINE void loadNormalDepth(const GBufferView& g, PixelIndex i, Float3& normal,
                                                float& depth) {
    if constexpr (Interleaved) {
        g.normalDepth.load(i, normal, depth);
    } else {
        normal = g.normal.load(i);
        depth = g.depth[i];
    }
}

// The values at p[0] and p[1] (neighbouring pixels of a plane) at a data-dependent address. On
// the CPU one 8-byte load, which the vectoriser turns into one 64-bit gather for both: the
// bilinear history taps come in such pairs, and gathers cost per element fetched. On the GPU two
// loads (an 8-byte one would need 8-byte alignment).
template <class T>
RTD_HOST_DEVICE RTD_INLINE void loadPair(const T* p, T& first, T& second) {
    static_assert(sizeof(T) == 4, "pairs of 32-bit values");
#if defined(__CUDA_ARCH__)
    first = p[0];
    second = p[1];
#else
    std::uint64_t bits;
    std::memcpy(&bits, p, sizeof bits);
    auto low = std::uint32_t(bits), high = std::uint32_t(bits >> 32);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    std::swap(low, high);  // p[0] is then the high half
#endif
    std::memcpy(&first, &low, sizeof first);
    std::memcpy(&second, &high, sizeof second);
#endif
}

// 1 for a pixel that holds an object, 0 for background or border (a multiplier, not a branch).
RTD_HOST_DEVICE RTD_INLINE float foregroundMask(std::int32_t id) {
    return id >= 0 ? 1.0f : 0.0f;
}

}  // namespace rtd
