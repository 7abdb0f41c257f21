// The order in which the benchmarks feed a few stored frames to a denoiser.
#pragma once

#include <cstddef>

namespace rtd {

// 0, 1, ..., n-1, n-2, ..., 1, 0, 1, ...: the frames played forwards then backwards, so every
// step is between neighbouring frames (cycling 0..n-1 would cut back to frame 0 each time, a
// disocclusion of the whole moving scene that a real sequence does not have).
inline std::size_t pingPongFrame(std::size_t i, std::size_t n) {
    if (n < 2) return 0;
    std::size_t period = 2 * (n - 1), k = i % period;
    return k < n ? k : period - k;
}

}  // namespace rtd
