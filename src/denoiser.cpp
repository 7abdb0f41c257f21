// The Denoiser: builds each method's pipeline as a list of named passes over device buffers, and
// runs it once per frame. Buffers are allocated when the frame size is first seen (or changes),
// never per frame or per pass.
#include "rtdenoise/denoiser.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <functional>

#include "devices/device.h"
#include "rtdenoise/error.h"

namespace rtd {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

Mat4 toMat4(const Matrix4& m) {
    Mat4 r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m.m[i][j];
    return r;
}

EdgeStoppingTerms edgeTerms(const EdgeStoppingSettings& s) {
    return {1.0f / (2.0f * s.sigmaColor * s.sigmaColor),
            1.0f / (2.0f * s.sigmaNormal * s.sigmaNormal),
            1.0f / (2.0f * s.sigmaPlane * s.sigmaPlane)};
}

void checkImage(const Image& image, int width, int height, int channels, const char* what) {
    if (image.width != width || image.height != height || image.channels != channels ||
        image.pixels.size() != std::size_t(width) * height * channels)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("frame: {} is {}x{}x{} ({} values), expected {}x{}x{}", what,
                                image.width, image.height, image.channels, image.pixels.size(),
                                width, height, channels));
}

// Names the first out-of-range ID (the ingest counts them on the device; this runs on the host
// only for a frame already known to hold one).
void checkObjectIds(const std::int32_t* ids, int w, int h, int objectCount) {
    std::size_t n = std::size_t(w) * h;
    for (std::size_t i = 0; i < n; ++i) {
        std::int32_t id = ids[i];
        if (id < -1 || id >= objectCount)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: object ID {} at pixel ({}, {}) is outside -1..{}", id,
                                    i % w, i / w, objectCount - 1));
    }
}

void checkFrame(const Frame& f) {
    int w = f.width(), h = f.height();
    if (w <= 0 || h <= 0) throw Error(ErrorCode::InvalidInput, "frame: empty beauty image");
    checkImage(f.beauty, w, h, 3, "beauty");
    checkImage(f.normal, w, h, 3, "normal");
    checkImage(f.position, w, h, 3, "position");
    checkImage(f.depth, w, h, 1, "depth");
    if (f.albedo) checkImage(*f.albedo, w, h, 3, "albedo");
    if (f.objectId.size() != std::size_t(w) * h)
        throw Error(
            ErrorCode::InvalidInput,
            fmt::format("frame: objectId has {} values, expected {}x{}", f.objectId.size(), w, h));
    // Object IDs are checked on the device, by the ingest (see throwBadObjectId).
}

}  // namespace

struct Pass {
    PassInfo info;
    std::function<void()> run;
};

// A frame input as the device reads it: the caller's buffer itself where the device shares host
// memory, else a copy in `staging`.
struct InputBuffer {
    DeviceBuffer<float> staging;  // only for devices that cannot read host memory
    const void* device = nullptr;
};

struct Denoiser::Impl {
    DenoiserSettings settings;
    std::unique_ptr<Device> device;
    std::vector<Pass> pipeline;
    std::vector<PassInfo> passInfos;
    FrameStats stats;

    Layout layout;    // padded planar layout of every device image (and the frame size)
    int padding = 0;  // widest filter reach of this pipeline, in pixels
    int current = 0;  // which of the ping-pong buffers hold this frame (the other: the last)
    bool hasHistory = false;
    bool temporal = false;  // the method keeps history
    bool frameHasAlbedo = false;

    // Planar device buffers (3 planes for colours and vectors).
    DeviceBuffer<float> noisy, despeckled, position, albedo, filtered, scratch, reprojected;
    DeviceBuffer<float> normal[2], depth[2], history[2];
    DeviceBuffer<std::int32_t> objectId[2];
    // The filters' tap keys where objects are not kept apart (else the object IDs serve).
    DeviceBuffer<std::int32_t> filterKeys;
    DeviceBuffer<float> derivatives;  // 3 planes: dz/dx, dz/dy, fwidth(n)
    DeviceBuffer<float> windowSums;   // 7 planes: separable window statistics
    DeviceBuffer<std::uint8_t> inputFlags, validity;
    // svgf only
    DeviceBuffer<float> illumination, varianceOut, filterA, filterB;  // 3, 4, 4, 4 planes
    DeviceBuffer<float> moments[2], historyLength[2], feedback[2];    // 2, 1, 4 planes
    DeviceBuffer<float> svgfHistory;  // kSvgfHistoryPlanes: the reprojected history (CPU)
    // svgf on a device that interleaves the guide: normal + depth, 4 floats per padded pixel,
    // this frame's and the last (in place of the normal and depth planes)
    DeviceBuffer<float> normalDepth[2];
    bool interleavedGuide = false;
    DeviceBuffer<float> stageOutput;
    DeviceBuffer<ObjectReprojection> objects;
    std::vector<ObjectReprojection> hostObjects;
    int objectCount = 0;            // K of the current frame
    float* outputTarget = nullptr;  // this frame's interleaved output, as the device sees it

