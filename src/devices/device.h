// A compute device: memory, copies and kernel launches. The CPU device runs kernels with an
// OpenMP parallelFor2D; a GPU device launches the same functors from CUDA.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "kernels/kernel_list.h"
#include "rtdenoise/settings.h"

namespace rtd {

class Device {
  public:
    virtual ~Device() = default;
    virtual std::string name() const = 0;
    // True if kernels can read and write host memory directly (no staging copies needed).
    virtual bool sharesHostMemory() const = 0;
    // True where log2 is one instruction (a GPU's special-function unit): SVGF's normal factor
    // max(0, n.n')^128 is then cheapest as exp2(128 log2(n.n')) inside the weight's exponent. On
    // the CPU log2 is a polynomial, and one fitted near n.n' = 1 for sigma_n = 128 wins
    // (svgfWeight).
    virtual bool hasFastLogarithm() const { return false; }
    // True where SVGF keeps normal and depth interleaved, one 16-byte load per tap (a GPU),
    // rather than in planes that load as contiguous vectors (a CPU). Such a device also has a
    // fast logarithm (the interleaved kernels use the log2 form) and prefers fused passes (the
    // temporal stage reads the interleaved copies in its one-pass form only), and it runs a
    // pixel per thread: the interleaved SVGF iteration and variance skip background (inactive)
    // pixels by a branch, where the CPU's forms compute every lane and select.
    virtual bool interleavesGuide() const { return false; }
    // True where passes the CPU keeps apart run better as one (a GPU): there a pass's
    // intermediate planes cost a round trip through memory, and a rare branch (SVGF's 3x3
    // history search) only its warp. The CPU splits them so that each vectorises. (SVGF's
    // temporal stage, SvgfTemporal; the temporal method's geometry slopes, reprojection and
    // accumulation, ReprojectAccumulate.)
    virtual bool prefersFusedPasses() const { return false; }

    // True where the firefly removal runs as one tile pass (OutlierTile, tile.h), its window's
    // row sums kept in the tile rather than in planes a second pass reads back (and SVGF's
    // history-clamp row sums computed in the same pass).
    virtual bool runsTilePasses() const { return false; }
    // Working memory the course's A-Trous levels need besides their buffers on this device (the
    // CPU's rows of pair weights, CpuScratch), for frames of `layout` and levels up to stride
    // layout.padding / 2: reserved with the denoiser's buffers, so that no pass allocates.
    virtual void reserveAtrousWorkspace(const Layout& layout) { (void)layout; }

    virtual void* allocate(std::size_t bytes) = 0;
    virtual void release(void* pointer) noexcept = 0;
    virtual void copyToDevice(void* deviceDst, const void* hostSrc, std::size_t bytes) = 0;
    virtual void copyToHost(void* hostDst, const void* deviceSrc, std::size_t bytes) = 0;
    // Sets `bytes` bytes of device memory to `value` (like memset).
    virtual void fill(void* deviceDst, int value, std::size_t bytes) = 0;
    virtual void synchronize() = 0;
    // The ingest's per-pixel input flags (IngestKernel::inputFlags) summed: values replaced
    // (bits 0-1), pixels with a bad object ID (bit 2), values clamped (bits 3-4), object pixels
    // without a normal (bit 5).
    struct InputFlagCounts {
        long long nonFinite = 0;
        long long badObjectIds = 0;
        long long clamped = 0;
        long long missingNormals = 0;
    };
    virtual InputFlagCounts countInputFlags(const std::uint8_t* deviceFlags, std::size_t n) = 0;

#define RTD_DECLARE_LAUNCH(K) virtual void launch(const K& kernel, int width, int height) = 0;
    RTD_FOR_EACH_KERNEL(RTD_DECLARE_LAUNCH)
#undef RTD_DECLARE_LAUNCH

    // Timestamps in the device's own order of work (slot 0 up to kTimestampSlots - 1), read
    // after synchronize(): the time between two, in milliseconds.
    static constexpr int kTimestampSlots = 64;
    virtual void recordTimestamp(int slot) = 0;
    virtual double millisecondsBetween(int firstSlot, int secondSlot) = 0;

    // Bytes held in DeviceBuffers on this device (what a denoiser keeps resident).
    std::size_t allocatedBytes() const {
        return allocatedBytes_;
    }
    void noteAllocation(std::size_t bytes, bool allocated) {
        allocatedBytes_ = allocated ? allocatedBytes_ + bytes : allocatedBytes_ - bytes;
    }

  private:
    std::size_t allocatedBytes_ = 0;
};

// memcpy on every core (OpenMP), for host-side staging copies of whole frames.
void parallelCopy(void* dst, const void* src, std::size_t bytes);

// Throws rtd::Error(DeviceFailure) if the requested device is not available.
std::unique_ptr<Device> createDevice(DeviceType type, CpuIsa cpuIsa = CpuIsa::Auto);
std::unique_ptr<Device> createCpuDevice(CpuIsa isa = CpuIsa::Auto);
// Only in builds with the CUDA back end (RTD_HAS_CUDA); throws if no GPU is present.
std::unique_ptr<Device> createCudaDevice();
bool cudaDeviceAvailable();

// An array of T in a device's memory, freed with its owner.
template <class T>
class DeviceBuffer {
  public:
    DeviceBuffer() = default;
    DeviceBuffer(Device& device, std::size_t count)
        : device_(&device),
          data_(static_cast<T*>(device.allocate(count * sizeof(T)))),
          count_(count) {
        device.noteAllocation(bytes(), true);
    }
    ~DeviceBuffer() { reset(); }
    DeviceBuffer(DeviceBuffer&& o) noexcept { swap(o); }
    DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
        DeviceBuffer(std::move(o)).swap(*this);
        return *this;
    }
    DeviceBuffer(const DeviceBuffer&) = delete;
    DeviceBuffer& operator=(const DeviceBuffer&) = delete;

    void reset() noexcept {
        if (data_) {
            device_->noteAllocation(bytes(), false);
            device_->release(data_);
        }
        data_ = nullptr;
        count_ = 0;
    }
    void swap(DeviceBuffer& o) noexcept {
        std::swap(device_, o.device_);
        std::swap(data_, o.data_);
        std::swap(count_, o.count_);
    }
    T* data() const { return data_; }
    std::size_t size() const { return count_; }
    std::size_t bytes() const { return count_ * sizeof(T); }

  private:
    Device* device_ = nullptr;
    T* data_ = nullptr;
    std::size_t count_ = 0;
};

}  // namespace rtd
