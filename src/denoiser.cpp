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
            1.0f / (2.0f * s.sigmaPlane * s.sigmaPlane), s.separateObjects ? 1 : 0};
}

void checkImage(const Image& image, int width, int height, int channels, const char* what) {
    if (image.width != width || image.height != height || image.channels != channels ||
        image.pixels.size() != std::size_t(width) * height * channels)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("frame: {} is {}x{}x{} ({} values), expected {}x{}x{}", what,
                                image.width, image.height, image.channels, image.pixels.size(),
                                width, height, channels));
}

void checkFrame(const Frame& f) {
    int w = f.width(), h = f.height();
    if (w <= 0 || h <= 0) throw Error(ErrorCode::InvalidInput, "frame: empty beauty image");
    checkImage(f.beauty, w, h, 3, "beauty");
    checkImage(f.normal, w, h, 3, "normal");
    checkImage(f.position, w, h, 3, "position");
    checkImage(f.depth, w, h, 1, "depth");
    if (f.objectId.size() != std::size_t(w) * h)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("frame: objectId has {} values, expected {}x{}",
                                f.objectId.size(), w, h));
    auto objectCount = std::int32_t(f.objectToWorld.size());
    for (std::size_t i = 0; i < f.objectId.size(); ++i) {
        std::int32_t id = f.objectId[i];
        if (id < -1 || id >= objectCount)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: object ID {} at pixel ({}, {}) is outside -1..{}", id,
                                    i % w, i / w, objectCount - 1));
    }
}

}  // namespace

struct Pass {
    PassInfo info;
    std::function<void()> run;
};

struct Denoiser::Impl {
    DenoiserSettings settings;
    std::unique_ptr<Device> device;
    std::vector<Pass> pipeline;
    std::vector<PassInfo> passInfos;
    FrameStats stats;

    Layout layout;    // padded planar layout of every device image (and the frame size)
    int padding = 0;  // widest filter reach of this pipeline, in pixels
    int current = 0;  // which of the ping-pong buffers holds this frame's ID and output
    bool hasHistory = false;

    // Planar device buffers (3 planes for colours and vectors).
    DeviceBuffer<float> noisy, despeckled, normal, position, depth, filtered, scratch,
        reprojected;
    DeviceBuffer<float> history[2];
    DeviceBuffer<float> windowSums;  // 7 planes: separable window statistics
    DeviceBuffer<std::int32_t> objectId[2];
    DeviceBuffer<std::uint8_t> nonFinite, validity;
    // Staging for devices that cannot read host memory.
    DeviceBuffer<float> stageBeauty, stageNormal, stagePosition, stageDepth, stageOutput;
    DeviceBuffer<std::int32_t> stageId;
    DeviceBuffer<ObjectReprojection> objects;
    std::vector<ObjectReprojection> hostObjects;

    // What the previous frame's matrices were (for back-projection).
    std::vector<Matrix4> previousObjectToWorld;
    Matrix4 previousWorldToScreen;

    // Set per frame before the passes run.
    const Frame* frame = nullptr;
    const float* inBeauty = nullptr;
    const float* inNormal = nullptr;
    const float* inPosition = nullptr;
    const float* inDepth = nullptr;
    const std::int32_t* inId = nullptr;

    // Where the spatial filter's result lies (fixed when the pipeline is built).
    DeviceBuffer<float>* spatialOutput = nullptr;

    explicit Impl(const DenoiserSettings& s) : settings(s) {
        validate(settings);
        device = createDevice(settings.device);
        buildPipeline();
    }

