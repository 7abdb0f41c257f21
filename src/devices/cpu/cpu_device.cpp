#include <omp.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <new>

#include "devices/cpu/cpu_kernels.h"
#include "devices/cpu/cpu_scratch.h"
#include "devices/cpu/parallel_for.h"
#include "devices/device.h"
#include "rtdenoise/error.h"

namespace rtd {

#if !RTD_CPU_KERNELS_AVX2
const CpuKernelTable* cpuKernelsAvx2() {
    return nullptr;
}
#endif
#if !RTD_CPU_KERNELS_AVX512
const CpuKernelTable* cpuKernelsAvx512() {
    return nullptr;
}
#endif

float* CpuScratch::floats(std::size_t count) {
    if (buffer_.size() < count) {
        buffer_.reset();  // the old one first: no moment with both held
        buffer_ = DeviceBuffer<float>(device_, count);
    }
    return buffer_.data();
}

namespace {

class CpuDevice final : public Device {
  public:
    explicit CpuDevice(CpuIsa isa) : kernels_(cpuKernels(isa)), scratch_(*this) {}
    std::string name() const override {
        return "cpu (" + std::to_string(omp_get_max_threads()) + " threads, " +
               toString(kernels_.isa) + ")";
    }
    bool sharesHostMemory() const override { return true; }
    void reserveAtrousWorkspace(const Layout& layout) override {
        scratch_.floats(sharingScratchFloats(layout.width, layout.height, layout.padding));
    }

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
    // Kernels run synchronously here: a timestamp is the clock when it is recorded.
    void recordTimestamp(int slot) override {
        if (slot >= 0 && slot < kTimestampSlots) stamps_[slot] = std::chrono::steady_clock::now();
    }
    double millisecondsBetween(int first, int second) override {
        return std::chrono::duration<double, std::milli>(stamps_[second] - stamps_[first]).count();
    }
    InputFlagCounts countInputFlags(const std::uint8_t* flags, std::size_t n) override {
        long long nonFinite = 0, badIds = 0, clamped = 0, missingNormals = 0;
#pragma omp parallel for reduction(+ : nonFinite, badIds, clamped, missingNormals) schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
            nonFinite += flags[i] & 3;
            badIds += (flags[i] >> 2) & 1;
            clamped += (flags[i] >> 3) & 3;
            missingNormals += flags[i] >> 5;
        }
        return {nonFinite, badIds, clamped, missingNormals};
    }

#define RTD_DEFINE_LAUNCH(K)                                       \
    void launch(const K& kernel, int width, int height) override { \
        kernels_.run##K(kernel, width, height, scratch_);          \
    }
    RTD_FOR_EACH_KERNEL(RTD_DEFINE_LAUNCH)
#undef RTD_DEFINE_LAUNCH

  private:
    const CpuKernelTable& kernels_;
    CpuScratch scratch_;
    std::array<std::chrono::steady_clock::time_point, kTimestampSlots> stamps_{};
};

}  // namespace

std::unique_ptr<Device> createCpuDevice(CpuIsa isa) {
    return std::make_unique<CpuDevice>(isa);
}

CpuIsa bestCpuIsa() {
#if defined(__x86_64__) || defined(__i386__)
    __builtin_cpu_init();
    // x86-64-v4 and v3 feature sets, as the -march levels the tables are built for define them.
    bool v4 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
              __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512dq") &&
              __builtin_cpu_supports("avx512vl");
    bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
              __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    if (v4 && v3 && cpuKernelsAvx512()) return CpuIsa::Avx512;
    if (v3 && cpuKernelsAvx2()) return CpuIsa::Avx2;
#endif
    return CpuIsa::Sse2;
}

const CpuKernelTable& cpuKernels(CpuIsa isa) {
    CpuIsa best = bestCpuIsa();
    if (isa == CpuIsa::Auto) isa = best;
    const CpuKernelTable* table = isa == CpuIsa::Avx512 ? cpuKernelsAvx512()
                                  : isa == CpuIsa::Avx2 ? cpuKernelsAvx2()
                                  : isa == CpuIsa::Sse2 ? cpuKernelsSse2()
                                                        : cpuKernelsScalar();
    if (!table)
        throw Error(ErrorCode::DeviceFailure,
                    std::string("--cpu-isa ") + toString(isa) + ": this build has no such kernels");
    if (int(isa) > int(best))
        throw Error(ErrorCode::DeviceFailure,
                    std::string("--cpu-isa ") + toString(isa) +
                        ": this processor does not support it (best: " + toString(best) + ")");
    return *table;
}

}  // namespace rtd
