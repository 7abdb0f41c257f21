// The CPU launcher: rows spread over all cores by OpenMP; the kernel functor is inlined into the
// row loop so the compiler can vectorise it across neighbouring pixels.
#pragma once

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

template <class Kernel>
void parallelFor2D(int width, int height, const Kernel& kernel) {
#pragma omp parallel
    {
        flushDenormalsToZero();
#pragma omp for schedule(dynamic, 4)
        for (int y = 0; y < height; ++y) {
            if constexpr (isSparse<Kernel>()) {
#if defined(__clang__)
#pragma clang loop vectorize(disable)
#endif
                for (int x = 0; x < width; ++x) kernel(x, y);
            } else {
#if !defined(RTD_CPU_SCALAR)
#pragma omp simd
#endif
                for (int x = 0; x < width; ++x) kernel(x, y);
            }
        }
    }
}

}  // namespace
}  // namespace rtd
