// The CUDA back end: the same per-pixel kernel functors as the CPU, launched over a 2-D grid on
// one stream; device memory from cudaMalloc, copies and fills asynchronous on that stream.
#include <cuda_runtime.h>

#include <string>
#include <vector>

#include "devices/device.h"
#include "kernels/launch_traits.h"
#include "rtdenoise/error.h"

namespace rtd {
namespace {

void check(cudaError_t status, const char* what) {
    if (status != cudaSuccess)
        throw Error(
            status == cudaErrorMemoryAllocation ? ErrorCode::OutOfMemory : ErrorCode::DeviceFailure,
            std::string("cuda: ") + what + ": " + cudaGetErrorString(status));
}

// Blocks of 128 threads. Each kernel's register budget is set by __launch_bounds__'s minimum of
// resident blocks per SM (LaunchTraits): 6 (the default) caps a thread at 85 registers, 5 at
// 102, 4 at 128, 3 at 170; each family's is the fastest measured (docs/performance-gpu.md).
constexpr int kThreadsPerBlock = 128;

// The A-Trous iterations with their stride as a compile-time constant (Kernel::filter<Stride>):
// each tap row then needs one address per plane, its taps' column offsets immediates.
template <class Kernel, int Stride>
struct FixedStride {
    Kernel kernel;
    __device__ __forceinline__ void operator()(int x, int y) const {
        kernel.template filter<Stride>(x, y);
    }
};

// A fixed-stride iteration run as pixel pairs a stride apart in a column
// (Kernel::filterPair<Stride>), for kernels whose LaunchTraits say kPairsRows: two pixels share
// 20 of their 25 taps, so a pair loads 30 where two threads load 50. Thread row r handles rows
// top(r) and top(r) + Stride, top(r) = 2 Stride floor(r / Stride) + r mod Stride (each row
// once); a top row whose partner lies outside the image is filtered alone.
template <class Kernel, int Stride>
struct PairedRows {
    Kernel kernel;
    int height;
    static constexpr int threadRows(int height) {
        return (height + 2 * Stride - 1) / (2 * Stride) * Stride;
    }
    __device__ __forceinline__ void operator()(int x, int r) const {
        int top = r / Stride * (2 * Stride) + r % Stride;
        if (top + Stride < height)
            kernel.template filterPair<Stride>(x, top);
        else if (top < height)
            kernel.template filter<Stride>(x, top);
    }
};

// How each kernel is launched, one entry per kernel family: kMinBlocks, its register budget (the
// minimum of resident blocks per SM, above; 3 allows 170 registers); kFixedStridesUpTo, the
// strides up to which it runs as FixedStride<Kernel, s>, or as PairedRows<Kernel, s> where
// kPairsRows; fixedStrideMinBlocks() or pairMinBlocks(), their budget (functions: nvcc warns of
// a constant that an instantiation does not use).
struct DefaultLaunch {
    static constexpr int kMinBlocks = 6;
    static constexpr int kFixedStridesUpTo = 0;  // a family with fixed strides says kPairsRows
};
template <class Kernel>
struct LaunchTraits : DefaultLaunch {};
// The course's: in pairs at 168 registers (PairedRows, above).
template <bool NarrowNormal, bool Modulated>
struct LaunchTraits<Atrous<NarrowNormal, Modulated>> : DefaultLaunch {
    static constexpr int kMinBlocks = 4;
    static constexpr int kFixedStridesUpTo = 16;
    static constexpr bool kPairsRows = true;
    static constexpr int pairMinBlocks() { return 3; }
};
// SVGF's with the guide interleaved: in pairs at 128 registers (PairedRows, above).
template <int FixedSigmaNormal, bool Modulated, bool Interleaved>
struct LaunchTraits<SvgfAtrous<FixedSigmaNormal, Modulated, Interleaved>> : DefaultLaunch {
    static constexpr int kMinBlocks = 5;
    static constexpr int kFixedStridesUpTo = 16;
    static constexpr bool kPairsRows = Interleaved;  // filterPair is the interleaved form's
    static constexpr int pairMinBlocks() { return 4; }
    // The planar forms' (the CPU's, compiled here but not run: the CUDA device interleaves).
    static constexpr int fixedStrideMinBlocks() { return 4; }
};
// SVGF's one-pass temporal stage at 64 registers: its history gathers wait on memory, and more
// resident warps hide more of it.
template <bool Interleaved>
struct LaunchTraits<SvgfTemporal<Interleaved>> : DefaultLaunch {
    static constexpr int kMinBlocks = 8;
};
// The planar variance (the interleaved one keeps the default, see above).
template <int FixedSigmaNormal, bool SkipsInactive>
struct LaunchTraits<SvgfVariance<FixedSigmaNormal, false, SkipsInactive>> : DefaultLaunch {
    static constexpr int kMinBlocks = 5;
};
template <class Kernel, int Stride>
struct LaunchTraits<FixedStride<Kernel, Stride>> : DefaultLaunch {
    static constexpr int kMinBlocks = LaunchTraits<Kernel>::fixedStrideMinBlocks();
};
template <class Kernel, int Stride>
struct LaunchTraits<PairedRows<Kernel, Stride>> : DefaultLaunch {
    static constexpr int kMinBlocks = LaunchTraits<Kernel>::pairMinBlocks();
};

template <class Kernel>
__global__ void __launch_bounds__(kThreadsPerBlock, LaunchTraits<Kernel>::kMinBlocks)
    runKernel2D(Kernel kernel, int width, int height) {
    int x = int(blockIdx.x * blockDim.x + threadIdx.x);
    int y = int(blockIdx.y * blockDim.y + threadIdx.y);
    if (x < width && y < height) kernel(x, y);
}

// Tile kernels (tile.h): a block per tile, its threads striding over each phase's items, the
// tile's intermediates in shared memory, a barrier between phases.
constexpr int kTileThreads = 256;

template <int Phase, class Kernel>
__device__ __forceinline__ void runPhasesFrom(const Kernel& kernel, typename Kernel::Shared& shared,
                                              int tileX, int tileY) {
    if constexpr (Phase < Kernel::kPhases) {
        runPhaseItems<Phase>(kernel, shared, tileX, tileY, int(threadIdx.x), int(blockDim.x));
        if constexpr (Phase + 1 < Kernel::kPhases) {
            __syncthreads();  // the next phase reads what this one wrote
            runPhasesFrom<Phase + 1>(kernel, shared, tileX, tileY);
        }
    }
}

template <class Kernel>
__global__ void __launch_bounds__(kTileThreads) runTileKernel(Kernel kernel) {
    __shared__ typename Kernel::Shared shared;
    runPhasesFrom<0>(kernel, shared, int(blockIdx.x) * Kernel::kTileWidth,
                     int(blockIdx.y) * Kernel::kTileHeight);
}

// Block shape: 32 x 4, or 64 x 2 for the A-Trous iterations whose taps are 8 or more rows apart
// (tapRowStride()): a block then fetches half as many distinct rows.
template <class Kernel>
dim3 blockShape(const Kernel& kernel) {
    int x = 32;
    if constexpr (kHasTapRowStride<Kernel>) x = kernel.tapRowStride() >= 8 ? 64 : 32;
    return dim3(x, kThreadsPerBlock / x);
}

// Device::InputFlagCounts' fields, in order, from the flag bits (Device::InputFlagCounts).
constexpr int kInputFlagCounters = 6;

__global__ void countInputFlagsKernel(const std::uint8_t* flags, std::size_t n,
                                      unsigned long long* totals) {
    unsigned long long counts[kInputFlagCounters] = {};
    for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < n;
         i += std::size_t(gridDim.x) * blockDim.x) {
        counts[0] += flags[i] & 3;
        counts[1] += (flags[i] >> 2) & 1;
        counts[2] += (flags[i] >> 3) & 3;
        counts[3] += (flags[i] >> 5) & 1;
        counts[4] += (flags[i] >> 6) & 1;
        counts[5] += flags[i] >> 7;
    }
    for (int k = 0; k < kInputFlagCounters; ++k)
        if (counts[k]) atomicAdd(&totals[k], counts[k]);
}

Device::InputFlagCounts countsOf(const unsigned long long (&totals)[kInputFlagCounters]) {
    return {static_cast<long long>(totals[0]), static_cast<long long>(totals[1]),
            static_cast<long long>(totals[2]), static_cast<long long>(totals[3]),
            static_cast<long long>(totals[4]), static_cast<long long>(totals[5])};
}

// What every Device made for one ComputeDevice shares: the stream (the caller's, or one made
// here) and the pinned staging chunks, allocated once per ComputeDevice, not per denoiser.
class CudaContext final : public DeviceContext {
  public:
    static constexpr std::size_t kStageChunk = std::size_t(8) << 20;
    static constexpr int kStageSlots = 3;