    std::size_t pixels() const { return std::size_t(layout.width) * layout.height; }
    int width() const { return layout.width; }
    int height() const { return layout.height; }
    Planes3 planes(const DeviceBuffer<float>& b) const { return {b.data(), layout.planeSize}; }
    PlaneSet sums() const { return {windowSums.data(), layout.planeSize}; }
    GBufferView gbuffer() const {
        return {layout, planes(normal), planes(position), depth.data(), objectId[current].data()};
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
        if (3 * planeSize > 0x7fffffffLL)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: {}x{} is too large for one device image", w, h));
        layout.planeSize = int(planeSize);
        std::size_t n = pixels(), padded = std::size_t(planeSize);
        Device& d = *device;
        // Zero everywhere, ID -1 everywhere: the border reads as background forever after.
        for (auto* b : {&noisy, &despeckled, &normal, &position, &filtered, &scratch, &reprojected,
                        &history[0], &history[1]}) {
            *b = DeviceBuffer<float>(d, 3 * padded);
            d.fill(b->data(), 0, b->bytes());
        }
        windowSums = DeviceBuffer<float>(d, 7 * padded);
        d.fill(windowSums.data(), 0, windowSums.bytes());
        depth = DeviceBuffer<float>(d, padded);
        d.fill(depth.data(), 0, depth.bytes());
        for (auto& ids : objectId) {
            ids = DeviceBuffer<std::int32_t>(d, padded);
            d.fill(ids.data(), 0xff, ids.bytes());
        }
        nonFinite = DeviceBuffer<std::uint8_t>(d, n);
        validity = DeviceBuffer<std::uint8_t>(d, padded);
        d.fill(validity.data(), kReprojectionBackground, validity.bytes());
        if (!d.sharesHostMemory()) {
            stageBeauty = DeviceBuffer<float>(d, 3 * n);
            stageNormal = DeviceBuffer<float>(d, 3 * n);
            stagePosition = DeviceBuffer<float>(d, 3 * n);
            stageDepth = DeviceBuffer<float>(d, n);
            stageId = DeviceBuffer<std::int32_t>(d, n);
            stageOutput = DeviceBuffer<float>(d, 3 * n);
        }
        hasHistory = false;
    }

    void addPass(std::string name, std::vector<std::string> inputs,
                 std::vector<std::string> outputs, std::function<void()> run) {
        pipeline.push_back({{std::move(name), std::move(inputs), std::move(outputs)}, std::move(run)});
    }

    // Adds the spatial filter reading `in`; returns the buffer holding its result.
    DeviceBuffer<float>* addSpatialPasses(SpatialFilter filter, DeviceBuffer<float>* in,
                                          const std::string& inName) {
        const EdgeStoppingTerms edges = edgeTerms(settings.edges);
        if (filter == SpatialFilter::Jbf) {
            padding = std::max(padding, settings.jbf.radius);
            float coordScale = 1.0f / (2.0f * settings.jbf.sigmaCoord * settings.jbf.sigmaCoord);
            int radius = settings.jbf.radius;
            addPass("jbf", {inName, "normal", "position", "objectId"}, {"filtered"},
                    [this, in, coordScale, radius, edges] {
                        device->launch(JbfKernel{gbuffer(), planes(*in), planes(filtered), radius,
                                                 coordScale, edges},
                                       width(), height());
                    });
            return &filtered;
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
            addPass(fmt::format("atrous{}", level),
                    {srcName, "normal", "position", "objectId"}, {dstName},
                    [this, src, dst, stride, edges] {
                        device->launch(
                            AtrousKernel{gbuffer(), planes(*src), planes(*dst), stride, edges},
                            width(), height());
                    });
            src = dst;
            srcName = dstName;
        }
        return &filtered;
    }