    // The previous frame's matrices (for back-projection).
    std::vector<Matrix4> previousObjectToWorld;
    Matrix4 previousWorldToScreen;

    // Per frame: the caller's buffers as the device sees them.
    InputBuffer inBeauty, inNormal, inPosition, inDepth, inId, inAlbedo;

    explicit Impl(const DenoiserSettings& s) : settings(s) {
        validate(settings);
        device = createDevice(settings.device, settings.cpuIsa);
        temporal = settings.method == Method::Temporal || settings.method == Method::Svgf;
        // Its temporal stage reads the interleaved copies in the one-pass form only.
        interleavedGuide = settings.method == Method::Svgf && device->interleavesGuide() &&
                           device->prefersFusedPasses();
        buildPipeline();
    }

    std::size_t pixels() const { return std::size_t(layout.width) * layout.height; }
    int width() const { return layout.width; }
    int height() const { return layout.height; }
    int previous() const { return 1 - current; }
    Planes3 planes(const DeviceBuffer<float>& b) const { return {b.data(), layout.planeSize}; }
    PlaneSet planeSet(const DeviceBuffer<float>& b) const { return {b.data(), layout.planeSize}; }
    PlaneSet sums() const { return planeSet(windowSums); }
    GBufferView gbuffer() const {
        return {layout,
                planes(normal[current]),
                planes(position),
                depth[current].data(),
                objectId[current].data(),
                {normalDepth[current].data()},
                filterKeys.data()};
    }
    PreviousGeometry previousGeometry() const {
        return {objectId[previous()].data(),
                depth[previous()].data(),
                planes(normal[previous()]),
                {normalDepth[previous()].data()}};
    }
    HistoryTest historyTest() const {
        return {settings.history.geometryTests ? 1 : 0, settings.history.depthTolerance,
                settings.history.normalTolerance};
    }
    template <class Kernel>
    Kernel svgfReproject() const {
        return {gbuffer(),
                previousGeometry(),
                objects.data(),
                objectCount,
                planeSet(derivatives),
                historyTest(),
                planeSet(feedback[previous()]),
                planeSet(moments[previous()]),
                historyLength[previous()].data(),
                planeSet(svgfHistory),
                validity.data(),
                hasHistory ? 1 : 0};
    }
    SvgfAccumulateKernel svgfAccumulate(const DeviceBuffer<float>& in) const {
        const SvgfSettings& sv = settings.svgf;
        return {gbuffer(),
                planes(in),
                sums(),
                kSvgfWindowRadius,
                sv.historyClampK,
                planeSet(svgfHistory),
                validity.data(),
                planes(illumination),
                planeSet(moments[current]),
                historyLength[current].data(),
                planeSet(varianceOut),
                sv.alpha,
                sv.momentsAlpha,
                float(sv.maxHistory)};
    }

    // Calls run.operator()<MaxRadius>() with the window instantiation (window_sums.h) that
    // covers `radius`: the 7x7 one where it suffices, else the widest.
    template <class Run>
    static void forWindow(int radius, Run&& run) {
        if (radius <= kNarrowWindow)
            run.template operator()<kNarrowWindow>();
        else
            run.template operator()<kWideWindow>();
    }
    // A window kernel in the instantiation that covers `radius` (forWindow).
    template <template <int> class Kernel, class... Fields>
    void launchWindowed(int radius, const Fields&... fields) {
        forWindow(radius, [&]<int R>() { launch(Kernel<R>{fields...}); });
    }

    // How far a window kernel of this radius reads (its compile-time width, window_sums.h).
    static int windowReach(int radius) {
        return radius <= kNarrowWindow ? kNarrowWindow : kWideWindow;
    }

    template <class Kernel>
    void launch(const Kernel& kernel) {
        device->launch(kernel, width(), height());
    }

    // A zero-filled padded buffer of `planes` planes (the border stays 0 forever after).
    DeviceBuffer<float> planesBuffer(int count) {
        DeviceBuffer<float> b(*device, std::size_t(count) * std::size_t(layout.planeSize));
        device->fill(b.data(), 0, b.bytes());
        return b;
    }