    CudaContext(bool callerStream, cudaStream_t stream) {
        type = DeviceType::Cuda;
        check(cudaGetDevice(&device), "cudaGetDevice");
        cudaDeviceProp properties{};
        check(cudaGetDeviceProperties(&properties, device), "cudaGetDeviceProperties");
        name = std::string("cuda (") + properties.name + ")";
        ownsStream_ = !callerStream;
        queues = callerStream;
        if (callerStream)
            this->stream = stream;
        else
            check(cudaStreamCreateWithFlags(&this->stream, cudaStreamNonBlocking),
                  "cudaStreamCreate");
    }
    ~CudaContext() override {
        cudaStreamSynchronize(stream);
        // Only what was made: destroying a null event would leave an error for the next
        // launch's check to report (in another Denoiser on this thread).
        for (int k = 0; k < kStageSlots; ++k) {
            if (stageFree[k]) cudaEventDestroy(stageFree[k]);
            if (stage[k]) cudaFreeHost(stage[k]);
        }
        if (ownsStream_) cudaStreamDestroy(stream);
    }
    void synchronize() override { check(cudaStreamSynchronize(stream), "synchronize"); }
    // Once, at the first large copy (24 MiB of pinned host memory).
    void allocateStaging() {
        if (stage[0]) return;
        for (int k = 0; k < kStageSlots; ++k) {
            check(cudaHostAlloc(&stage[k], kStageChunk, cudaHostAllocDefault), "cudaHostAlloc");
            check(cudaEventCreateWithFlags(&stageFree[k], cudaEventDisableTiming),
                  "cudaEventCreate");
        }
    }