    void buildPipeline() {
        padding = std::max(settings.outlier.enabled ? settings.outlier.radius : 0,
                           settings.method == Method::Temporal ? settings.temporal.clampRadius : 0);
        addPass("ingest", {"frame"}, {"noisy", "normal", "position", "depth", "objectId"},
                [this] { ingest(); });
        DeviceBuffer<float>* in = &noisy;
        std::string inName = "noisy";
        if (settings.outlier.enabled) {
            int radius = settings.outlier.radius;
            float k = settings.outlier.k;
            addPass("outlier-rows", {"noisy", "objectId"}, {"windowSums"}, [this, radius] {
                device->launch(LuminanceRowSumsKernel{gbuffer(), planes(noisy), sums(), radius},
                               width(), height());
            });
            addPass("outlier", {"noisy", "windowSums", "objectId"}, {"despeckled"},
                    [this, radius, k] {
                        device->launch(OutlierKernel{gbuffer(), sums(), planes(noisy),
                                                     planes(despeckled), radius, k},
                                       width(), height());
                    });
            in = &despeckled;
            inName = "despeckled";
        }
        SpatialFilter filter = settings.method == Method::Jbf      ? SpatialFilter::Jbf
                               : settings.method == Method::Atrous ? SpatialFilter::Atrous
                                                                   : settings.temporal.spatialFilter;
        spatialOutput = addSpatialPasses(filter, in, inName);

        if (settings.method == Method::Temporal) {
            addPass("reproject",
                    {"position", "objectId", "previousObjectId", "history", "matrices"},
                    {"reprojected", "validity"}, [this] { reproject(); });
            float alpha = settings.temporal.alpha, k = settings.temporal.clampK;
            int radius = settings.temporal.clampRadius;
            addPass("clamp-rows", {"filtered", "objectId"}, {"windowSums"}, [this, radius] {
                device->launch(ColorRowSumsKernel{gbuffer(), planes(*spatialOutput), sums(), radius},
                               width(), height());
            });
            addPass("accumulate", {"filtered", "windowSums", "reprojected", "validity"},
                    {"output", "history"}, [this, alpha, k, radius] {
                        device->launch(AccumulateKernel{gbuffer(), sums(), planes(*spatialOutput),
                                                        planes(reprojected), validity.data(),
                                                        planes(history[current]), alpha, k,
                                                        radius},
                                       width(), height());
                    });
        }
        for (const Pass& p : pipeline) passInfos.push_back(p.info);
        stats.passMilliseconds.assign(pipeline.size(), 0.0);
    }

    void ingest() {
        device->launch(IngestKernel{layout, inBeauty, inNormal, inPosition, inDepth, inId,
                                    planes(noisy), planes(normal), planes(position),
                                    depth.data(), objectId[current].data(), nonFinite.data()},
                       width(), height());
    }

    void reproject() {
        // One matrix per object: current world -> object -> previous world -> previous screen.
        const Frame& f = *frame;
        std::size_t count = f.objectToWorld.size();
        hostObjects.resize(count);
        for (std::size_t k = 0; k < count; ++k) {
            ObjectReprojection& o = hostObjects[k];
            o.valid = 0;
            o.currentWorldToPreviousScreen = Mat4{};
            Mat4 inverseModel;
            if (!hasHistory || k >= previousObjectToWorld.size() ||
                !invert(toMat4(f.objectToWorld[k]), inverseModel))
                continue;
            o.currentWorldToPreviousScreen =
                multiply(toMat4(previousWorldToScreen),
                         multiply(toMat4(previousObjectToWorld[k]), inverseModel));
            o.valid = 1;
        }
        if (objects.size() < std::max<std::size_t>(count, 1))
            objects = DeviceBuffer<ObjectReprojection>(*device, std::max<std::size_t>(count, 1));
        if (count > 0)
            device->copyToDevice(objects.data(), hostObjects.data(),
                                 count * sizeof(ObjectReprojection));
        int previous = 1 - current;
        device->launch(ReprojectKernel{gbuffer(), objectId[previous].data(), objects.data(),
                                       planes(history[previous]), planes(reprojected),
                                       validity.data(), hasHistory ? 1 : 0},
                       width(), height());
    }

