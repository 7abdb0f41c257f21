// What kernels see of the buffers: raw pointers (host or device) into planar images, so that one
// channel of neighbouring pixels is contiguous (vector loads on the CPU, coalesced on the GPU).
#pragma once

#include <cstddef>
#include <cstdint>

#include "core/math.h"

namespace rtd {

// Three planes of width*height floats: x (or R) plane, then y, then z.
struct Planes3 {
    float* data = nullptr;
    std::size_t planeSize = 0;

    RTD_HOST_DEVICE RTD_INLINE Float3 load(std::size_t i) const {
        return {data[i], data[i + planeSize], data[i + 2 * planeSize]};
    }
    RTD_HOST_DEVICE RTD_INLINE void store(std::size_t i, Float3 v) const {
        data[i] = v.x;
        data[i + planeSize] = v.y;
        data[i + 2 * planeSize] = v.z;
    }
};

// The noise-free geometry of one frame.
struct GBufferView {
    int width = 0;
    int height = 0;
    Planes3 normal;
    Planes3 position;
    const float* depth = nullptr;
    const std::int32_t* objectId = nullptr;  // -1: background

    RTD_HOST_DEVICE RTD_INLINE std::size_t index(int x, int y) const {
        return std::size_t(y) * std::size_t(width) + std::size_t(x);
    }
};

}  // namespace rtd
