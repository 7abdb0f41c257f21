// Small vector/matrix types and fast, branch-free math for the kernels (vectorisable on the CPU,
// the hardware intrinsics on the GPU).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/host_device.h"

namespace rtd {

struct Float3 {
    float x = 0.0f, y = 0.0f, z = 0.0f;
};

RTD_HOST_DEVICE RTD_INLINE Float3 make3(float x, float y, float z) { return Float3{x, y, z}; }
RTD_HOST_DEVICE RTD_INLINE Float3 operator+(Float3 a, Float3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
RTD_HOST_DEVICE RTD_INLINE Float3 operator-(Float3 a, Float3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
RTD_HOST_DEVICE RTD_INLINE Float3 operator*(Float3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
RTD_HOST_DEVICE RTD_INLINE Float3 operator*(Float3 a, Float3 b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
RTD_HOST_DEVICE RTD_INLINE Float3& operator+=(Float3& a, Float3 b) {
    a.x += b.x;
    a.y += b.y;
    a.z += b.z;
    return a;
}
RTD_HOST_DEVICE RTD_INLINE float dot(Float3 a, Float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
RTD_HOST_DEVICE RTD_INLINE float minf(float a, float b) { return a < b ? a : b; }
RTD_HOST_DEVICE RTD_INLINE float maxf(float a, float b) { return a > b ? a : b; }
RTD_HOST_DEVICE RTD_INLINE float clampf(float v, float lo, float hi) {
    return minf(maxf(v, lo), hi);
}
RTD_HOST_DEVICE RTD_INLINE int mini(int a, int b) { return a < b ? a : b; }
RTD_HOST_DEVICE RTD_INLINE int maxi(int a, int b) { return a > b ? a : b; }
RTD_HOST_DEVICE RTD_INLINE Float3 clamp3(Float3 v, Float3 lo, Float3 hi) {
    return {clampf(v.x, lo.x, hi.x), clampf(v.y, lo.y, hi.y), clampf(v.z, lo.z, hi.z)};
}
RTD_HOST_DEVICE RTD_INLINE float luminance(Float3 c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
RTD_HOST_DEVICE RTD_INLINE bool isFinite(float v) {
    // Exponent bits all ones means Inf or NaN; works under any floating-point flags.
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return (bits & 0x7f800000u) != 0x7f800000u;
}

// e^x for x <= 0 (the filters' weights): 2^t = 2^floor(t) * p(frac(t)), p a degree-7 polynomial
// of 2^f on [0,1); relative error below 1e-5 (from rounding x * log2(e) at large |x|), 2e-6
// for x > -10. Results under 2^-126 flush to 0.
RTD_HOST_DEVICE RTD_INLINE float expNegative(float x) {
#if defined(__CUDA_ARCH__)
    return __expf(x);
#else
    float t = maxf(x * 1.44269504f, -126.0f);
    float whole = std::floor(t);
    float f = t - whole;
    float p = 1.52527338e-5f;
    p = p * f + 1.54035304e-4f;
    p = p * f + 1.33335581e-3f;
    p = p * f + 9.61812911e-3f;
    p = p * f + 5.55041087e-2f;
    p = p * f + 2.40226507e-1f;
    p = p * f + 6.93147181e-1f;
    p = p * f + 1.0f;
    std::int32_t bits = (static_cast<std::int32_t>(whole) + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return p * scale;
#endif
}

// arccos on [-1, 1] (input clamped): Abramowitz & Stegun 4.4.46, |error| <= 2e-8 rad.
RTD_HOST_DEVICE RTD_INLINE float acosFast(float x) {
    x = clampf(x, -1.0f, 1.0f);
    float a = x < 0.0f ? -x : x;
    float p = -0.0012624911f;
    p = p * a + 0.0066700901f;
    p = p * a - 0.0170881256f;
    p = p * a + 0.0308918810f;
    p = p * a - 0.0501743046f;
    p = p * a + 0.0889789874f;
    p = p * a - 0.2145988016f;
    p = p * a + 1.5707963050f;
    float r = std::sqrt(1.0f - a) * p;
    return x < 0.0f ? 3.14159265f - r : r;
}

// Row-major 4x4 (m[row][col]) for column vectors.
struct Mat4 {
    float m[4][4];
};

struct Float4 {
    float x, y, z, w;
};

RTD_HOST_DEVICE RTD_INLINE Float4 transformPoint(const Mat4& a, Float3 p) {
    return {a.m[0][0] * p.x + a.m[0][1] * p.y + a.m[0][2] * p.z + a.m[0][3],
            a.m[1][0] * p.x + a.m[1][1] * p.y + a.m[1][2] * p.z + a.m[1][3],
            a.m[2][0] * p.x + a.m[2][1] * p.y + a.m[2][2] * p.z + a.m[2][3],
            a.m[3][0] * p.x + a.m[3][1] * p.y + a.m[3][2] * p.z + a.m[3][3]};
}

// Host-only helpers for per-frame matrix set-up (a handful of matrices per frame).
Mat4 multiply(const Mat4& a, const Mat4& b);
// Inverse by cofactors in double precision; returns false if the matrix is singular.
bool invert(const Mat4& a, Mat4& inverse);

}  // namespace rtd