    int device = 0;
    std::string name;
    cudaStream_t stream = nullptr;
    void* stage[kStageSlots] = {};
    cudaEvent_t stageFree[kStageSlots] = {};
    int nextStage = 0;
    bool queues = false;  // device-memory frames are queued without a wait (the caller's stream)

  private:
    bool ownsStream_ = true;
};

class CudaDevice final : public Device {
  public:
    CudaDevice(std::shared_ptr<CudaContext> context, TilePasses tilePasses)
        : tiles_(tilePasses == TilePasses::On),
          context_(std::move(context)),
          stream_(context_->stream),
          stage_(context_->stage),
          stageFree_(context_->stageFree),
          nextStage_(context_->nextStage) {
        check(cudaMalloc(&counters_, 2 * kInputFlagCounters * sizeof(unsigned long long)),
              "cudaMalloc");
        check(cudaMemsetAsync(counters_, 0, 2 * kInputFlagCounters * sizeof(unsigned long long),
                              stream_),
              "memset");
        for (cudaEvent_t& e : events_) check(cudaEventCreate(&e), "cudaEventCreate");
    }
    ~CudaDevice() override {
        cudaStreamSynchronize(stream_);
        detailHistory_.reset();
        for (cudaEvent_t e : events_) cudaEventDestroy(e);
        cudaFree(counters_);
    }

    std::string name() const override { return context_->name; }
    // On the caller's stream the caller orders its work after ours: a frame need not be waited
    // for. On a stream of our own the caller could not, so each frame is.
    bool queuesWork() const override { return context_->queues; }
    bool sharesHostMemory() const override { return false; }

    // SVGF's guide interleaved (one 16-byte load per tap): its steps have that form here. The
    // fused stages keep their intermediates in registers and need no working planes.
    void prepare(const Layout& layout, const std::vector<StepKind>& steps) override {
        layout_ = layout;
        interleaved_ = false;
        bool detail = false;
        for (StepKind k : steps) {
            interleaved_ = interleaved_ || k == StepKind::SvgfTemporalStage;
            detail = detail || k == StepKind::DetailTemporalStage;
        }
        // The detail method's split temporal stage hands its history on through planes (its
        // guide is planar: its reprojection reads the planar form).
        detailHistory_.reset();
        if (detail)
            detailHistory_ = DeviceBuffer<float>(
                *this, std::size_t(kDetailHistoryPlanes) * std::size_t(layout.planeSize));
    }

