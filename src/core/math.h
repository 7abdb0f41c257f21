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

RTD_HOST_DEVICE RTD_INLINE Float3 make3(float x, float y, float z) {
    return Float3{x, y, z};
}
RTD_HOST_DEVICE RTD_INLINE Float3 operator+(Float3 a, Float3 b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
RTD_HOST_DEVICE RTD_INLINE Float3 operator-(Float3 a, Float3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
RTD_HOST_DEVICE RTD_INLINE Float3 operator*(Float3 a, float s) {
    return {a.x * s, a.y * s, a.z * s};
}
RTD_HOST_DEVICE RTD_INLINE Float3 operator*(Float3 a, Float3 b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
RTD_HOST_DEVICE RTD_INLINE Float3& operator+=(Float3& a, Float3 b) {
    a.x += b.x;
    a.y += b.y;
    a.z += b.z;
    return a;
}
RTD_HOST_DEVICE RTD_INLINE float dot(Float3 a, Float3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
RTD_HOST_DEVICE RTD_INLINE float square(float v) {
    return v * v;
}
RTD_HOST_DEVICE RTD_INLINE Float3 normalize(Float3 v) {
    // One scale factor, not a choice between two vectors: a select of whole structs would stop
    // the CPU compiler vectorising the caller.
    float length2 = dot(v, v);
    return v * (length2 > 0.0f ? 1.0f / std::sqrt(length2) : 1.0f);
}
RTD_HOST_DEVICE RTD_INLINE float minf(float a, float b) {
    return a < b ? a : b;
}
RTD_HOST_DEVICE RTD_INLINE float maxf(float a, float b) {
    return a > b ? a : b;
}
RTD_HOST_DEVICE RTD_INLINE float clampf(float v, float lo, float hi) {
    return minf(maxf(v, lo), hi);
}
RTD_HOST_DEVICE RTD_INLINE int mini(int a, int b) {
    return a < b ? a : b;
}
RTD_HOST_DEVICE RTD_INLINE int maxi(int a, int b) {
    return a > b ? a : b;
}
// min(x, 1) for callers to which a negative x read as 0 gives the same answer: on the GPU x
// clamped to [0, 1] by the saturation modifier of the instruction that produced x (free), on
// the CPU one instruction rather than a clamp's two.
RTD_HOST_DEVICE RTD_INLINE float atMostOneOrSaturated(float x) {
#if defined(__CUDA_ARCH__)
    return __saturatef(x);
#else
    return minf(x, 1.0f);
#endif
}
// |x|: a sign-bit mask on the CPU, an operand modifier (no instruction) on the GPU.
RTD_HOST_DEVICE RTD_INLINE float absf(float x) {
    return std::fabs(x);
}
RTD_HOST_DEVICE RTD_INLINE Float3 clamp3(Float3 v, Float3 lo, Float3 hi) {
    return {clampf(v.x, lo.x, hi.x), clampf(v.y, lo.y, hi.y), clampf(v.z, lo.z, hi.z)};
}
// v clamped to the box [lo, hi] grown to hold `own`: a history box that never rejects the
// pixel's own current value (a light a pixel wide lies far outside its neighbourhood's box).
RTD_HOST_DEVICE RTD_INLINE Float3 clampToBoxHolding(Float3 v, Float3 lo, Float3 hi, Float3 own) {
    return {clampf(v.x, minf(lo.x, own.x), maxf(hi.x, own.x)),
            clampf(v.y, minf(lo.y, own.y), maxf(hi.y, own.y)),
            clampf(v.z, minf(lo.z, own.z), maxf(hi.z, own.z))};
}
// a where pick, else b, per component: a selected structure would stop the CPU vectorising
// the kernel that uses it.
RTD_HOST_DEVICE RTD_INLINE Float3 select3(bool pick, Float3 a, Float3 b) {
    return {pick ? a.x : b.x, pick ? a.y : b.y, pick ? a.z : b.z};
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

constexpr float kLog2e = 1.44269504f;

// c0 + x (c1 + x (c2 + ...)): Horner's scheme, one fused multiply-add per coefficient after the
// last.
template <class... Rest>
RTD_HOST_DEVICE RTD_INLINE float polynomial(float x, float c0, Rest... rest) {
    if constexpr (sizeof...(Rest) == 0)
        return c0;
    else
        return polynomial(x, rest...) * x + c0;
}

// 2^t for t <= 0 (the filters' weights, with their exponents in base 2): 2^n p(t - n) with n the
// nearest integer to t and p a degree-5 near-minimax fit of 2^f on [-1/2, 1/2] with p(0) = 1
// (relative error 9e-8). 2^n without a conversion to an integer: n + 1.5 * 2^23 + 127 holds
// n + 127 in its low mantissa bits, which shifted into the exponent field make 2^n. Results under
// 2^-126 become 2^-126. GPU: its exp2 instruction (2 ulp).
RTD_HOST_DEVICE RTD_INLINE float exp2Negative(float t) {
#if defined(__CUDA_ARCH__)
    return exp2f(t);
#else
    t = maxf(t, -126.0f);
    float n = std::rint(t);  // one rounding instruction; round-half-even by default
    float f = t - n;         // in [-1/2, 1/2], exact
    // Exactly 1 at 0: the centre tap's weight is exactly 1.
    float p = polynomial(f, 1.0f, 6.93147004e-1f, 2.40222424e-1f, 5.55073358e-2f, 9.67151299e-3f,
                         1.32647238e-3f);
    float biased = n + 12583039.0f;  // 1.5 * 2^23 + 127 + n, exact
    std::int32_t bits;
    std::memcpy(&bits, &biased, sizeof bits);
    bits <<= 23;  // n + 127 in [1, 127] into the exponent, the rest shifted out
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return p * scale;
#endif
}

// e^x for x <= 0: 2^(x log2 e); rounding x * log2(e) adds up to 1e-5 relative at large |x|.
RTD_HOST_DEVICE RTD_INLINE float expNegative(float x) {
#if defined(__CUDA_ARCH__)
    return __expf(x);
#else
    return exp2Negative(x * kLog2e);
#endif
}

// log2(x) for normal x > 0: x = 2^e m, m in [1, 2), ln(m) = t q(t) with t = m - 1 and q a
// degree-6 near-minimax fit (|error| < 2.2e-7). Branch-free, so it vectorises.
RTD_HOST_DEVICE RTD_INLINE float log2Positive(float x) {
#if defined(__CUDA_ARCH__)
    return __log2f(x);
#else
    std::int32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    float exponent = float(((bits >> 23) & 0xff) - 127);
    std::int32_t mantissaBits = (bits & 0x007fffff) | 0x3f800000;
    float m;
    std::memcpy(&m, &mantissaBits, sizeof m);
    float t = m - 1.0f;
    float q = polynomial(t, 9.99981138e-1f, -4.99471772e-1f, 3.28242120e-1f, -2.25897751e-1f,
                         1.34674123e-1f, -5.51448824e-2f, 1.07644191e-2f);
    return exponent + t * q * kLog2e;
#endif
}

// a / b and sqrt(x) inside the filters' weights, where a few ulp do not matter: the GPU's
// approximate instructions (2 ulp, no IEEE slow path); the CPU's vector division and square root
// are already fast. Only here: nvcc's whole-file -prec-div=false -prec-sqrt=false -ftz=true made
// the JBF and A-Trous about 1.4x faster on an H100 but moved the reprojection's validity
// decisions, and the course-scene CPU/CUDA equivalence test failed.
RTD_HOST_DEVICE RTD_INLINE float divideApprox(float a, float b) {
#if defined(__CUDA_ARCH__)
    return __fdividef(a, b);
#else
    return a / b;
#endif
}
RTD_HOST_DEVICE RTD_INLINE float sqrtApprox(float x) {
#if defined(__CUDA_ARCH__)
    float r;
    asm("sqrt.approx.f32 %0, %1;" : "=f"(r) : "f"(x));
    return r;
#else
    return std::sqrt(x);
#endif
}

// p(a) with acos(a) = sqrt(1 - a) p(a) on [0, 1]: a degree-5 near-minimax fit (|error| of the
// product < 1.2e-6 rad).
RTD_HOST_DEVICE RTD_INLINE float acosSqrtFactor(float a) {
    return polynomial(a, 1.57079521f, -2.14512260e-1f, 8.78755555e-2f, -4.49569637e-2f,
                      1.93479445e-2f, -4.33703996e-3f);
}

// q(a) with acos(a)^2 = (1 - a) q(a), fitted where a filter's narrow normal term needs it:
// a degree-3 near-minimax fit on [0.6, 1] (relative error 1.5e-6; (1 - a) q(a) evaluated in
// float: 1.6e-6, as acos(a): 8e-7).
// Below 0.6 it keeps growing as a falls (to 3.3 at -1), so (1 - a) q(a) >= acos(0.6)^2 = 0.86
// there, where a narrow normal term's weight is e^-30 or less anyway (OppositeNormalsVanish,
// edge_stopping.h). Two multiply-adds fewer per tap than a fit on all of [0, 1] of equal
// accuracy (scripts/fit_polynomials.py fits it).
RTD_HOST_DEVICE RTD_INLINE float acosSquaredFactorNearOne(float a) {
    return polynomial(a, 2.45852923f, -6.22350633e-1f, 2.02668637e-1f, -3.88501473e-2f);
}

// L(a) with -log2(a) = (1 - a) L(a), fitted where a weight max(0, a)^sigma with a large sigma
// needs it: a degree-4 near-minimax fit on [0.8, 1] (relative error 2.2e-7; (1 - a) L(a)
// evaluated in float: 4.8e-7). Below 0.8 it keeps growing as a falls (to 14.7 at -1), so
// (1 - a) L(a) >= -log2(0.8) = 0.3219 there (kNegLog2NearOneFloor); scripts/fit_polynomials.py
// fits it.
RTD_HOST_DEVICE RTD_INLINE float negLog2FactorNearOne(float a) {
    return polynomial(a, 3.42985296f, -4.48950958f, 4.19275141f, -2.14431977f, 4.53920215e-1f);
}
constexpr float kNegLog2NearOneFloor = 0.3219f;

// arccos on [-1, 1] (input clamped): acos(|x|) = sqrt(1 - |x|) p(|x|), reflected for x < 0.
RTD_HOST_DEVICE RTD_INLINE float acosFast(float x) {
    x = clampf(x, -1.0f, 1.0f);
    float a = absf(x);
    float r = sqrtApprox(1.0f - a) * acosSqrtFactor(a);
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

// The upper 3x3 of `a` applied to a direction (no translation).
RTD_HOST_DEVICE RTD_INLINE Float3 transformVector(const Mat4& a, Float3 v) {
    return {a.m[0][0] * v.x + a.m[0][1] * v.y + a.m[0][2] * v.z,
            a.m[1][0] * v.x + a.m[1][1] * v.y + a.m[1][2] * v.z,
            a.m[2][0] * v.x + a.m[2][1] * v.y + a.m[2][2] * v.z};
}

// Host-only helpers for per-frame matrix set-up (a handful of matrices per frame).
Mat4 multiply(const Mat4& a, const Mat4& b);
// Inverse by cofactors in double precision; returns false if the matrix is singular.
bool invert(const Mat4& a, Mat4& inverse);

}  // namespace rtd
