// Tile kernels: a kernel whose pixels need their neighbours' intermediate values (a window's
// statistics, then a window over those) computes a block of output pixels at a time, keeping
// the intermediates of the block and its halo in a `Shared` struct, rather than in planes that a
// second pass would read back from memory (NRD's and OIDN's GPU passes work so).
//
// A tile kernel declares
//   static constexpr int kTileWidth, kTileHeight;  // the output pixels of one tile
//   static constexpr int kPhases;
//   struct Shared { ... };                          // plain arrays of the tile's intermediates
//   static constexpr PhaseExtent phaseExtent(int phase);
//   template <int Phase> void item(Shared&, int tileX, int tileY, int u, int v) const;
// Phase p's items are (u, v) over phaseExtent(p), in tile coordinates: pixel (tileX + u,
// tileY + v), where (tileX, tileY) is the tile's first output pixel; u or v outside the tile
// is its halo. The items of one phase are independent of one another: each writes its own
// entries of Shared (or pixels of the output) and reads only what earlier phases wrote. So a
// back end may run them in any order and on any number of threads, with a barrier between
// phases: the GPU runs a tile per block, its threads striding over each phase's items, with
// __syncthreads() between phases and Shared in shared memory; the CPU runs a tile per core at
// a time, each phase's rows of items vectorised, Shared on its stack. Tests run the phases'
// items in reverse order too, which would expose an item that read another of its phase.
#pragma once

#include <type_traits>

#include "core/host_device.h"

namespace rtd {

// The items of one phase: u in [u0, u0 + width), v in [v0, v0 + height).
struct PhaseExtent {
    int u0, v0, width, height;
    RTD_HOST_DEVICE constexpr int items() const { return width * height; }
};

template <class Kernel, class = void>
inline constexpr bool kIsTileKernel = false;
template <class Kernel>
inline constexpr bool kIsTileKernel<Kernel, std::void_t<typename Kernel::Shared>> = true;

// The tiles covering a width x height image.
template <class Kernel>
RTD_HOST_DEVICE constexpr int tilesAcross(int width) {
    return (width + Kernel::kTileWidth - 1) / Kernel::kTileWidth;
}
template <class Kernel>
RTD_HOST_DEVICE constexpr int tilesDown(int height) {
    return (height + Kernel::kTileHeight - 1) / Kernel::kTileHeight;
}

// Phase `Phase`'s items k = first, first + step, ... (k: raster order over its extent) of the
// tile at (tileX, tileY): one GPU thread's share (first: its index, step: the block's size).
template <int Phase, class Kernel>
RTD_HOST_DEVICE RTD_INLINE void runPhaseItems(const Kernel& kernel, typename Kernel::Shared& shared,
                                              int tileX, int tileY, int first, int step) {
    constexpr PhaseExtent e = Kernel::phaseExtent(Phase);
    for (int k = first; k < e.items(); k += step)
        kernel.template item<Phase>(shared, tileX, tileY, e.u0 + k % e.width, e.v0 + k / e.width);
}

}  // namespace rtd