    void run(const IngestStep& s) override {
        interleaved_ ? launch(ingestForm<true>(s.ingest)) : launch(s.ingest);
        if (s.hasMotion) launch(s.motion);
    }
    void run(const ConvertStep& s) override {
        runConvertStep(s, [this](const auto& k) { launch(k); });
    }
    void run(const DespeckleStep& s) override {
        runDespeckleStep(s, tiles_, [this](const auto& k) { launch(k); });
    }
    void run(const JbfStep& s) override {
        runJbfStep(s, [this](const auto& k) { launch(k); });
    }
    void run(const AtrousLevelStep& s) override {
        runAtrousLevelStep(s, [this](const auto& k) { launch(k); });
    }
    // Fused: the history in registers, the slopes computed where needed (ReprojectAccumulate).
    void run(const TemporalStageStep& s) override {
        const AccumulateModulatedKernel& a = s.accumulate;
        if (a.radius <= kNarrowWindow) {
            launch(ColorRowSumsKernel{a.g, a.current, a.rowSums, a.radius});
            launch(ReprojectAccumulateKernel{s.reproject, a});
        } else {
            launch(ColorRowSumsWideKernel{a.g, a.current, a.rowSums, a.radius});
            launch(ReprojectAccumulateWideKernel{s.reproject, accumulateForm<kWideWindow>(a)});
        }
    }
    void run(const GeometryStep& s) override {
        if (interleaved_)
            launch(GeometryDerivativesInterleavedKernel{s.geometry.g, s.geometry.out});
        else
            launch(s.geometry);
    }
    // Fused: a pass's intermediate planes would cost a round trip through memory, and the rare
    // 3x3 search's branch costs only its warp (SvgfTemporal).
    void run(const SvgfTemporalStageStep& s) override {
        const SvgfAccumulateKernel& a = s.accumulate;
        if (s.clampRows) launch(ColorRowSumsKernel{a.g, a.radiance, a.rowSums, kSvgfWindowRadius});
        if (interleaved_)
            launch(SvgfTemporalInterleavedKernel{s.reproject, a});
        else
            launch(SvgfTemporalKernel{s.reproject, a});
    }
    // log2 is one instruction here: max(0, n.n')^sigma as exp2(sigma log2(n.n')) for any sigma.
    void run(const SvgfVarianceStep& s) override {
        // Either guide layout skips the pixels whose history is long by a branch (detail's
        // guide is planar).
        interleaved_ ? launch(svgfVarianceForm<-1, true>(s.variance))
                     : launch(svgfVarianceForm<-1, false, true>(s.variance));
        if (s.historyFix.slow.data) launch(s.historyFix);
    }
    void run(const SvgfAtrousIterationStep& s) override {
        const SvgfAtrousModulatedKernel& k = s.iteration;
        if (interleaved_)
            s.modulated ? launch(svgfAtrousForm<-1, true, true>(k))
                        : launch(svgfAtrousForm<-1, false, true>(k));
        else
            s.modulated ? launch(k) : launch(svgfAtrousForm<-1, false, false>(k));
    }
    void run(const DetailTemporalStageStep& s) override {
        runDetailTemporalStep(s, {detailHistory_.data(), layout_.planeSize},
                              [this](const auto& k) { launch(k); });
    }

    void run(const DetailClampStep& s) override {
        runDetailClampStep(s, [this](const auto& k) { launch(k); });
    }
    void run(const DetailSplitStep& s) override { launch(s.split); }
    void run(const DetailStabiliseStep& s) override { launch(s.stabilise); }
    void run(const AddToOutputStep& s) override { launch(s.add); }
    void run(const ModulateStep& s) override { launch(s.modulate); }
    void run(const EnergyInputStep& s) override { launch(s.input); }
    void run(const LearnedMixStep& s) override { launch(s.mix); }
    void run(const EnergyStep& s) override {
        const int across = s.gain.grid.across, down = s.gain.grid.down;
        launchAny(s.sums, across, down);
        launchAny(s.accumulate, across, down);
        launchAny(s.frameCap, 1, 1);
        launchAny(s.tail, across, down);
        launchAny(s.gain, across, down);
        launchAny(s.frameGain, 1, 1);
        check(cudaGetLastError(), "kernel launch");
        launch(s.apply);
    }

