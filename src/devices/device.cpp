#include "devices/device.h"

#include <cstring>

#include "devices/cpu/cpu_kernels.h"
#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"
#include "tuning.h"

namespace rtd {

std::unique_ptr<Device> createDevice(DeviceType type, CpuIsa cpuIsa, TilePasses tilePasses) {
#if RTD_HAS_CUDA
    switch (type) {
        case DeviceType::Cpu:
            return createCpuDevice(cpuIsa, tilePasses);
        case DeviceType::Cuda:
            return createCudaDevice(tilePasses);
        case DeviceType::Auto:
            return cudaDeviceAvailable() ? createCudaDevice(tilePasses)
                                         : createCpuDevice(cpuIsa, tilePasses);
    }
#else
    switch (type) {
        case DeviceType::Cpu:
        case DeviceType::Auto:  // no GPU back end in this build: the CPU is the only device
            return createCpuDevice(cpuIsa, tilePasses);
        case DeviceType::Cuda:
            throw Error(ErrorCode::DeviceFailure,
                        "--device cuda: this build has no CUDA back end (nvcc was not found when "
                        "it was configured); use --device cpu");
    }
#endif
    throw Error(ErrorCode::InvalidArgument, "unknown device type");
}

std::shared_ptr<DeviceContext> createDeviceContext(DeviceType type, bool callerStream,
                                                   void* cudaStream) {
#if RTD_HAS_CUDA
    if (type == DeviceType::Cuda || callerStream ||
        (type == DeviceType::Auto && cudaDeviceAvailable()))
        return createCudaContext(callerStream, cudaStream);
#else
    (void)cudaStream;
    if (type == DeviceType::Cuda || callerStream)
        throw Error(ErrorCode::DeviceFailure,
                    "cuda: this build has no CUDA back end (nvcc was not found when it was "
                    "configured); use the cpu device");
#endif
    return std::make_shared<DeviceContext>();
}

std::unique_ptr<Device> createDevice(const std::shared_ptr<DeviceContext>& context, CpuIsa cpuIsa,
                                     TilePasses tilePasses) {
#if RTD_HAS_CUDA
    if (context->type == DeviceType::Cuda) return createCudaDevice(context, tilePasses);
#endif
    return createCpuDevice(cpuIsa, tilePasses);
}

#if !RTD_HAS_CUDA
bool isCudaDeviceMemory(const void*) {
    return false;
}
#endif

void parallelCopy(void* dst, const void* src, std::size_t bytes) {
    constexpr std::size_t kPiece = std::size_t(1) << 20;  // 1 MiB per task
    const long pieces = long((bytes + kPiece - 1) / kPiece);
#pragma omp parallel for schedule(static)
    for (long k = 0; k < pieces; ++k) {
        std::size_t start = std::size_t(k) * kPiece;
        std::size_t n = bytes - start < kPiece ? bytes - start : kPiece;
        std::memcpy(static_cast<char*>(dst) + start, static_cast<const char*>(src) + start, n);
    }
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
