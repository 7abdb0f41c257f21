#include "devices/device.h"

#include "rtdenoise/error.h"

namespace rtd {

std::unique_ptr<Device> createDevice(DeviceType type) {
#if RTD_HAS_CUDA
    switch (type) {
        case DeviceType::Cpu:
            return createCpuDevice();
        case DeviceType::Cuda:
            return createCudaDevice();
        case DeviceType::Auto:
            return cudaDeviceAvailable() ? createCudaDevice() : createCpuDevice();
    }
#else
    switch (type) {
        case DeviceType::Cpu:
        case DeviceType::Auto:  // no GPU back end in this build: the CPU is the only device
            return createCpuDevice();
        case DeviceType::Cuda:
            throw Error(ErrorCode::DeviceFailure,
                        "--device cuda: this build has no CUDA back end (nvcc was not found when "
                        "it was configured); use --device cpu");
    }
#endif
    throw Error(ErrorCode::InvalidArgument, "unknown device type");
}

}  // namespace rtd
