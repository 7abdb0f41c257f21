// The CPU launcher: rows spread over all cores by OpenMP; the kernel functor is inlined into the
// row loop so the compiler can vectorise it across neighbouring pixels.
#pragma once

#include <omp.h>

#include <algorithm>
#include <concepts>
#include <utility>

#include "core/host_device.h"
#include "devices/cpu/cpu_scratch.h"
#include "kernels/launch_traits.h"

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

namespace rtd {
// Internal linkage: each instruction-set copy of the launchers (cpu_kernels.cpp) gets its own.
namespace {

// Flush denormals to zero in this thread: filter weights far below 1e-38 times a colour would
// otherwise take the processor's slow denormal path (several times slower per operation).
inline void flushDenormalsToZero() {
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
// with an active pixel (a KeyedRuns kernel too: its runs without one are skipped first).
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
// RTD_CPU_SIMD_MASKED_TAIL: the same, with clang asked to run a loop's remainder as one masked
// vector step rather than scalar iterations (loops of a few vectors: a tile phase's rows).
#if defined(RTD_CPU_SCALAR)
#define RTD_CPU_SIMD
#define RTD_CPU_SIMD_OR(flag)
#define RTD_CPU_SIMD_MASKED_TAIL
#else
#define RTD_CPU_SIMD RTD_PRAGMA(omp simd)
#define RTD_CPU_SIMD_OR(flag) RTD_PRAGMA(omp simd reduction(| : flag))
#if defined(__clang__)
#define RTD_CPU_SIMD_MASKED_TAIL \
    RTD_PRAGMA(clang loop vectorize(assume_safety) vectorize_predicate(enable))
#else
#define RTD_CPU_SIMD_MASKED_TAIL RTD_CPU_SIMD
#endif
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
            if constexpr (BlockSparse<Kernel>) {
                if (!anyInRun(b0, b1, [&](int x) { return kernel.active(x, y); })) continue;
            }
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
                RTD_CPU_SIMD
                for (int x = b0; x < b1; ++x) kernel(x, y);
            }
        }
    } else {
        RTD_CPU_SIMD
        for (int x = x0; x < x1; ++x) kernel(x, y);
    }
}

// A kernel with tapRowStride() (kHasTapRowStride, launch_traits.h) reads rows y + k * stride,
// |k| <= 2 (an A-Trous level). In plain order a row it reads is read again over the next 4 * stride
// rows, which at wide strides no longer fit a core's L2 cache (strides 8 and 16 at 1080p, 4 to 16
// at 4K), so there (interleaveRows) the rows are visited in classes of equal y mod stride: y = r,
// r + stride, ..., for r = 0 .. stride - 1. Consecutive rows visited then share 4 of their 5 input
// rows. At narrower strides plain order is faster: its reads are continuous streams for the
// hardware prefetchers.
// Interleave when the rows read over 4 * stride rows (about 9 planes of floats: colour, variance,
// depth, normal, ID) exceed a core's L2, taken as 2 MiB (the value the row orders were timed
// with: docs/performance-cpu.md).
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
// instantiation: with the order chosen at run time the plain order ran slower
// (docs/performance-cpu.md).
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
        // rows it then reuses from its own L2. The other kernels keep the dynamic chunks, which
        // suit a streaming pass such as the ingest (both timed: docs/performance-cpu.md), as do
        // block-sparse levels: their work may lie in one core's block.
        if constexpr (kHasTapRowStride<Kernel> && !BlockSparse<Kernel>) {
#pragma omp for schedule(static)
            for (int k = 0; k < height; ++k) runRow(local, 0, width, rowOf(k));
        } else {
            // monotonic: libomp 14 serves the default (nonmonotonic) dynamic schedule by work
            // stealing, whose assertion aborted a run (docs/robustness.md); so every dynamic loop.
#pragma omp for schedule(monotonic : dynamic, 4)
            for (int k = 0; k < height; ++k) runRow(local, 0, width, rowOf(k));
        }
    }
}

// A kernel with filterSharingPairs (the course's A-Trous level, Atrous) evaluates each pair of
// pixels once for both: a row stores, for its taps in the rows below, the weights it has as their
// tap, which those rows then load. Each core runs its block of the visited rows in runs (a run:
// rows `step` apart, step 1 in plain order, the stride in classes of equal y mod stride) and keeps
// the stored weights of the last 2 stride / step rows in a ring of rows of its scratch. The rows
// above a run's first are run first for their stored weights only (zero above the image).
template <class Kernel>
concept SharesPairs = requires(const Kernel& k, const PartnerWeightRows& rows) {
    k.template filterSharingPairs<true>(0, 0, rows);
    k.template filterSharingPairs<false>(0, 0, rows);
};

