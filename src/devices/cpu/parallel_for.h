// The CPU launcher: rows spread over all cores by OpenMP; the kernel functor is inlined into the
// row loop so the compiler can vectorise it across neighbouring pixels.
#pragma once

#include <concepts>

#include "core/host_device.h"

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

// One row of [x0, x1): scalar, block-sparse or vectorised, as the kernel declares.
template <class Kernel>
RTD_INLINE void runRow(const Kernel& kernel, int x0, int x1, int y) {
    if constexpr (isSparse<Kernel>()) {
#if defined(__clang__)
#pragma clang loop vectorize(disable)
#endif
        for (int x = x0; x < x1; ++x) kernel(x, y);
    } else if constexpr (BlockSparse<Kernel>) {
        for (int b0 = x0; b0 < x1; b0 += kSparseBlock) {
            int b1 = b0 + kSparseBlock < x1 ? b0 + kSparseBlock : x1;
            int active = 0;
#if !defined(RTD_CPU_SCALAR)
#pragma omp simd reduction(| : active)
#endif
            for (int x = b0; x < b1; ++x) active |= kernel.active(x, y) ? 1 : 0;
            if (!active) continue;
#if !defined(RTD_CPU_SCALAR)
#pragma omp simd
#endif
            for (int x = b0; x < b1; ++x) kernel(x, y);
        }
    } else {
#if !defined(RTD_CPU_SCALAR)
#pragma omp simd
#endif
        for (int x = x0; x < x1; ++x) kernel(x, y);
    }
}

template <class Kernel>
void parallelFor2D(int width, int height, const Kernel& kernel) {
#pragma omp parallel
    {
        flushDenormalsToZero();
        // A private copy, whose address never escapes: its fields (pointers, sizes) are then
        // known not to change when the kernel stores through a pointer. Read through the
        // reference, any int or byte store (object IDs, validity codes) might overwrite them, so
        // the compiler reloaded them per pixel and wrote the planes with scatters.
        const Kernel local = kernel;
#pragma omp for schedule(dynamic, 4)
        for (int y = 0; y < height; ++y) runRow(local, 0, width, y);
    }
}

}  // namespace
}  // namespace rtd