    void allocate(int w, int h) {
        // Rows padded to whole cache lines; the border (see kernels/views.h) rounded up likewise
        // so that pixel (0, 0) is aligned.
        constexpr int kAlign = 16;
        int border = (padding + kAlign - 1) / kAlign * kAlign;
        layout.width = w;
        layout.height = h;
        layout.padding = border;
        layout.pitch = (w + 2 * border + kAlign - 1) / kAlign * kAlign;
        layout.origin = border * layout.pitch + border;
        long long planeSize = (long long)layout.pitch * (h + 2 * border);
        if (7 * planeSize > 0x7fffffffLL)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: {}x{} is too large for one device image", w, h));
        layout.planeSize = int(planeSize);
        std::size_t n = pixels(), padded = std::size_t(planeSize);
        Device& d = *device;
        // Only what this pipeline uses (deviceMemoryBytes() reports the total).
        bool atrousLevels = settings.method == Method::Atrous ||
                            (settings.method == Method::Temporal &&
                             settings.temporal.spatialFilter == SpatialFilter::Atrous);
        bool assignmentTemporal = settings.method == Method::Temporal;
        if (atrousLevels) d.reserveAtrousWorkspace(layout);
        for (auto* b : {&noisy, &position, &albedo}) *b = planesBuffer(3);
        for (int k = 0; k < 2; ++k) {
            if (interleavedGuide) {
                normalDepth[k] = planesBuffer(4);
            } else {
                normal[k] = planesBuffer(3);
                depth[k] = planesBuffer(1);
            }
        }
        if (settings.method != Method::Svgf) filtered = planesBuffer(3);
        if (settings.outlier.enabled) despeckled = planesBuffer(3);
        if (atrousLevels) scratch = planesBuffer(3);
        if (assignmentTemporal) {
            for (auto* b : {&history[0], &history[1]}) *b = planesBuffer(3);
            // The fused pass keeps the reprojected history in registers.
            if (!d.prefersFusedPasses()) reprojected = planesBuffer(3);
        }
        // The temporal method's fused pass (a GPU's) computes its slopes where it needs them.
        if (settings.method == Method::Svgf ||
            (settings.method == Method::Temporal && !d.prefersFusedPasses()))
            derivatives = planesBuffer(3);
        if (usesWindowSums()) windowSums = planesBuffer(7);
        auto idPlane = [&] {  // -1 everywhere: the border reads as background
            DeviceBuffer<std::int32_t> ids(d, padded);
            d.fill(ids.data(), 0xff, ids.bytes());
            return ids;
        };
        for (auto& ids : objectId) ids = idPlane();
        filterKeys = idPlane();
        inputFlags = DeviceBuffer<std::uint8_t>(d, n);
        validity = DeviceBuffer<std::uint8_t>(d, padded);
        d.fill(validity.data(), kReprojectionNoHistory, validity.bytes());
        if (settings.method == Method::Svgf) {
            illumination = planesBuffer(3);
            varianceOut = planesBuffer(4);
            filterA = planesBuffer(4);
            filterB = planesBuffer(4);
            // The one-pass temporal stage keeps the history in registers.
            if (!device->prefersFusedPasses()) svgfHistory = planesBuffer(kSvgfHistoryPlanes);
            for (int k = 0; k < 2; ++k) {
                moments[k] = planesBuffer(2);
                historyLength[k] = planesBuffer(1);
                feedback[k] = planesBuffer(4);
            }
        }
        if (!d.sharesHostMemory()) {
            for (auto* in : {&inBeauty, &inNormal, &inPosition, &inAlbedo})
                in->staging = DeviceBuffer<float>(d, 3 * n);
            inDepth.staging = DeviceBuffer<float>(d, n);
            inId.staging = DeviceBuffer<float>(d, n);  // holds int32 IDs: same size
            stageOutput = DeviceBuffer<float>(d, 3 * n);
        }
        hasHistory = false;
    }

    void addPass(std::string name, std::vector<std::string> inputs,
                 std::vector<std::string> outputs, std::function<void()> run) {
        pipeline.push_back(
            {{std::move(name), std::move(inputs), std::move(outputs)}, std::move(run)});
    }

    // A pass's inputs, plus the albedo when it also modulates the output.
    static std::vector<std::string> withModulation(bool modulated, std::vector<std::string> names) {
        if (modulated) names.push_back("albedo");
        return names;
    }

    // The albedo multiplied back into `source` (its first three planes), written straight
    // into the caller's interleaved output (or the staging buffer a GPU copies it from): for the
    // methods whose last pass does not do it as it writes.
    void addModulatePass(std::string inputName, const DeviceBuffer<float>& source) {
        addPass("modulate", {std::move(inputName), "albedo"}, {"output"}, [this, &source] {
            launch(ModulateKernel{layout, planes(source), planes(albedo), outputTarget});
        });
    }

