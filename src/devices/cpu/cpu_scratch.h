// Working memory of the CPU launchers besides the kernels' own buffers: each core's rows of
// A-Trous partner weights (parallel_for.h). The device keeps one, reserved with the denoiser's
// buffers (Device::prepare); a launch grows it only if it needs more than that
// (more OpenMP threads since), so passes and frames allocate nothing.
#pragma once

#include <cstddef>

#include "devices/device.h"

namespace rtd {

class CpuScratch {
  public:
    explicit CpuScratch(Device& device) : device_(device) {}
    // At least `count` floats, 64-byte aligned; valid until the next call. Defined in
    // cpu_device.cpp (compiled for the baseline instruction set: every kernel table calls it).
    float* floats(std::size_t count);

  private:
    Device& device_;
    DeviceBuffer<float> buffer_;
};

}  // namespace rtd
