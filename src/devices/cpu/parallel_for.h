// The CPU launcher: rows spread over all cores by OpenMP; the kernel functor is inlined into the
// row loop so the compiler can vectorise it across neighbouring pixels.
#pragma once

#include <concepts>

#include "core/host_device.h"
#include "kernels/kernel_list.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace rtd {
// Internal linkage: each instruction-set copy of the launchers (cpu_kernels.cpp) gets its own.
namespace {

// Flush denormals to zero in this thread: filter weights far below 1e-38 times a colour would
// otherwise take the processor's slow denormal path (several times slower per operation).
void flushDenormalsToZero() {
#if defined(__SSE__)
    _mm_setcsr(_mm_getcsr() | 0x8040);  // FTZ | DAZ
#endif
}

// A kernel that declares `static constexpr bool kSparse = true` does real work on few pixels
// and returns at once on the rest: vectorised, it would do the work on every lane, so its loop
// stays scalar.
template <class Kernel>
constexpr bool isSparse() {
    if constexpr (requires { Kernel::kSparse; })
        return Kernel::kSparse;
    else
        return false;
}

// A kernel with `bool active(int x, int y) const` (whose body does nothing where it is false)
// is block-sparse: its work concerns few pixels but those lie together, so each run of
// kSparseBlock pixels is tested first (vectorised) and the vectorised body runs only on runs
// with an active pixel.
template <class Kernel>
concept BlockSparse = requires(const Kernel& k) {
    { k.active(0, 0) } -> std::same_as<bool>;
};
constexpr int kSparseBlock = 16;  // one AVX-512 vector of floats

// A kernel with `std::int32_t runKey(int x, int y) const` and
// `template <bool KnownKey> void pixel(int x, int y, std::int32_t key) const` does less work where
// neighbouring pixels share their key (an object ID: one set of matrices rather than one gathered
// per pixel, ReprojectKernel): runs of kSparseBlock pixels with one key call pixel<true> with it,
// the others pixel<false>.
template <class Kernel>
concept KeyedRuns = requires(const Kernel& k) {
    { k.runKey(0, 0) } -> std::same_as<std::int32_t>;
    k.template pixel<true>(0, 0, std::int32_t(0));
};

// The pixel loops' vectorisation: `omp simd` on every instruction-set copy but the scalar one
// (the baseline speed-ups are measured against).
#define RTD_PRAGMA(x) _Pragma(#x)
#if defined(RTD_CPU_SCALAR)
#define RTD_CPU_SIMD
#define RTD_CPU_SIMD_OR(flag)
#else
#define RTD_CPU_SIMD RTD_PRAGMA(omp simd)
#define RTD_CPU_SIMD_OR(flag) RTD_PRAGMA(omp simd reduction(| : flag))
#endif

// Whether pred(x) holds for some x in [x0, x1), tested vectorised.
template <class Pred>
RTD_INLINE bool anyInRun(int x0, int x1, Pred pred) {
    int any = 0;
    RTD_CPU_SIMD_OR(any)
    for (int x = x0; x < x1; ++x) any |= pred(x) ? 1 : 0;
    return any != 0;
}

// One row of [x0, x1): scalar, block-sparse, keyed or vectorised, as the kernel declares.
template <class Kernel>
RTD_INLINE void runRow(const Kernel& kernel, int x0, int x1, int y) {
    if constexpr (isSparse<Kernel>()) {
#if defined(__clang__)
#pragma clang loop vectorize(disable)
#endif
        for (int x = x0; x < x1; ++x) kernel(x, y);
    } else if constexpr (KeyedRuns<Kernel> || BlockSparse<Kernel>) {
        for (int b0 = x0; b0 < x1; b0 += kSparseBlock) {
            int b1 = b0 + kSparseBlock < x1 ? b0 + kSparseBlock : x1;
            if constexpr (KeyedRuns<Kernel>) {
                const std::int32_t key = kernel.runKey(b0, y);
                if (anyInRun(b0, b1, [&](int x) { return kernel.runKey(x, y) != key; })) {
                    RTD_CPU_SIMD
                    for (int x = b0; x < b1; ++x) kernel.template pixel<false>(x, y, 0);
                } else {
                    RTD_CPU_SIMD
                    for (int x = b0; x < b1; ++x) kernel.template pixel<true>(x, y, key);
                }
            } else {
                if (!anyInRun(b0, b1, [&](int x) { return kernel.active(x, y); })) continue;
                RTD_CPU_SIMD
                for (int x = b0; x < b1; ++x) kernel(x, y);
            }
        }
    } else {
        RTD_CPU_SIMD
        for (int x = x0; x < x1; ++x) kernel(x, y);
    }
}

// A kernel with tapRowStride() (kHasTapRowStride, kernel_list.h) reads rows y + k * stride,
// |k| <= 2 (an A-Trous level). In plain order a row it reads is read again over the next 4 * stride
// rows, which at wide strides no longer fit a core's L2 cache (strides 8 and 16 at 1080p, 4 to 16
// at 4K), so there (interleaveRows) the rows are visited in classes of equal y mod stride: y = r,
// r + stride, ..., for r = 0 .. stride - 1. Consecutive rows visited then share 4 of their 5 input
// rows. At narrower strides plain order is faster: its reads are continuous streams for the
// hardware prefetchers.
// Interleave when the rows read over 4 * stride rows (about 9 planes of floats: colour, variance,
// depth, normal, ID) exceed a core's L2 (2 MiB on this machine's Sapphire Rapids class cores).
constexpr long kL2CacheBytes = 2L << 20;
constexpr long kPlanesPerTap = 9;
inline bool interleaveRows(int stride, int width) {
    return 4L * stride * width * long(sizeof(float)) * kPlanesPerTap > kL2CacheBytes;
}

// The k-th row visited when rows are taken in classes of equal y mod stride.
inline int interleavedRow(int k, int height, int stride) {
    int perClass = height / stride, longClasses = height % stride;  // those have one row more
    int inLong = longClasses * (perClass + 1);
    if (k < inLong) return k / (perClass + 1) + (k % (perClass + 1)) * stride;
    k -= inLong;
    return longClasses + k / perClass + (k % perClass) * stride;
}

// Rows shared out to all cores, the k-th visited being rowOf(k). Each order gets its own
// instantiation: folded into one function with the order chosen at run time, the plain order's
// SVGF A-Trous ran 8 % slower at 512x512 (a clean-build A/B).
template <class Kernel, class RowOf>
void parallelRows(int width, int height, const Kernel& kernel, RowOf rowOf) {
#pragma omp parallel
    {
        flushDenormalsToZero();
        // A private copy, whose address never escapes: its fields (pointers, sizes) are then
        // known not to change when the kernel stores through a pointer. Read through the
        // reference, any int or byte store (object IDs, validity codes) might overwrite them, so
        // the compiler reloaded them per pixel and wrote the planes with scatters.
        const Kernel local = kernel;
        // A-Trous levels: each core takes one contiguous block of the visited rows, whose tap
        // rows it then reuses from its own L2 (box temporal's levels 4 % faster than with
        // 4-row chunks dealt out in turn, 1080p unchanged). The other kernels keep the dynamic
        // chunks: the ingest, streaming its input, ran 30 % slower in static blocks.
        if constexpr (kHasTapRowStride<Kernel>) {
#pragma omp for schedule(static)
            for (int k = 0; k < height; ++k) runRow(local, 0, width, rowOf(k));
        } else {
#pragma omp for schedule(dynamic, 4)
            for (int k = 0; k < height; ++k) runRow(local, 0, width, rowOf(k));
        }
    }
}

template <class Kernel>
void parallelFor2D(int width, int height, const Kernel& kernel) {
    if constexpr (kHasTapRowStride<Kernel>) {
        int stride = kernel.tapRowStride();
        if (stride > 1 && stride < height && interleaveRows(stride, width))
            return parallelRows(width, height, kernel,
                                [=](int k) { return interleavedRow(k, height, stride); });
    }
    parallelRows(width, height, kernel, [](int k) { return k; });
}

}  // namespace
}  // namespace rtd
