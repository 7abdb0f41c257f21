#include <omp.h>

#include <cstdlib>
#include <cstring>
#include <new>

#include "devices/cpu/parallel_for.h"
#include "devices/device.h"
#include "rtdenoise/error.h"

namespace rtd {
namespace {

class CpuDevice final : public Device {
  public:
    std::string name() const override {
        return "cpu (" + std::to_string(omp_get_max_threads()) + " threads)";
    }
    bool sharesHostMemory() const override { return true; }

    void* allocate(std::size_t bytes) override {
        // 64-byte alignment: whole cache lines, aligned vector loads.
        std::size_t rounded = (bytes + 63) / 64 * 64;
        void* p = std::aligned_alloc(64, rounded == 0 ? 64 : rounded);
        if (!p) throw Error(ErrorCode::DeviceFailure, "cpu: out of memory");
        return p;
    }
    void release(void* pointer) noexcept override { std::free(pointer); }
    void copyToDevice(void* dst, const void* src, std::size_t bytes) override {
        std::memcpy(dst, src, bytes);
    }
    void copyToHost(void* dst, const void* src, std::size_t bytes) override {
        std::memcpy(dst, src, bytes);
    }
    void fill(void* dst, int value, std::size_t bytes) override { std::memset(dst, value, bytes); }
    void synchronize() override {}
    long long sumBytes(const std::uint8_t* data, std::size_t n) override {
        long long total = 0;
#pragma omp parallel for reduction(+ : total) schedule(static)
        for (std::size_t i = 0; i < n; ++i) total += data[i];
        return total;
    }

#define RTD_DEFINE_LAUNCH(K)                                       \
    void launch(const K& kernel, int width, int height) override { \
        parallelFor2D(width, height, kernel);                      \
    }
    RTD_FOR_EACH_KERNEL(RTD_DEFINE_LAUNCH)
#undef RTD_DEFINE_LAUNCH
};

}  // namespace

std::unique_ptr<Device> createCpuDevice() {
    return std::make_unique<CpuDevice>();
}

}  // namespace rtd
