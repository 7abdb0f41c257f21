// The caller's buffer layouts (FrameView: float or half, 1 to 4 channels, any pixel and row
// stride in bytes) into the packed float buffers the ingest reads, and the result back into the
// caller's output layout. They run only for inputs not already packed float (the common float3
// case reads the caller's buffer itself). Also the motion vectors into the previous pixel and
// depth each pixel's history test uses (findHistory).
#pragma once

#include <cstdint>

#include "core/math.h"
#include "kernels/views.h"

namespace rtd {

// Element types of a caller's buffer (rtd::DataType's values).
enum SpanType : int { kSpanFloat32 = 0, kSpanFloat16 = 1, kSpanInt32 = 2 };

// IEEE 754 binary16 to binary32, exact for every value (subnormals, infinities and NaN included):
// integer operations, the same on the host and the GPU.
RTD_HOST_DEVICE RTD_INLINE float halfToFloat(std::uint16_t h) {
    std::uint32_t sign = std::uint32_t(h & 0x8000u) << 16;
    std::uint32_t exponent = (h >> 10) & 0x1fu;
    std::uint32_t mantissa = h & 0x3ffu;
    std::uint32_t bits;
    if (exponent == 0x1fu) {
        bits = sign | 0x7f800000u | (mantissa << 13);  // Inf, NaN
    } else if (exponent != 0) {
        bits = sign | ((exponent + 112u) << 23) | (mantissa << 13);
    } else {
        // Zero or subnormal: mantissa * 2^-24, exact in float.
        float magnitude = float(mantissa) * 5.9604644775390625e-8f;
        std::uint32_t m;
        std::memcpy(&m, &magnitude, 4);
        bits = sign | m;
    }
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

// Binary32 to binary16, rounded to nearest even; beyond the half range: infinity; NaN stays NaN.
RTD_HOST_DEVICE RTD_INLINE std::uint16_t floatToHalf(float f) {
    std::uint32_t bits;
    std::memcpy(&bits, &f, 4);
    std::uint32_t sign = (bits >> 16) & 0x8000u;
    std::uint32_t magnitude = bits & 0x7fffffffu;
    if (magnitude >= 0x7f800000u)  // Inf or NaN (a quiet NaN keeps a mantissa bit)
        return std::uint16_t(sign | 0x7c00u | (magnitude > 0x7f800000u ? 0x200u : 0u));
    if (magnitude >= 0x477ff000u) return std::uint16_t(sign | 0x7c00u);  // rounds past 65504
    if (magnitude < 0x38800000u) {
        // Subnormal half (or zero): scaled so that the float's rounding does the half's.
        float scaled;
        std::memcpy(&scaled, &magnitude, 4);
        scaled = scaled * 16777216.0f;  // 2^24: units of the smallest subnormal
        std::uint32_t units = std::uint32_t(scaled);
        float remainder = scaled - float(units);
        units += remainder > 0.5f || (remainder == 0.5f && (units & 1u)) ? 1u : 0u;
        return std::uint16_t(sign | units);
    }
    std::uint32_t rounded = magnitude + 0xfffu + ((magnitude >> 13) & 1u);  // to nearest even
    return std::uint16_t(sign | ((rounded - 0x38000000u) >> 13));
}

// A caller's image: `channels` values of `type` per pixel, pixel (x, y) at
// data + y * rowStride + x * pixelStride bytes.
struct InputSpan {
    const unsigned char* data = nullptr;
    int type = kSpanFloat32;
    int channels = 0;
    std::int64_t pixelStride = 0;
    std::int64_t rowStride = 0;

    RTD_HOST_DEVICE RTD_INLINE const unsigned char* pixel(int x, int y) const {
        return data + std::int64_t(y) * rowStride + std::int64_t(x) * pixelStride;
    }
    // Channel c as a float (an int32 converted).
    RTD_HOST_DEVICE RTD_INLINE float load(int x, int y, int c) const {
        const unsigned char* p = pixel(x, y);
        if (type == kSpanFloat16) {
            std::uint16_t h;
            std::memcpy(&h, p + 2 * c, 2);
            return halfToFloat(h);
        }
        if (type == kSpanInt32) {
            std::int32_t v;
            std::memcpy(&v, p + 4 * c, 4);
            return float(v);
        }
        float v;
        std::memcpy(&v, p + 4 * c, 4);
        return v;
    }
};

// v clamped to [0, 1], NaN read as 1.
RTD_HOST_DEVICE RTD_INLINE float unitNanAsOne(float v) {
    return v >= 0.0f ? (v < 1.0f ? v : 1.0f) : (v < 0.0f ? 0.0f : 1.0f);
}

// The caller's history confidence (FrameBinding::confidence, its first channel) at (x, y), as
// the kernels should read it: clamped to [0, 1], NaN as 1 (as if none were given), 1 when absent.
RTD_HOST_DEVICE RTD_INLINE float loadConfidence(const InputSpan& confidence, int x, int y) {
    if (!confidence.data) return 1.0f;
    return unitNanAsOne(confidence.load(x, y, 0));
}

// An image of the caller's as packed floats (`channels` per pixel: the first ones of the input,
// 0 beyond its own). As IDs (toIds): packed int32, a float ID rounded to the nearest integer,
// one that is not finite or not near an integer becoming kUnreadableId (the ingest flags it).
struct ConvertInputKernel {
    InputSpan in;
    int width = 0;
    int channels = 0;
    float* out = nullptr;  // packed floats, or (toIds) int32
    int toIds = 0;
    static constexpr std::int32_t kUnreadableId = -2147483647 - 1;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::int64_t s = std::int64_t(y) * width + x;
        if (toIds) {
            std::int32_t id;
            if (in.type == kSpanInt32) {
                std::memcpy(&id, in.pixel(x, y), 4);
            } else {
                float v = in.load(x, y, 0);
                float nearest = std::floor(v + 0.5f);
                bool integral = isFinite(v) && absf(v - nearest) < 0.01f && absf(nearest) < 2e9f;
                id = integral ? std::int32_t(nearest) : kUnreadableId;
            }
            std::memcpy(out + s, &id, 4);
            return;
        }
        for (int c = 0; c < channels; ++c)
            out[s * channels + c] = c < in.channels ? in.load(x, y, c) : 0.0f;
    }
};

// Ray distance to view depth where back-projection uses matrices: the view depth of the pixel's
// world position is the w of worldToScreen * (p, 1) (the course's convention); background keeps 0.
struct ViewDepthFromPositionKernel {
    const float* position = nullptr;  // packed RGB
    int width = 0;
    Float4 screenW;          // the last row of worldToScreen
    float* depth = nullptr;  // packed, in place of the ray distance

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::int64_t s = std::int64_t(y) * width + x;
        float w = screenW.x * position[3 * s] + screenW.y * position[3 * s + 1] +
                  screenW.z * position[3 * s + 2] + screenW.w;
        depth[s] = depth[s] > 0.0f ? w : depth[s];
    }
};