    // Adds the spatial filter reading `in`; its result lands in `filtered`.
    // modulateLast: the last A-Trous level also writes the output (the atrous method).
    void addSpatialPasses(SpatialFilter filter, DeviceBuffer<float>* in, const std::string& inName,
                          bool modulateLast = false) {
        const EdgeStoppingTerms edges = edgeTerms(settings.edges);
        if (filter == SpatialFilter::Jbf) {
            padding = std::max(padding, settings.jbf.radius);
            float coordScale = 1.0f / (2.0f * settings.jbf.sigmaCoord * settings.jbf.sigmaCoord);
            int radius = settings.jbf.radius;
            addPass("jbf", {inName, "normal", "position", "objectId"}, {"filtered"},
                    [this, in, coordScale, radius, edges] {
                        if (oppositeNormalsVanish(edges))  // no square root per tap
                            launch(JbfNarrowNormalKernel{gbuffer(), planes(*in), planes(filtered),
                                                         radius, coordScale, edges});
                        else
                            launch(JbfKernel{gbuffer(), planes(*in), planes(filtered), radius,
                                             coordScale, edges});
                    });
            return;
        }
        // A-Trous levels ping-pong between `filtered` and `scratch`, ending in `filtered`.
        int levels = settings.atrous.passes;
        padding = std::max(padding, 2 << (levels - 1));  // the last level reaches 2 * 2^(levels-1)
        DeviceBuffer<float>* src = in;
        std::string srcName = inName;
        for (int level = 0; level < levels; ++level) {
            bool last = level == levels - 1;
            bool toFiltered = ((levels - 1 - level) % 2) == 0;
            DeviceBuffer<float>* dst = toFiltered ? &filtered : &scratch;
            std::string dstName = last ? "filtered" : fmt::format("atrous{}", level);
            int stride = 1 << level;
            bool modulated = last && modulateLast;
            addPass(fmt::format("atrous{}", level),
                    withModulation(modulated, {srcName, "normal", "position", "objectId"}),
                    {modulated ? std::string("output") : dstName},
                    [this, src, dst, stride, edges, modulated] {
                        auto run = [&]<class Kernel>() {
                            launch(Kernel{gbuffer(), planes(*src), planes(*dst), stride, edges,
                                          planes(albedo), outputTarget});
                        };
                        bool narrow = oppositeNormalsVanish(edges);  // no square root per tap
                        if (modulated)
                            narrow ? run.template operator()<AtrousNarrowNormalModulatedKernel>()
                                   : run.template operator()<AtrousModulatedKernel>();
                        else
                            narrow ? run.template operator()<AtrousNarrowNormalKernel>()
                                   : run.template operator()<AtrousKernel>();
                    });
            src = dst;
            srcName = dstName;
        }
    }

    void addGeometryPass() {
        // Derivatives read 1 pixel away; the reprojection's 3x3 taps reach 2 past the screen.
        padding = std::max(padding, 2);
        addPass("geometry", {"depth", "normal", "objectId"}, {"derivatives"}, [this] {
            if (interleavedGuide)
                launch(GeometryDerivativesInterleavedKernel{gbuffer(), planeSet(derivatives)});
            else
                launch(GeometryDerivativesKernel{gbuffer(), planeSet(derivatives)});
        });
    }

    // The assignment's pipeline after the spatial filter.
    void addTemporalPasses() {
        const bool fused = device->prefersFusedPasses();
        if (fused)
            padding = std::max(padding, 2);  // the fused pass's slopes and 2x2 taps (geometry's)
        else
            addGeometryPass();
        float alpha = settings.temporal.alpha, k = settings.temporal.clampK;
        int radius = settings.temporal.clampRadius;
        padding = std::max(padding, windowReach(radius));
        addPass("clamp-rows", {"filtered", "objectId"}, {"windowSums"}, [this, radius] {
            launchWindowed<ColorRowSums>(radius, gbuffer(), planes(filtered), sums(), radius);
        });
        // The accumulation modulates too: the result goes out from registers, not read back by
        // a modulate pass.
        auto accumulate = [this, alpha, k, radius]<int R>() {
            return AccumulateModulated<R>{gbuffer(),
                                          sums(),
                                          planes(filtered),
                                          planes(reprojected),
                                          validity.data(),
                                          planes(history[current]),
                                          alpha,
                                          k,
                                          radius,
                                          planes(albedo),
                                          outputTarget};
        };
        if (fused) {
            // One pass, the history in registers and the slopes computed (ReprojectAccumulate).
            addPass("reproject-accumulate",
                    {"position", "normal", "depth", "objectId", "previous geometry", "history",
                     "matrices", "filtered", "windowSums", "albedo"},
                    {"history", "validity", "output"}, [this, radius, accumulate] {
                        forWindow(radius, [&]<int R>() {
                            launch(ReprojectAccumulate<R>{reprojectKernel(),
                                                          accumulate.template operator()<R>()});
                        });
                    });
            return;
        }
        addPass("reproject",
                {"position", "normal", "depth", "objectId", "derivatives", "previous geometry",
                 "history", "matrices"},
                {"reprojected", "validity"}, [this] { launch(reprojectKernel()); });
        addPass("accumulate", {"filtered", "windowSums", "reprojected", "validity", "albedo"},
                {"history", "output"}, [this, radius, accumulate] {
                    forWindow(radius,
                              [&]<int R>() { launch(accumulate.template operator()<R>()); });
                });
    }
    // The temporal method's reprojection into `reprojected` (unallocated, and unused by
    // ReprojectAccumulate, where the device prefers fused passes).
    ReprojectKernel reprojectKernel() const {
        return {gbuffer(),
                previousGeometry(),
                objects.data(),
                objectCount,
                planeSet(derivatives),
                historyTest(),
                planes(history[previous()]),
                planes(reprojected),
                validity.data(),
                hasHistory ? 1 : 0};
    }

    // Where an svgf stage keeps illumination + variance (4 planes).
    enum class Slot { Variance, A, B, Feedback };
    DeviceBuffer<float>& slot(Slot s) {
        switch (s) {
            case Slot::Variance:
                return varianceOut;
            case Slot::A:
                return filterA;
            case Slot::B:
                return filterB;
            case Slot::Feedback:
                return feedback[current];
        }
        return filterA;
    }
    static std::string slotName(Slot s) {
        switch (s) {
            case Slot::Variance:
                return "illumination+variance";
            case Slot::A:
                return "filterA";
            case Slot::B:
                return "filterB";
            case Slot::Feedback:
                return "feedback";
        }
        return "?";
    }

