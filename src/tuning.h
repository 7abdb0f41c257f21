// Device choices that leave the result as it is (up to rounding) and exist for comparisons and
// tests: the CPU kernels' instruction set and the firefly removal's tile pass. Not part of the
// public settings; the bench (--device cpu-scalar|cpu-sse2|..., --tile-passes) and the tests use
// them through makeTunedDenoiser.
#pragma once

#include "rtdenoise/denoiser.h"

namespace rtd {

// The CPU kernels' instruction set. Auto: the widest this processor and build support. Scalar:
// the same kernels not vectorised (one pixel at a time), the baseline speed-ups are quoted against.
enum class CpuIsa { Auto, Scalar, Sse2, Avx2, Avx512 };

// How the firefly removal runs: as one tile pass, its window statistics kept on chip (shared
// memory on a GPU) and SVGF's history-clamp row sums computed with it, or as separate passes
// over planes in memory. Windows of radius over 3 always run separately. Auto: the device's
// choice (separate on every device so far, see docs/performance-*.md).
enum class TilePasses { Auto, On, Off };

struct DeviceTuning {
    CpuIsa cpuIsa = CpuIsa::Auto;              // CPU device only
    TilePasses tilePasses = TilePasses::Auto;  // any device
};

Denoiser makeTunedDenoiser(const DenoiserSettings& settings, const DeviceTuning& tuning);

// The CPU instruction set Auto picks on this processor.
CpuIsa bestCpuInstructionSet();

const char* toString(CpuIsa isa);
const char* toString(TilePasses tilePasses);

}  // namespace rtd
