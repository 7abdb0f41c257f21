#include <omp.h>

#include <algorithm>
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
    CpuDevice(CpuIsa isa, TilePasses tilePasses)
        : kernels_(cpuKernels(isa)), tiles_(tilePasses == TilePasses::On), scratch_(*this) {}
    std::string name() const override {
        return "cpu (" + std::to_string(omp_get_max_threads()) + " threads, " +
               toString(kernels_.isa) + ")";
    }
    bool sharesHostMemory() const override { return true; }

    void prepare(const Layout& layout, const std::vector<StepKind>& steps) override {
        layout_ = layout;
        auto has = [&](StepKind k) {
            return std::find(steps.begin(), steps.end(), k) != steps.end();
        };
        auto planes = [&](DeviceBuffer<float>& b, int count) {
            b = DeviceBuffer<float>(*this, std::size_t(count) * std::size_t(layout.planeSize));
            fill(b.data(), 0, b.bytes());
        };
        // The A-Trous levels' rows of pair weights (CpuScratch), up to stride padding / 2.
        if (has(StepKind::AtrousLevel))
            scratch_.floats(sharingScratchFloats(layout.width, layout.height, layout.padding));
        // The split temporal stages hand their slopes and history on through planes.
        if (has(StepKind::TemporalStage)) {
            planes(derivatives_, 3);
            planes(reprojected_, 3);
        }
        if (has(StepKind::SvgfTemporalStage)) planes(svgfHistory_, kSvgfHistoryPlanes);
        if (has(StepKind::DetailTemporalStage)) planes(detailHistory_, kDetailHistoryPlanes);
    }

    void run(const IngestStep& s) override {
        launch(s.ingest);
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
    // Split: each pass vectorises (the reprojection's gathers would stop the accumulation's).
    void run(const TemporalStageStep& s) override {
        const AccumulateModulatedKernel& a = s.accumulate;
        ReprojectKernel reproject = s.reproject;
        reproject.derivatives = {derivatives_.data(), layout_.planeSize};
        reproject.reprojected = {reprojected_.data(), layout_.planeSize};
        forWindow(a.radius, [&]<int R>() {
            launch(ColorRowSums<R>{a.g, a.current, a.rowSums, a.radius});
            launch(GeometryDerivativesKernel{a.g, reproject.derivatives});
            launch(reproject);
            AccumulateModulated<R> accumulate = accumulateForm<R>(a);
            accumulate.reprojected = reproject.reprojected;
            launch(accumulate);
        });
    }
    void run(const GeometryStep& s) override { launch(s.geometry); }
    // Split: the bilinear reprojection vectorises; the 3x3 search runs on the few pixels whose
    // taps all failed (block-sparse), then the accumulation vectorises again.
    void run(const SvgfTemporalStageStep& s) override {
        const SvgfAccumulateKernel& a = s.accumulate;
        if (s.clampRows) launch(ColorRowSumsKernel{a.g, a.radiance, a.rowSums, kSvgfWindowRadius});
        SvgfReprojectKernel reproject = s.reproject;
        reproject.history = {svgfHistory_.data(), layout_.planeSize};
        launch(reproject);
        launch(svgfReprojectForm<true>(reproject));
        SvgfAccumulateKernel accumulate = a;
        accumulate.history = reproject.history;
        launch(accumulate);
    }
    // sigma_n = 128 (the paper's): max(0, n.n')^128 by a polynomial fitted near 1 (svgfWeight),
    // log2 being no single instruction here.
    void run(const SvgfVarianceStep& s) override {
        if (hasPaperSigmaNormal(s.variance.terms))
            launch(svgfVarianceForm<kPaperSigmaNormal, false>(s.variance));
        else
            launch(s.variance);
        if (s.historyFix.slow.data) launchWhereKeyed(s.historyFix, s.onlyKeyed);
    }
    void run(const SvgfAtrousIterationStep& s) override {
        const bool sigma128 = hasPaperSigmaNormal(s.iteration.terms);
        const SvgfAtrousModulatedKernel& k = s.iteration;
        if (s.modulated)
            sigma128 ? launch(svgfAtrousForm<kPaperSigmaNormal, true, false>(k)) : launch(k);
        else
            sigma128
                ? launchWhereKeyed(svgfAtrousForm<kPaperSigmaNormal, false, false>(k), s.onlyKeyed)
                : launchWhereKeyed(svgfAtrousForm<-1, false, false>(k), s.onlyKeyed);
    }
    // Split as SVGF's: the vectorised bilinear reprojection, the sparse 3x3 search, the
    // vectorised accumulation.
    void run(const DetailTemporalStageStep& s) override {
        runDetailTemporalStep(s, {detailHistory_.data(), layout_.planeSize},
                              [&](const auto& k) { launchWhereKeyed(k, s.onlyKeyed); });
    }

    void run(const DetailClampStep& s) override {
        runDetailClampStep(s, [&](const auto& k) { launchWhereKeyed(k, s.onlyKeyed); });
    }
    void run(const DetailSplitStep& s) override { launch(s.split); }
    void run(const DetailStabiliseStep& s) override { launch(s.stabilise); }
    void run(const AddToOutputStep& s) override { launchWhereKeyed(s.add, s.add.key); }
    void run(const ModulateStep& s) override { launch(s.modulate); }
    void run(const EnergyInputStep& s) override { launch(s.input); }
    void run(const LearnedMixStep& s) override { launch(s.mix); }
    void run(const EnergyStep& s) override {
        const int across = s.gain.grid.across, down = s.gain.grid.down;
        kernels_.runEnergyOutputSumsKernel(s.sums, across, down, scratch_);
        kernels_.runEnergyAccumulateKernel(s.accumulate, across, down, scratch_);
        kernels_.runEnergyFrameCapKernel(s.frameCap, 1, 1, scratch_);
        kernels_.runEnergyTailKernel(s.tail, across, down, scratch_);
        kernels_.runEnergyGainKernel(s.gain, across, down, scratch_);
        kernels_.runEnergyFrameGainKernel(s.frameGain, 1, 1, scratch_);
        launch(s.apply);
    }

    void* allocate(std::size_t bytes) override {
        // 64-byte alignment: whole cache lines, aligned vector loads.
        std::size_t rounded = (bytes + 63) / 64 * 64;
        void* p = std::aligned_alloc(64, rounded == 0 ? 64 : rounded);
        if (!p)
            throw Error(ErrorCode::OutOfMemory,
                        "cpu: out of memory (" + std::to_string(rounded) + " bytes)");
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
        long long nonFiniteGeometry = 0, background = 0;
#pragma omp parallel for reduction(+ : nonFinite, badIds, clamped, missingNormals, \
                                       nonFiniteGeometry, background) schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
            nonFinite += flags[i] & 3;
            badIds += (flags[i] >> 2) & 1;
            clamped += (flags[i] >> 3) & 3;
            missingNormals += (flags[i] >> 5) & 1;
            nonFiniteGeometry += (flags[i] >> 6) & 1;
            background += flags[i] >> 7;
        }
        return {nonFinite, badIds, clamped, missingNormals, nonFiniteGeometry, background};
    }

  private:
#define RTD_DEFINE_LAUNCH(K)                                              \
    void launch(const K& kernel) {                                        \
        kernels_.run##K(kernel, layout_.width, layout_.height, scratch_); \
    }
    RTD_FOR_EACH_CPU_KERNEL(RTD_DEFINE_LAUNCH)
#undef RTD_DEFINE_LAUNCH

    // The kernel, or where `keys` is set and the kernel has a WhereKeyed form, that form: the
    // runs of pixels whose key is < 0 are skipped.
    template <class Kernel>
    void launchWhereKeyed(const Kernel& kernel, const std::int32_t* keys) {
        using Masked = WhereKeyed<Kernel, kKeyedReach<Kernel>>;
        if constexpr (requires { launch(Masked{kernel, layout_, keys}); }) {
            if (keys) return launch(Masked{kernel, layout_, keys});
        }
        launch(kernel);
    }

    const CpuKernelTable& kernels_;
    bool tiles_;  // the firefly removal as one tile pass (a tuning for comparisons)
    CpuScratch scratch_;
    Layout layout_;
    DeviceBuffer<float> derivatives_, reprojected_, svgfHistory_,
        detailHistory_;  // the split stages' planes
    std::array<std::chrono::steady_clock::time_point, kTimestampSlots> stamps_{};
};

}  // namespace

std::unique_ptr<Device> createCpuDevice(CpuIsa isa, TilePasses tilePasses) {
    return std::make_unique<CpuDevice>(isa, tilePasses);
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
                    std::string("cpu kernels ") + toString(isa) + ": this build has none");
    if (int(isa) > int(best))
        throw Error(ErrorCode::DeviceFailure,
                    std::string("cpu kernels ") + toString(isa) +
                        ": this processor does not support it (best: " + toString(best) + ")");
    return *table;
}

}  // namespace rtd