// The result (packed RGB floats) into the caller's layout: float or half, 3 channels, or 4 with
// alpha 1 (to keep the caller's alpha, give 3 channels with a 4-channel pixel stride).
struct WriteOutputKernel {
    const float* rgb = nullptr;
    int width = 0;
    unsigned char* data = nullptr;
    int type = kSpanFloat32;
    int channels = 3;
    std::int64_t pixelStride = 0;
    std::int64_t rowStride = 0;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        std::int64_t s = std::int64_t(y) * width + x;
        unsigned char* p = data + std::int64_t(y) * rowStride + std::int64_t(x) * pixelStride;
        for (int c = 0; c < channels; ++c) {
            float v = c < 3 ? rgb[3 * s + c] : 1.0f;
            if (type == kSpanFloat16) {
                std::uint16_t h = floatToHalf(v);
                std::memcpy(p + 2 * c, &h, 2);
            } else {
                std::memcpy(p + 4 * c, &v, 4);
            }
        }
    }
};

// The motion vectors (NRD's convention, previous = current + motion, after `scale` per axis)
// into the history test's inputs: the previous frame's continuous pixel coordinate (pixel
// centres at integers) and the point's expected previous depth (the current one plus the third
// channel where given). Non-finite motion puts the point off the screen: no history.
struct MotionIngestKernel {
    Layout layout;
    InputSpan motion;
    const float* depth = nullptr;                       // packed, as the ingest reads it
    float scaleX = 1.0f, scaleY = 1.0f, scaleZ = 1.0f;  // scaleZ: -1 for current - previous
    Planes3 out;  // previous x, previous y, expected previous depth

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        float mx = motion.load(x, y, 0) * scaleX;
        float my = motion.load(x, y, 1) * scaleY;
        float dz = motion.channels > 2 ? motion.load(x, y, 2) * scaleZ : 0.0f;
        float z = depth[std::int64_t(y) * layout.width + x];
        bool usable = isFinite(mx) && isFinite(my) && isFinite(dz) && isFinite(z);
        out.store(layout.index(x, y),
                  usable ? make3(float(x) + mx, float(y) + my, z + dz) : make3(-2.0f, -2.0f, 0.0f));
    }
};

}  // namespace rtd