    void addSvgfPasses(DeviceBuffer<float>* in, const std::string& inName) {
        const SvgfSettings& sv = settings.svgf;
        SvgfTerms terms{sv.sigmaDepth, sv.sigmaNormal, sv.sigmaLuminance};
        // The kernels with sigma_n = 128 fixed (svgfWeight), where log2 is not one instruction.
        const bool sigma128 = hasPaperSigmaNormal(terms) && !device->hasFastLogarithm();
        padding = std::max({padding, kSvgfWindowRadius, 2 << (sv.iterations - 1)});
        addGeometryPass();
        if (sv.historyClampK > 0.0f && !clampRowsInTile()) {
            addPass("svgf-clamp-rows", {inName, "objectId"}, {"windowSums"}, [this, in] {
                launch(ColorRowSumsKernel{gbuffer(), planes(*in), sums(), kSvgfWindowRadius});
            });
        }
        std::vector<std::string> reprojectInputs = {
            "position",          "normal",   "depth",   "objectId",      "derivatives",
            "previous geometry", "feedback", "moments", "historyLength", "matrices"};
        std::vector<std::string> accumulated = {"illumination", "moments", "historyLength",
                                                "illumination+variance"};
        if (device->prefersFusedPasses()) {
            // One pass, the history in registers (SvgfTemporalKernel).
            std::vector<std::string> inputs = reprojectInputs;
            inputs.insert(inputs.end(), {inName, "windowSums"});
            accumulated.push_back("validity");
            addPass("svgf-temporal", inputs, accumulated, [this, in] {
                auto reproject = svgfReproject<SvgfReprojectKernel>();
                if (interleavedGuide)
                    launch(SvgfTemporalInterleavedKernel{reproject, svgfAccumulate(*in)});
                else
                    launch(SvgfTemporalKernel{reproject, svgfAccumulate(*in)});
            });
        } else {
            addPass("svgf-reproject", reprojectInputs, {"history", "validity"},
                    [this] { launch(svgfReproject<SvgfReprojectKernel>()); });
            // The pixels whose bilinear taps all failed, again with the 3x3 search (few:
            // sparse).
            reprojectInputs.push_back("validity");
            addPass("svgf-reproject-search", reprojectInputs, {"history", "validity"},
                    [this] { launch(svgfReproject<SvgfReprojectSearchKernel>()); });
            addPass("svgf-accumulate", {inName, "windowSums", "objectId", "history", "validity"},
                    accumulated, [this, in] { launch(svgfAccumulate(*in)); });
        }
        // Short histories only (block-sparse): the accumulation wrote the rest.
        addPass(
            "svgf-variance",
            {"illumination", "moments", "historyLength", "derivatives", "illumination+variance"},
            {"illumination+variance"}, [this, terms, sigma128] {
                // The moments pass uses Falcor's wider luminance tolerance: no variance yet.
                SvgfTerms wide = terms;
                wide.sigmaLuminance = 10.0f;
                constexpr float kShortHistory = 4.0f;  // frames: below, estimate spatially
                auto run = [&]<class Kernel>() {
                    launch(Kernel{gbuffer(), planeSet(derivatives), planes(illumination),
                                  planeSet(moments[current]), historyLength[current].data(),
                                  planeSet(varianceOut), wide, kShortHistory});
                };
                if (interleavedGuide)
                    run.template operator()<SvgfVarianceInterleavedKernel>();
                else if (sigma128)
                    run.template operator()<SvgfVarianceNormal128Kernel>();
                else
                    run.template operator()<SvgfVarianceKernel>();
            });
        // Iterations read the variance pass's output (kept for the debug view), then ping-pong
        // between filterA and filterB; the feedback iteration writes the next frame's colour
        // history (feedback[current]) directly, and the next iteration reads it from there.
        Slot src = Slot::Variance;
        for (int it = 0; it < sv.iterations; ++it) {
            bool isFeedback = it == sv.feedbackIteration;
            Slot dst = isFeedback ? Slot::Feedback : (src == Slot::A ? Slot::B : Slot::A);
            int stride = 1 << it;
            // The last iteration writes the output (modulated) rather than its slot: the result
            // goes out from registers, not read back by a modulate pass. Unless it feeds the
            // history too: then its slot is written and a modulate pass follows.
            bool last = it == sv.iterations - 1;
            bool modulated = last && !isFeedback;
            addPass(fmt::format("svgf-atrous{}", it),
                    withModulation(modulated, {slotName(src), "normal", "depth", "derivatives"}),
                    {modulated ? std::string("output") : slotName(dst)},
                    [this, terms, stride, src, dst, modulated, sigma128] {
                        auto run = [&]<class Kernel>() {
                            launch(Kernel{gbuffer(), planeSet(derivatives), planeSet(slot(src)),
                                          planeSet(slot(dst)), stride, terms, planes(albedo),
                                          outputTarget});
                        };
                        if (interleavedGuide)
                            modulated
                                ? run.template operator()<SvgfAtrousInterleavedModulatedKernel>()
                                : run.template operator()<SvgfAtrousInterleavedKernel>();
                        else if (modulated)
                            sigma128 ? run.template operator()<SvgfAtrousNormal128ModulatedKernel>()
                                     : run.template operator()<SvgfAtrousModulatedKernel>();
                        else
                            sigma128 ? run.template operator()<SvgfAtrousNormal128Kernel>()
                                     : run.template operator()<SvgfAtrousKernel>();
                    });
            src = dst;
            if (last && !modulated) addModulatePass(slotName(dst), slot(dst));
        }
    }