// The ring's shape for one level: 2 stride / step + 1 rows, each kForwardTaps planes of the
// width plus a margin of 2 strides (the taps above reach that far out), rounded to whole cache
// lines. The margins stay 0: taps in the border weigh nothing.
struct PartnerRing {
    int rows = 0;
    int margin = 0;
    long planeStride = 0;
    PartnerRing(int stride, int step, int width)
        : rows(2 * stride / step + 1),
          margin((2 * stride + 15) / 16 * 16),
          planeStride(width + 2L * margin) {}
    std::size_t floatsPerRow() const { return std::size_t(kForwardTaps) * planeStride; }
    std::size_t floatsPerCore() const { return std::size_t(rows) * floatsPerRow(); }
};

// Whether a SharesPairs kernel visits its rows in classes of equal y mod stride: as
// interleaveRows, but counting the plain order's ring too, and against 3/4 of L2 (the output
// rows share it). At 512x512 the course's stride 16 then runs interleaved (in plain order its
// ring of 33 rows holds 0.76 MB besides 1.2 MB of tap rows); at 1920x1080, strides 4 to 16
// (the timings: docs/performance-cpu.md).
inline bool visitsInterleaved(int stride, int width, int height) {
    if (stride <= 1 || stride >= height) return false;
    long tapRows = 4L * stride * width * long(sizeof(float)) * kPlanesPerTap;
    long ring = long(PartnerRing(stride, 1, width).floatsPerCore() * sizeof(float));
    return tapRows + ring > kL2CacheBytes / 4 * 3;
}

// Where core c's block of the visited rows starts (c = cores: the end), one contiguous block per
// core as in parallelRows' static schedule. In plain order (step 1) each core but the first also
// runs `above` rows for their weights only, about half a row's work each, so those cores take
// that many half rows fewer (at most height / 2 cores of them: the blocks stay in order and
// within the image).
inline int sharingBlockStart(int c, int cores, int height, int above, int step) {
    if (c <= 0) return 0;
    if (c >= cores) return height;
    const double extra = step == 1 ? std::min(0.5 * above, height / (2.0 * cores)) : 0.0;
    const double share = (height + (cores - 1) * extra) / cores;
    return int(c * share - (c - 1) * extra + 0.5);
}

template <bool WithResult, class Kernel>
RTD_INLINE void runSharingRow(const Kernel& kernel, int width, int y,
                              const PartnerWeightRows& rows) {
    RTD_CPU_SIMD
    for (int x = 0; x < width; ++x) kernel.template filterSharingPairs<WithResult>(x, y, rows);
}

template <class Kernel, class RowOf>
void parallelRowsSharingPairs(int width, int height, const Kernel& kernel, RowOf rowOf, int step,
                              float* scratch) {
    const int stride = kernel.tapRowStride();
    const PartnerRing ring(stride, step, width);
    const int above = 2 * stride / step;  // rows run before a run's first, for their weights
#pragma omp parallel
    {
        flushDenormalsToZero();
        const Kernel local = kernel;  // a private copy, as in parallelRows
        const int core = omp_get_thread_num(), cores = omp_get_num_threads();
        float* const mine = scratch + std::size_t(core) * ring.floatsPerCore();
        // The ring row of a run's m-th row (m < 0: the rows above it), at column 0.
        auto ringRow = [&](int m) {
            int slot = ((m % ring.rows) + ring.rows) % ring.rows;
            return mine + std::size_t(slot) * ring.floatsPerRow() + ring.margin;
        };
        for (int r = 0; r < ring.rows; ++r) {
            for (int k = 0; k < kForwardTaps; ++k) {
                float* plane = ringRow(r) + k * ring.planeStride;
                std::fill(plane - ring.margin, plane, 0.0f);
                std::fill(plane + width, plane + width + ring.margin, 0.0f);
            }
        }
        const int k0 = sharingBlockStart(core, cores, height, above, step),
                  k1 = sharingBlockStart(core + 1, cores, height, above, step);
        for (int k = k0; k < k1;) {
            const int yStart = rowOf(k);
            int count = 1;
            while (k + count < k1 && rowOf(k + count) == yStart + count * step) ++count;
            for (int m = -above; m < 0; ++m) {
                const int y = yStart + m * step;
                float* own = ringRow(m);
                if (y < 0) {
                    for (int t = 0; t < kForwardTaps; ++t)
                        std::fill(own + t * ring.planeStride, own + t * ring.planeStride + width,
                                  0.0f);
                } else {
                    runSharingRow<false>(local, width, y,
                                         {own, nullptr, nullptr, ring.planeStride});
                }
            }
            for (int m = 0; m < count; ++m)
                runSharingRow<true>(local, width, yStart + m * step,
                                    {ringRow(m), ringRow(m - stride / step),
                                     ringRow(m - 2 * stride / step), ring.planeStride});
            k += count;
        }
    }
}