    void* allocate(std::size_t bytes) override {
        void* p = nullptr;
        check(cudaMalloc(&p, bytes == 0 ? 1 : bytes), "cudaMalloc");
        return p;
    }
    void release(void* pointer) noexcept override { cudaFree(pointer); }
    // Host frames are pageable memory, which the driver would stage through its own pinned
    // buffers at about a third of the bus's speed: large copies go through pinned chunks of
    // ours instead, each filled on every core while the previous one is in flight.
    void copyToDevice(void* dst, const void* src, std::size_t bytes) override {
        if (bytes < kStageChunk / 4) {
            check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyHostToDevice, stream_),
                  "copy to device");
            return;
        }
        allocateStaging();
        for (std::size_t done = 0; done < bytes;) {
            std::size_t n = bytes - done < kStageChunk ? bytes - done : kStageChunk;
            int slot = nextStage_;
            nextStage_ = (slot + 1) % kStageSlots;
            // The slot's last copy must have left it before it is refilled.
            check(cudaEventSynchronize(stageFree_[slot]), "staging wait");
            parallelCopy(stage_[slot], static_cast<const char*>(src) + done, n);
            check(cudaMemcpyAsync(static_cast<char*>(dst) + done, stage_[slot], n,
                                  cudaMemcpyHostToDevice, stream_),
                  "copy to device");
            check(cudaEventRecord(stageFree_[slot], stream_), "cudaEventRecord");
            done += n;
        }
    }
    // Large copies back through the same pinned chunks: chunk k is copied out on every core
    // while chunk k + 1 is in flight. Returns when `dst` is complete (the caller reads it next).
    void copyToHost(void* dst, const void* src, std::size_t bytes) override {
        if (bytes < kStageChunk / 4) {
            check(cudaMemcpyAsync(dst, src, bytes, cudaMemcpyDeviceToHost, stream_),
                  "copy to host");
            synchronize();
            return;
        }
        allocateStaging();
        const std::size_t chunks = (bytes + kStageChunk - 1) / kStageChunk;
        auto size = [&](std::size_t k) {
            return k + 1 < chunks ? kStageChunk : bytes - k * kStageChunk;
        };
        for (std::size_t k = 0; k <= chunks; ++k) {
            if (k < chunks) {  // queue chunk k (stream order: after any copy out of its slot)
                int slot = int(k % kStageSlots);
                check(cudaMemcpyAsync(stage_[slot], static_cast<const char*>(src) + k * kStageChunk,
                                      size(k), cudaMemcpyDeviceToHost, stream_),
                      "copy to host");
                check(cudaEventRecord(stageFree_[slot], stream_), "cudaEventRecord");
            }
            if (k > 0) {  // drain chunk k - 1
                int slot = int((k - 1) % kStageSlots);
                check(cudaEventSynchronize(stageFree_[slot]), "staging wait");
                parallelCopy(static_cast<char*>(dst) + (k - 1) * kStageChunk, stage_[slot],
                             size(k - 1));
            }
        }
    }
    void fill(void* dst, int value, std::size_t bytes) override {
        check(cudaMemsetAsync(dst, value, bytes, stream_), "cudaMemsetAsync");
    }
    void synchronize() override { check(cudaStreamSynchronize(stream_), "synchronize"); }
    // Events in the stream: no host wait between passes.
    void recordTimestamp(int slot) override {
        if (slot >= 0 && slot < kTimestampSlots)
            check(cudaEventRecord(events_[slot], stream_), "cudaEventRecord");
    }
    double millisecondsBetween(int first, int second) override {
        float ms = 0.0f;
        check(cudaEventElapsedTime(&ms, events_[first], events_[second]), "cudaEventElapsedTime");
        return ms;
    }
    InputFlagCounts countInputFlags(const std::uint8_t* flags, std::size_t n) override {
        check(
            cudaMemsetAsync(counters_, 0, kInputFlagCounters * sizeof(unsigned long long), stream_),
            "memset");
        countInputFlagsKernel<<<256, 256, 0, stream_>>>(flags, n, counters_);
        check(cudaGetLastError(), "countInputFlags");
        unsigned long long totals[kInputFlagCounters] = {};
        copyToHost(totals, counters_, sizeof totals);
        return countsOf(totals);
    }

    // Queued frames' flags add up in the second half of counters_ until takeQueuedInputFlags().
    void queueInputFlagCount(const std::uint8_t* flags, std::size_t n) override {
        countInputFlagsKernel<<<256, 256, 0, stream_>>>(flags, n, counters_ + kInputFlagCounters);
        check(cudaGetLastError(), "countInputFlags");
    }
    InputFlagCounts takeQueuedInputFlags() override {
        unsigned long long totals[kInputFlagCounters] = {};
        copyToHost(totals, counters_ + kInputFlagCounters, sizeof totals);
        check(cudaMemsetAsync(counters_ + kInputFlagCounters, 0, sizeof totals, stream_), "memset");
        return countsOf(totals);
    }

  private:
    template <class Kernel>
    void launch(const Kernel& kernel) {
        launchAny(kernel, layout_.width, layout_.height);
        check(cudaGetLastError(), "kernel launch");
    }

    template <class Kernel>
    void launchAny(const Kernel& kernel, int width, int height) {
        if constexpr (kIsTileKernel<Kernel>) {
            dim3 grid(tilesAcross<Kernel>(width), tilesDown<Kernel>(height));
            runTileKernel<<<grid, kTileThreads, 0, stream_>>>(kernel);
        } else {
            dim3 block = blockShape(kernel);
            dim3 grid((width + block.x - 1) / block.x, (height + block.y - 1) / block.y);
            launchOn(kernel, grid, block, width, height);
        }
    }

    // The kernel as FixedStride<Kernel, s> when its stride s is one of those, else as it is.
    template <class Kernel, int Stride = 1>
    void launchOn(const Kernel& kernel, dim3 grid, dim3 block, int width, int height) {
        if constexpr (Stride <= LaunchTraits<Kernel>::kFixedStridesUpTo) {
            if (kernel.tapRowStride() != Stride) {
                launchOn<Kernel, 2 * Stride>(kernel, grid, block, width, height);
            } else if constexpr (LaunchTraits<Kernel>::kPairsRows) {
                using Paired = PairedRows<Kernel, Stride>;
                int rows = Paired::threadRows(height);
                dim3 pairGrid(grid.x, (rows + block.y - 1) / block.y);
                runKernel2D<<<pairGrid, block, 0, stream_>>>(Paired{kernel, height}, width, rows);
            } else {
                runKernel2D<<<grid, block, 0, stream_>>>(FixedStride<Kernel, Stride>{kernel}, width,
                                                         height);
            }
        } else {
            runKernel2D<<<grid, block, 0, stream_>>>(kernel, width, height);
        }
    }

    static constexpr std::size_t kStageChunk = CudaContext::kStageChunk;
    static constexpr int kStageSlots = CudaContext::kStageSlots;
    void allocateStaging() { context_->allocateStaging(); }

    bool tiles_;  // the firefly removal as one tile pass (a tuning for comparisons)
    bool interleaved_ = false;
    Layout layout_;
    std::shared_ptr<CudaContext> context_;
    cudaStream_t stream_;
    void* (&stage_)[kStageSlots];
    cudaEvent_t (&stageFree_)[kStageSlots];
    int& nextStage_;
    unsigned long long* counters_ = nullptr;  // this frame's flag counts, then the queued ones'
    DeviceBuffer<float> detailHistory_;       // the detail method's reprojected history
    cudaEvent_t events_[kTimestampSlots] = {};
};

}  // namespace