    // Whether the firefly removal runs as one tile pass (settings.tilePasses; its window up
    // to OutlierTile's radius).
    bool outlierRunsAsTile() const {
        const bool tiles = settings.tilePasses == TilePasses::On ||
                           (settings.tilePasses == TilePasses::Auto && device->runsTilePasses());
        return settings.outlier.enabled && tiles && settings.outlier.radius <= kNarrowWindow;
    }
    // Whether that pass computes SVGF's history-clamp row sums too (svgf-clamp-rows is then not
    // added).
    bool clampRowsInTile() const {
        return outlierRunsAsTile() && settings.method == Method::Svgf &&
               settings.svgf.historyClampK > 0.0f;
    }
    // Whether a pass reads or writes windowSums (else it is not allocated): the temporal
    // methods' clamp windows, and the firefly removal's separate passes.
    bool usesWindowSums() const {
        return settings.method == Method::Temporal || settings.method == Method::Svgf ||
               (settings.outlier.enabled && !outlierRunsAsTile());
    }

    // The firefly removal as one tile pass (outlierRunsAsTile), with SVGF's history-clamp row
    // sums where clampRowsInTile.
    void addOutlierTilePass(int radius, float k) {
        if (clampRowsInTile()) {
            static_assert(
                OutlierClampTileKernel::kPhases == 4 &&
                    std::is_same_v<OutlierClampTileKernel, OutlierTile<kSvgfWindowRadius>>,
                "the tile's clamp window is SVGF's");
            addPass("outlier+clamp-rows", {"noisy", "objectId"}, {"despeckled", "windowSums"},
                    [this, radius, k] {
                        launch(OutlierClampTileKernel{gbuffer(), planes(noisy), planes(despeckled),
                                                      sums(), radius, k});
                    });
        } else {
            addPass("outlier-tile", {"noisy", "objectId"}, {"despeckled"}, [this, radius, k] {
                launch(
                    OutlierTileKernel{gbuffer(), planes(noisy), planes(despeckled), {}, radius, k});
            });
        }
    }

    void buildPipeline() {
        padding = std::max(settings.outlier.enabled ? settings.outlier.radius : 0,
                           settings.method == Method::Temporal ? settings.temporal.clampRadius : 0);
        std::vector<std::string> ingested = {"noisy", "albedo",   "normal",    "position",
                                             "depth", "objectId", "filterKeys"};
        addPass("ingest", {"frame"}, ingested, [this] { ingest(); });
        DeviceBuffer<float>* in = &noisy;
        std::string inName = "noisy";
        if (settings.outlier.enabled) {
            int radius = settings.outlier.radius;
            float k = settings.outlier.k;
            padding = std::max(padding, windowReach(radius));
            if (outlierRunsAsTile()) {
                addOutlierTilePass(radius, k);
            } else {
                addPass("outlier-rows", {"noisy", "objectId"}, {"windowSums"}, [this, radius] {
                    launchWindowed<LuminanceRowSums>(radius, gbuffer(), planes(noisy), sums(),
                                                     radius);
                });
                addPass("outlier", {"noisy", "windowSums", "objectId"}, {"despeckled"},
                        [this, radius, k] {
                            launchWindowed<Outlier>(radius, gbuffer(), sums(), planes(noisy),
                                                    planes(despeckled), radius, k);
                        });
            }
            in = &despeckled;
            inName = "despeckled";
        }
        switch (settings.method) {
            case Method::Jbf:
                addSpatialPasses(SpatialFilter::Jbf, in, inName);
                break;
            case Method::Atrous:
                addSpatialPasses(SpatialFilter::Atrous, in, inName, true);
                break;
            case Method::Temporal:
                addSpatialPasses(settings.temporal.spatialFilter, in, inName);
                addTemporalPasses();
                break;
            case Method::Svgf:
                addSvgfPasses(in, inName);
                break;
        }
        // Multiply the albedo back (1 without one). The other methods' last passes did it already
        // (the JBF's own pass is under 1 % of its time).
        if (settings.method == Method::Jbf) addModulatePass("filtered", filtered);
        if (int(pipeline.size()) >= Device::kTimestampSlots)
            throw Error(ErrorCode::InvalidArgument, "settings: too many passes to time");
        for (const Pass& p : pipeline) passInfos.push_back(p.info);
        stats.passMilliseconds.assign(pipeline.size(), 0.0);
    }

