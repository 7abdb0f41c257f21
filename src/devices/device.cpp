#include "devices/device.h"

#include "devices/cpu/cpu_kernels.h"
#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"

namespace rtd {

std::unique_ptr<Device> createDevice(DeviceType type, CpuIsa cpuIsa) {
#if RTD_HAS_CUDA
    switch (type) {
        case DeviceType::Cpu:
            return createCpuDevice(cpuIsa);
        case DeviceType::Cuda:
            return createCudaDevice();
        case DeviceType::Auto:
            return cudaDeviceAvailable() ? createCudaDevice() : createCpuDevice(cpuIsa);
    }
#else
    switch (type) {
        case DeviceType::Cpu:
        case DeviceType::Auto:  // no GPU back end in this build: the CPU is the only device
            return createCpuDevice(cpuIsa);
        case DeviceType::Cuda:
            throw Error(ErrorCode::DeviceFailure,
                        "--device cuda: this build has no CUDA back end (nvcc was not found when "
                        "it was configured); use --device cpu");
    }
#endif
    throw Error(ErrorCode::InvalidArgument, "unknown device type");
}

std::string gpuName() {
#if RTD_HAS_CUDA
    return cudaDeviceAvailable() ? createCudaDevice()->name() : std::string();
#else
    return {};
#endif
}

CpuIsa bestCpuInstructionSet() {
    return bestCpuIsa();
}

}  // namespace rtd
