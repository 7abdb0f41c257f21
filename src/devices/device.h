// A compute device: memory, copies and the logical kernels (steps.h). The CPU device runs their
// functors with an OpenMP parallelFor2D; a GPU device launches the same functors from CUDA.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "devices/steps.h"
#include "rtdenoise/settings.h"
#include "tuning.h"

namespace rtd {

// What the Devices of one ComputeDevice share (on CUDA: the stream and the pinned staging). The
// CPU's holds nothing: each denoiser's Device has its own working memory.
struct DeviceContext {
    virtual ~DeviceContext() = default;
    // Waits for the work queued on the shared stream (none on the CPU).
    virtual void synchronize() {}
    DeviceType type = DeviceType::Cpu;  // Cpu or Cuda
};

class Device {
  public:
    virtual ~Device() = default;
    virtual std::string name() const = 0;
    // True if a frame of device buffers may be left queued when processFrame returns (a GPU on
    // the caller's stream), false if each call returns with its work done.
    virtual bool queuesWork() const { return false; }
    // True if kernels can read and write host memory directly (no staging copies needed).
    virtual bool sharesHostMemory() const = 0;

    // Sees a pipeline's logical steps before its first frame (and when the frame size changes),
    // picks each one's form and reserves the working memory those forms need beside the
    // pipeline's own images (counted in allocatedBytes()), so that no step allocates.
    virtual void prepare(const Layout& layout, const std::vector<StepKind>& steps) = 0;

    virtual void* allocate(std::size_t bytes) = 0;
    virtual void release(void* pointer) noexcept = 0;
    virtual void copyToDevice(void* deviceDst, const void* hostSrc, std::size_t bytes) = 0;
    virtual void copyToHost(void* hostDst, const void* deviceSrc, std::size_t bytes) = 0;
    // Sets `bytes` bytes of device memory to `value` (like memset).
    virtual void fill(void* deviceDst, int value, std::size_t bytes) = 0;
    virtual void synchronize() = 0;
    // The ingest's per-pixel input flags (IngestKernel::inputFlags) summed: values replaced
    // (bits 0-1), pixels with a bad object ID (bit 2), values clamped (bits 3-4), object pixels
    // without a normal (bit 5), object pixels with a NaN/Inf position or depth (bit 6),
    // background pixels (bit 7).
    struct InputFlagCounts {
        long long nonFinite = 0;
        long long badObjectIds = 0;
        long long clamped = 0;
        long long missingNormals = 0;
        long long nonFiniteGeometry = 0;
        long long background = 0;
    };
    virtual InputFlagCounts countInputFlags(const std::uint8_t* deviceFlags, std::size_t n) = 0;
    // The same without a wait: the counts add up on the device until takeQueuedInputFlags()
    // (after a synchronize()) reads and clears them.
    virtual void queueInputFlagCount(const std::uint8_t* deviceFlags, std::size_t n) {
        queued_ = add(queued_, countInputFlags(deviceFlags, n));
    }
    virtual InputFlagCounts takeQueuedInputFlags() {
        InputFlagCounts taken = queued_;
        queued_ = {};
        return taken;
    }

    // The logical kernels (steps.h), each over the frame's pixels in this device's form.
    virtual void run(const IngestStep& step) = 0;
    virtual void run(const DespeckleStep& step) = 0;
    virtual void run(const JbfStep& step) = 0;
    virtual void run(const AtrousLevelStep& step) = 0;
    virtual void run(const TemporalStageStep& step) = 0;
    virtual void run(const GeometryStep& step) = 0;
    virtual void run(const SvgfTemporalStageStep& step) = 0;
    virtual void run(const SvgfVarianceStep& step) = 0;
    virtual void run(const SvgfAtrousIterationStep& step) = 0;
    virtual void run(const DetailTemporalStageStep& step) = 0;
    virtual void run(const DetailClampStep& step) = 0;
    virtual void run(const DetailSplitStep& step) = 0;
    virtual void run(const DetailStabiliseStep& step) = 0;
    virtual void run(const AddToOutputStep& step) = 0;
    virtual void run(const ModulateStep& step) = 0;
    virtual void run(const EnergyInputStep& step) = 0;
    virtual void run(const EnergyStep& step) = 0;
    virtual void run(const LearnedMixStep& step) = 0;
    virtual void run(const ConvertStep& step) = 0;

    // Timestamps in the device's own order of work (slot 0 up to kTimestampSlots - 1), read
    // after synchronize(): the time between two, in milliseconds.
    static constexpr int kTimestampSlots = 64;
    virtual void recordTimestamp(int slot) = 0;
    virtual double millisecondsBetween(int firstSlot, int secondSlot) = 0;

    // Bytes held in DeviceBuffers on this device (what a denoiser keeps resident).
    std::size_t allocatedBytes() const { return allocatedBytes_; }
    void noteAllocation(std::size_t bytes, bool allocated) {
        allocatedBytes_ = allocated ? allocatedBytes_ + bytes : allocatedBytes_ - bytes;
    }

  private:
    static InputFlagCounts add(InputFlagCounts a, const InputFlagCounts& b) {
        a.nonFinite += b.nonFinite;
        a.badObjectIds += b.badObjectIds;
        a.clamped += b.clamped;
        a.missingNormals += b.missingNormals;
        a.nonFiniteGeometry += b.nonFiniteGeometry;
        a.background += b.background;
        return a;
    }
    std::size_t allocatedBytes_ = 0;
    InputFlagCounts queued_;
};

// memcpy on every core (OpenMP), for host-side staging copies of whole frames.
void parallelCopy(void* dst, const void* src, std::size_t bytes);

// Throws rtd::Error(DeviceFailure) if the requested device is not available.
// cpuIsa and tilePasses: the comparisons' tuning (tuning.h); Auto is the device's choice.
std::unique_ptr<Device> createDevice(DeviceType type, CpuIsa cpuIsa = CpuIsa::Auto,
                                     TilePasses tilePasses = TilePasses::Auto);
std::unique_ptr<Device> createCpuDevice(CpuIsa isa = CpuIsa::Auto,
                                        TilePasses tilePasses = TilePasses::Auto);
// A context for `type` (Auto: CUDA when a GPU is there). callerStream: CUDA only, queue on
// `cudaStream` (a cudaStream_t, null: the default stream) instead of a stream of its own.
std::shared_ptr<DeviceContext> createDeviceContext(DeviceType type, bool callerStream = false,
                                                   void* cudaStream = nullptr);
// A Device on `context` (each Denoiser has its own; they share the context's stream).
std::unique_ptr<Device> createDevice(const std::shared_ptr<DeviceContext>& context,
                                     CpuIsa cpuIsa = CpuIsa::Auto,
                                     TilePasses tilePasses = TilePasses::Auto);
// Only in builds with the CUDA back end (RTD_HAS_CUDA); throw if no GPU is present.
std::unique_ptr<Device> createCudaDevice(TilePasses tilePasses = TilePasses::Auto);
std::shared_ptr<DeviceContext> createCudaContext(bool callerStream, void* stream);
std::unique_ptr<Device> createCudaDevice(const std::shared_ptr<DeviceContext>& context,
                                         TilePasses tilePasses);
bool cudaDeviceAvailable();
// Whether `pointer` is GPU memory (cudaMalloc or managed); false in a build without CUDA.
bool isCudaDeviceMemory(const void* pointer);

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