    void ingest() {
        auto floats = [](const InputBuffer& b) { return static_cast<const float*>(b.device); };
        auto run = [&]<class Kernel>() {
            launch(Kernel{layout,
                          floats(inBeauty),
                          floats(inNormal),
                          floats(inPosition),
                          floats(inDepth),
                          static_cast<const std::int32_t*>(inId.device),
                          objectCount,
                          frameHasAlbedo ? floats(inAlbedo) : nullptr,
                          settings.albedo.epsilon,
                          planes(noisy),
                          planes(albedo),
                          planes(normal[current]),
                          planes(position),
                          depth[current].data(),
                          objectId[current].data(),
                          inputFlags.data(),
                          {normalDepth[current].data()},
                          filterKeys.data(),
                          settings.edges.separateObjects ? 1 : 0});
        };
        if (interleavedGuide)
            run.template operator()<IngestInterleavedKernel>();
        else
            run.template operator()<IngestKernel>();
    }

    // One matrix per object: current world -> object -> previous world (-> previous screen).
    void uploadObjectMatrices(const FrameView& f) {
        std::size_t count = std::size_t(f.objectCount);
        objectCount = f.objectCount;
        hostObjects.resize(count);
        for (std::size_t k = 0; k < count; ++k) {
            ObjectReprojection& o = hostObjects[k];
            o = ObjectReprojection{};
            Mat4 inverseModel;
            if (!hasHistory || k >= previousObjectToWorld.size() ||
                !invert(toMat4(f.objectToWorld[k]), inverseModel))
                continue;
            o.currentWorldToPreviousWorld =
                multiply(toMat4(previousObjectToWorld[k]), inverseModel);
            o.currentWorldToPreviousScreen =
                multiply(toMat4(previousWorldToScreen), o.currentWorldToPreviousWorld);
            o.valid = 1;
        }
        if (objects.size() < std::max<std::size_t>(count, 1))  // grows only with K
            objects = DeviceBuffer<ObjectReprojection>(*device, std::max<std::size_t>(count, 1));
        if (count > 0)
            device->copyToDevice(objects.data(), hostObjects.data(),
                                 count * sizeof(ObjectReprojection));
    }

    void bindInputs(const FrameView& f) {
        frameHasAlbedo = f.albedo != nullptr && settings.albedo.demodulate;
        struct Source {
            InputBuffer* in;
            const void* host;
            std::size_t bytes;
        };
        std::size_t n = pixels();
        Source sources[] = {
            {&inBeauty, f.beauty, 3 * n * sizeof(float)},
            {&inNormal, f.normal, 3 * n * sizeof(float)},
            {&inPosition, f.position, 3 * n * sizeof(float)},
            {&inDepth, f.depth, n * sizeof(float)},
            {&inId, f.objectId, n * sizeof(std::int32_t)},
            {&inAlbedo, frameHasAlbedo ? f.albedo : nullptr,
             frameHasAlbedo ? 3 * n * sizeof(float) : 0},
        };
        // Device memory, and host memory a CPU device reads directly, need no copy.
        bool direct = device->sharesHostMemory() || f.space == MemorySpace::Device;
        for (Source& s : sources) {
            if (direct || s.host == nullptr) {
                s.in->device = s.host;
            } else {
                device->copyToDevice(s.in->staging.data(), s.host, s.bytes);
                s.in->device = s.in->staging.data();
            }
        }
        device->synchronize();
    }

    void process(const Frame& f, Image& output) {
        checkFrame(f);
        if (output.width != f.width() || output.height != f.height() || output.channels != 3)
            output = Image(f.width(), f.height(), 3);
        process(viewOf(f), output.pixels.data());
    }

    void process(const FrameView& f, float* outputRgb) {
        checkView(f);
        if (f.width != width() || f.height != height()) allocate(f.width, f.height);

        auto start = Clock::now();
        bindInputs(f);
        objectCount = f.objectCount;
        if (temporal) uploadObjectMatrices(f);
        stats.uploadMilliseconds = millisecondsSince(start);

        bool direct = device->sharesHostMemory() || f.space == MemorySpace::Device;
        outputTarget = direct ? outputRgb : stageOutput.data();
        // Each pass's time from device timestamps: one wait for the whole frame, not one per
        // pass (on a GPU a wait costs about as much as a small kernel).
        device->recordTimestamp(0);
        for (std::size_t p = 0; p < pipeline.size(); ++p) {
            pipeline[p].run();
            device->recordTimestamp(int(p) + 1);
        }
        device->synchronize();
        for (std::size_t p = 0; p < pipeline.size(); ++p)
            stats.passMilliseconds[p] = device->millisecondsBetween(int(p), int(p) + 1);
        stats.deviceMilliseconds = device->millisecondsBetween(0, int(pipeline.size()));
        Device::InputFlagCounts flags = device->countInputFlags(inputFlags.data(), pixels());
        stats.nonFiniteReplaced = flags.nonFinite;
        stats.radianceClamped = flags.clamped;
        stats.missingNormals = flags.missingNormals;
        // Bad IDs were read as background; the frame is refused (before it becomes history),
        // naming the first such pixel.
        if (flags.badObjectIds > 0) throwBadObjectId(f);

        start = Clock::now();
        if (!direct)
            device->copyToHost(outputRgb, stageOutput.data(), 3 * pixels() * sizeof(float));
        device->synchronize();
        stats.downloadMilliseconds = millisecondsSince(start);

        // This frame's geometry and output are the next frame's history.
        previousObjectToWorld.assign(f.objectToWorld, f.objectToWorld + f.objectCount);
        previousWorldToScreen = f.worldToScreen;
        hasHistory = temporal;
        current = 1 - current;
    }

