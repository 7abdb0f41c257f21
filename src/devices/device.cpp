#include "devices/device.h"

#include "rtdenoise/error.h"

namespace rtd {

std::unique_ptr<Device> createDevice(DeviceType type) {
    switch (type) {
        case DeviceType::Cpu:
        case DeviceType::Auto:  // no GPU back end in this build: the CPU is the only device
            return createCpuDevice();
        case DeviceType::Cuda:
            throw Error(ErrorCode::DeviceFailure,
                        "--device cuda: this build has no CUDA back end; use --device cpu");
    }
    throw Error(ErrorCode::InvalidArgument, "unknown device type");
}

}  // namespace rtd