bool cudaDeviceAvailable() {
    int count = 0;
    return cudaGetDeviceCount(&count) == cudaSuccess && count > 0;
}

std::shared_ptr<DeviceContext> createCudaContext(bool callerStream, void* stream) {
    if (!cudaDeviceAvailable())
        throw Error(ErrorCode::DeviceFailure,
                    "--device cuda: no CUDA GPU is available (driver missing or no device)");
    return std::make_shared<CudaContext>(callerStream, static_cast<cudaStream_t>(stream));
}

std::unique_ptr<Device> createCudaDevice(const std::shared_ptr<DeviceContext>& context,
                                         TilePasses tilePasses) {
    auto cuda = std::dynamic_pointer_cast<CudaContext>(context);
    if (!cuda) throw Error(ErrorCode::DeviceFailure, "not a CUDA device context");
    return std::make_unique<CudaDevice>(std::move(cuda), tilePasses);
}

std::unique_ptr<Device> createCudaDevice(TilePasses tilePasses) {
    return createCudaDevice(createCudaContext(false, nullptr), tilePasses);
}

bool isCudaDeviceMemory(const void* pointer) {
    cudaPointerAttributes attributes{};
    if (cudaPointerGetAttributes(&attributes, pointer) != cudaSuccess) {
        cudaGetLastError();  // not an error to report later: host memory on older drivers
        return false;
    }
    return attributes.type == cudaMemoryTypeDevice || attributes.type == cudaMemoryTypeManaged;
}

}  // namespace rtd