    void checkView(const FrameView& f) const {
        if (f.width <= 0 || f.height <= 0)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: size {}x{} is empty", f.width, f.height));
        if (!f.beauty || !f.normal || !f.position || !f.depth || !f.objectId || f.objectCount < 0 ||
            (f.objectCount > 0 && !f.objectToWorld))
            throw Error(ErrorCode::InvalidInput, "frame: a required buffer is missing");
        if (f.space == MemorySpace::Device && device->sharesHostMemory())
            throw Error(ErrorCode::InvalidArgument,
                        "frame: device memory needs a Denoiser on a GPU device (" + device->name() +
                            " reads host memory)");
    }

    [[noreturn]] void throwBadObjectId(const FrameView& f) {
        std::vector<std::int32_t> ids(pixels());
        device->copyToHost(ids.data(), inId.device, ids.size() * sizeof(std::int32_t));
        checkObjectIds(ids.data(), f.width, f.height, f.objectCount);
        throw Error(ErrorCode::InvalidInput, "frame: an object ID is outside -1..objectCount-1");
    }

    // One value per pixel of a padded device plane, on the host.
    template <class T>
    std::vector<T> downloadPlane(const T* plane) const {
        std::vector<T> padded(std::size_t(layout.planeSize)), values(pixels());
        device->copyToHost(padded.data(), plane, padded.size() * sizeof(T));
        for (int y = 0; y < height(); ++y)
            for (int x = 0; x < width(); ++x)
                values[std::size_t(y) * width() + x] = padded[layout.index(x, y)];
        return values;
    }

    Image debugImage(DebugView view) const {
        Image image(width(), height(), 3);
        if (!temporal || width() == 0) return image;
        int last = previous();  // process() has already flipped `current`
        if (view == DebugView::Reprojection) {
            static const float colours[5][3] = {
                {0.0f, 1.0f, 0.0f},  // valid: green
                {1.0f, 0.0f, 0.0f},  // outside the screen: red
                {1.0f, 1.0f, 0.0f},  // other object (or depth/normal disagree): yellow
                {0.0f, 0.0f, 1.0f},  // background: blue
                {0.0f, 0.0f, 0.0f},  // no history: black
            };
            std::vector<std::uint8_t> codes = downloadPlane(validity.data());
            for (std::size_t i = 0; i < codes.size(); ++i)
                for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = colours[codes[i] % 5][c];
            return image;
        }
        if (settings.method != Method::Svgf) return image;
        // Variance after the variance pass (before A-Trous) shown as its square root, the
        // luminance standard deviation (clipped at 1); history length as a fraction of the cap.
        bool variance = view == DebugView::Variance;
        std::vector<float> values =
            variance ? downloadPlane(varianceOut.data() + 3 * std::size_t(layout.planeSize))
                     : downloadPlane(historyLength[last].data());
        for (std::size_t i = 0; i < values.size(); ++i) {
            float v = variance ? std::min(1.0f, std::sqrt(std::max(values[i], 0.0f)))
                               : values[i] / float(settings.svgf.maxHistory);
            for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = v;
        }
        return image;
    }
};

Denoiser::Denoiser(const DenoiserSettings& settings) : impl_(std::make_unique<Impl>(settings)) {}
Denoiser::~Denoiser() = default;
Denoiser::Denoiser(Denoiser&&) noexcept = default;
Denoiser& Denoiser::operator=(Denoiser&&) noexcept = default;

Image Denoiser::processFrame(const Frame& frame) {
    Image output;
    impl_->process(frame, output);
    return output;
}

void Denoiser::processFrame(const Frame& frame, Image& output) {
    impl_->process(frame, output);
}

void Denoiser::processFrame(const FrameView& frame, float* outputRgb) {
    impl_->process(frame, outputRgb);
}

void Denoiser::reset() {
    impl_->hasHistory = false;
}
const DenoiserSettings& Denoiser::settings() const {
    return impl_->settings;
}
const std::vector<PassInfo>& Denoiser::passes() const {
    return impl_->passInfos;
}
const FrameStats& Denoiser::lastFrameStats() const {
    return impl_->stats;
}
std::size_t Denoiser::deviceMemoryBytes() const {
    return impl_->device->allocatedBytes();
}

std::string Denoiser::deviceName() const {
    return impl_->device->name();
}
Image Denoiser::debugImage(DebugView view) const {
    return impl_->debugImage(view);
}

}  // namespace rtd
