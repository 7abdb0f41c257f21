// The one place that knows which compiler sees the code: kernels are marked RTD_HOST_DEVICE and
// compile unchanged for the CPU (g++/clang) and for CUDA (nvcc).
#pragma once

#if defined(__CUDACC__)
#define RTD_HOST_DEVICE __host__ __device__
#define RTD_INLINE __forceinline__
#else
#define RTD_HOST_DEVICE
#define RTD_INLINE inline __attribute__((always_inline))
#endif

// Index of a pixel in a padded plane. 64-bit on the CPU: a tap's address is then a base pointer
// plus the index, where a 32-bit index would need an add and a sign extension per tap (the
// compiler must allow for it wrapping); 32-bit on the GPU, where 64-bit integer math costs more.
#if defined(__CUDACC__)
using PixelIndex = int;
#else
using PixelIndex = long;
#endif

// Fully unrolls a short loop with a constant trip count (the 5x5 taps), which lets the CPU
// compiler vectorise the pixel loop around it.
#if defined(__CUDACC__)
#define RTD_UNROLL _Pragma("unroll")
#elif defined(__clang__)
#define RTD_UNROLL _Pragma("clang loop unroll(full)")
#else
#define RTD_UNROLL _Pragma("GCC unroll 16")
#endif

// On a vectorised inner loop with a short run-time trip count (the JBF's 2r+1 = 33 taps). CPU: at
// most two vectors per iteration with AVX-512. Clang otherwise interleaves four 16-wide vectors
// (64 taps) per iteration, and a 33-tap row runs entirely in the scalar remainder (5x slower);
// with AVX2 its default (4 x 8 = 32 taps) is the better fit.
#if defined(__clang__) && defined(__AVX512F__) && !defined(__CUDACC__)
#define RTD_SHORT_VECTOR_LOOP _Pragma("clang loop interleave_count(2)")
#elif defined(__CUDACC__)
// On the GPU, unrolled by 4: the taps' loads then share addresses with immediate offsets
// (the JBF at 1080p on an H100: 5.8 -> 4.5 ms).
#define RTD_SHORT_VECTOR_LOOP _Pragma("unroll 4")
#else
#define RTD_SHORT_VECTOR_LOOP
#endif

// At the top of a function body: no reassociation of its floating-point arithmetic, whatever
// the file's flags. Clang's reassociation (-fassociative-math) turns `a * (1 / b)`, with 1 / b
// hoisted out of a filter's tap loop, back into `a / b` on every tap, a vector division each.
#if defined(__clang__) && !defined(__CUDACC__)
#define RTD_NO_REASSOCIATION _Pragma("clang fp reassociate(off)")
#else
#define RTD_NO_REASSOCIATION
#endif