// What a SharesPairs kernel needs of the scratch: the ring of every core at the widest
// stride any level can have (padding / 2), so that one allocation serves every level (the
// device reserves it with the denoiser's buffers: Device::prepare).
inline std::size_t sharingScratchFloats(int width, int height, int padding) {
    std::size_t most = 0;
    for (int stride = 1; 2 * stride <= padding && stride < height; stride *= 2) {
        int step = visitsInterleaved(stride, width, height) ? stride : 1;
        most = std::max(most, PartnerRing(stride, step, width).floatsPerCore());
    }
    return most * std::size_t(omp_get_max_threads());
}

// A tile kernel's phase p for one tile (tile.h): its rows of items, each row vectorised.
template <int Phase, class Kernel>
RTD_INLINE void runTilePhase(const Kernel& kernel, typename Kernel::Shared& shared, int tileX,
                             int tileY) {
    constexpr PhaseExtent e = Kernel::phaseExtent(Phase);
    for (int v = e.v0; v < e.v0 + e.height; ++v) {
        RTD_CPU_SIMD_MASKED_TAIL
        for (int u = e.u0; u < e.u0 + e.width; ++u)
            kernel.template item<Phase>(shared, tileX, tileY, u, v);
    }
}

// Tiles shared out to all cores; each core runs a tile's phases in order with the tile's
// intermediates (Shared) on its stack, where they stay in L1.
template <class Kernel>
void parallelTiles(int width, int height, const Kernel& kernel) {
    const int across = tilesAcross<Kernel>(width), tiles = across * tilesDown<Kernel>(height);
#pragma omp parallel
    {
        flushDenormalsToZero();
        const Kernel local = kernel;  // a private copy, as in parallelRows
        typename Kernel::Shared shared;
#pragma omp for schedule(monotonic : dynamic, 4)
        for (int t = 0; t < tiles; ++t) {
            const int tileX = t % across * Kernel::kTileWidth,
                      tileY = t / across * Kernel::kTileHeight;
            [&]<int... Phase>(std::integer_sequence<int, Phase...>) {
                (runTilePhase<Phase>(local, shared, tileX, tileY), ...);
            }
            (std::make_integer_sequence<int, Kernel::kPhases>{});
        }
    }
}

// scratch: the device's, for the kernels that need it (SharesPairs); without it they run in
// their per-pixel form, as they do at strides of the image's height or more (every tap off the
// centre's row then lies in the border: nothing to share, and the plain order's ring would
// hold 2 stride + 1 rows, 210 MB for the 10th level at 512x512).
template <class Kernel>
void parallelFor2D(int width, int height, const Kernel& kernel, CpuScratch* scratch = nullptr) {
    if constexpr (kIsTileKernel<Kernel>) {
        parallelTiles(width, height, kernel);
    } else {
        if constexpr (kHasTapRowStride<Kernel>) {
            int stride = kernel.tapRowStride();
            if constexpr (SharesPairs<Kernel>) {
                if (scratch && stride < height) {
                    float* memory = scratch->floats(
                        sharingScratchFloats(width, height, kernel.g.layout.padding));
                    if (visitsInterleaved(stride, width, height))
                        return parallelRowsSharingPairs(
                            width, height, kernel,
                            [=](int k) { return interleavedRow(k, height, stride); }, stride,
                            memory);
                    return parallelRowsSharingPairs(
                        width, height, kernel, [](int k) { return k; }, 1, memory);
                }
            }
            if (stride > 1 && stride < height && interleaveRows(stride, width))
                return parallelRows(width, height, kernel,
                                    [=](int k) { return interleavedRow(k, height, stride); });
        }
        parallelRows(width, height, kernel, [](int k) { return k; });
    }
}

}  // namespace
}  // namespace rtd