    void process(const Frame& f, Image& output) {
        checkFrame(f);
        if (f.width() != width() || f.height() != height()) allocate(f.width(), f.height());
        frame = &f;

        auto start = Clock::now();
        std::size_t n = pixels();
        if (device->sharesHostMemory()) {
            inBeauty = f.beauty.pixels.data();
            inNormal = f.normal.pixels.data();
            inPosition = f.position.pixels.data();
            inDepth = f.depth.pixels.data();
            inId = f.objectId.data();
        } else {
            device->copyToDevice(stageBeauty.data(), f.beauty.pixels.data(), 3 * n * sizeof(float));
            device->copyToDevice(stageNormal.data(), f.normal.pixels.data(), 3 * n * sizeof(float));
            device->copyToDevice(stagePosition.data(), f.position.pixels.data(),
                                 3 * n * sizeof(float));
            device->copyToDevice(stageDepth.data(), f.depth.pixels.data(), n * sizeof(float));
            device->copyToDevice(stageId.data(), f.objectId.data(), n * sizeof(std::int32_t));
            device->synchronize();
            inBeauty = stageBeauty.data();
            inNormal = stageNormal.data();
            inPosition = stagePosition.data();
            inDepth = stageDepth.data();
            inId = stageId.data();
        }
        stats.uploadMilliseconds = millisecondsSince(start);

        for (std::size_t p = 0; p < pipeline.size(); ++p) {
            auto passStart = Clock::now();
            pipeline[p].run();
            device->synchronize();
            stats.passMilliseconds[p] = millisecondsSince(passStart);
        }
        stats.nonFiniteReplaced = device->sumBytes(nonFinite.data(), n);

        start = Clock::now();
        if (output.width != width() || output.height != height() || output.channels != 3)
            output = Image(width(), height(), 3);
        DeviceBuffer<float>& result =
            settings.method == Method::Temporal ? history[current] : *spatialOutput;
        float* packTarget = device->sharesHostMemory() ? output.pixels.data() : stageOutput.data();
        device->launch(PackKernel{layout, planes(result), packTarget}, width(), height());
        if (!device->sharesHostMemory())
            device->copyToHost(output.pixels.data(), stageOutput.data(), 3 * n * sizeof(float));
        device->synchronize();
        stats.downloadMilliseconds = millisecondsSince(start);

        // The output and IDs of this frame are the next frame's history.
        previousObjectToWorld = f.objectToWorld;
        previousWorldToScreen = f.worldToScreen;
        hasHistory = settings.method == Method::Temporal;
        current = 1 - current;
        frame = nullptr;
    }

    Image reprojectionDebugImage() const {
        Image image(width(), height(), 3);
        if (settings.method != Method::Temporal || width() == 0) return image;
        std::vector<std::uint8_t> padded(validity.size()), codes(pixels());
        device->copyToHost(padded.data(), validity.data(), padded.size());
        for (int y = 0; y < height(); ++y)
            for (int x = 0; x < width(); ++x)
                codes[std::size_t(y) * width() + x] = padded[layout.index(x, y)];
        static const float colours[5][3] = {
            {0.0f, 1.0f, 0.0f},  // valid: green
            {1.0f, 0.0f, 0.0f},  // outside the screen: red
            {1.0f, 1.0f, 0.0f},  // other object: yellow
            {0.0f, 0.0f, 1.0f},  // background: blue
            {0.0f, 0.0f, 0.0f},  // no history: black
        };
        for (std::size_t i = 0; i < codes.size(); ++i)
            for (int c = 0; c < 3; ++c) image.pixels[3 * i + c] = colours[codes[i] % 5][c];
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

void Denoiser::processFrame(const Frame& frame, Image& output) { impl_->process(frame, output); }

void Denoiser::reset() { impl_->hasHistory = false; }
const DenoiserSettings& Denoiser::settings() const { return impl_->settings; }
const std::vector<PassInfo>& Denoiser::passes() const { return impl_->passInfos; }
const FrameStats& Denoiser::lastFrameStats() const { return impl_->stats; }
std::string Denoiser::deviceName() const { return impl_->device->name(); }
Image Denoiser::reprojectionDebugImage() const { return impl_->reprojectionDebugImage(); }

}  // namespace rtd
