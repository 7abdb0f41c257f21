// The Denoiser: a driver of the method's pipeline (methods/), which declares the passes and the
// images. Here: the frame's buffers bound (or staged onto the device), the matrices, the images
// allocated when the frame size is first seen (or changes), never per frame or per pass.
#include "rtdenoise/denoiser.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>

#include "devices/device.h"
#include "methods/method.h"
#include "rtdenoise/error.h"
#include "tuning.h"

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

// A frame input as the device reads it: the caller's buffer itself where the device shares host
// memory, else a copy in `staging`.
struct InputBuffer {
    DeviceBuffer<float> staging;  // only for devices that cannot read host memory
    const void* device = nullptr;
};

struct Denoiser::Impl {
    DenoiserSettings settings;
    std::unique_ptr<Device> device;
    Pipeline pipeline;
    FrameImages images;
    FrameStats stats;
    bool hasHistory = false;

    DeviceBuffer<float> stageOutput;
    DeviceBuffer<ObjectReprojection> objects;
    std::vector<ObjectReprojection> hostObjects;
    // The previous frame's matrices (for back-projection).
    std::vector<Matrix4> previousObjectToWorld;
    Matrix4 previousWorldToScreen;
    // Per frame: the caller's buffers as the device sees them.
    InputBuffer inBeauty, inNormal, inPosition, inDepth, inId, inAlbedo;

    Impl(const DenoiserSettings& s, const DeviceTuning& tuning) : settings(s) {
        validate(settings);
        device = createDevice(settings.device, tuning.cpuIsa, tuning.tilePasses);
        images = declareMethod(pipeline, settings);
        stats.passMilliseconds.assign(pipeline.passes().size(), 0.0);
    }

    const Layout& layout() const { return pipeline.layout(); }
    std::size_t pixels() const { return std::size_t(layout().width) * layout().height; }

    void allocate(int w, int h) {
        pipeline.allocate(*device, w, h);
        if (!device->sharesHostMemory()) {
            std::size_t n = pixels();
            for (auto* in : {&inBeauty, &inNormal, &inPosition, &inAlbedo})
                in->staging = DeviceBuffer<float>(*device, 3 * n);
            inDepth.staging = DeviceBuffer<float>(*device, n);
            inId.staging = DeviceBuffer<float>(*device, n);  // holds int32 IDs: same size
            stageOutput = DeviceBuffer<float>(*device, 3 * n);
        }
        hasHistory = false;
    }

    // One matrix per object: current world -> object -> previous world (-> previous screen).
    void uploadObjectMatrices(const FrameView& f) {
        std::size_t count = std::size_t(f.objectCount);
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
        const bool frameHasAlbedo = f.albedo != nullptr && settings.albedo.demodulate;
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
        if (f.width != layout().width || f.height != layout().height) allocate(f.width, f.height);

        auto start = Clock::now();
        bindInputs(f);
        const bool temporal = pipeline.keepsHistory();
        if (temporal) uploadObjectMatrices(f);
        stats.uploadMilliseconds = millisecondsSince(start);

        bool direct = device->sharesHostMemory() || f.space == MemorySpace::Device;
        auto floats = [](const InputBuffer& b) { return static_cast<const float*>(b.device); };
        FrameBinding frame{floats(inBeauty),
                           floats(inNormal),
                           floats(inPosition),
                           floats(inDepth),
                           static_cast<const std::int32_t*>(inId.device),
                           floats(inAlbedo),
                           f.objectCount,
                           objects.data(),
                           hasHistory ? 1 : 0,
                           direct ? outputRgb : stageOutput.data()};
        // Each pass's time from device timestamps: one wait for the whole frame, not one per
        // pass (on a GPU a wait costs about as much as a small kernel).
        pipeline.run(*device, frame);
        device->synchronize();
        const std::size_t passes = pipeline.passes().size();
        for (std::size_t p = 0; p < passes; ++p)
            stats.passMilliseconds[p] = device->millisecondsBetween(int(p), int(p) + 1);
        stats.deviceMilliseconds = device->millisecondsBetween(0, int(passes));
        Device::InputFlagCounts flags =
            device->countInputFlags(pipeline.frameBytes(images.inputFlags), pixels());
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
        pipeline.endFrame();
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
};

Denoiser::Denoiser(const DenoiserSettings& settings) : Denoiser(settings, DeviceTuning{}) {}
Denoiser::Denoiser(const DenoiserSettings& settings, const DeviceTuning& tuning)
    : impl_(std::make_unique<Impl>(settings, tuning)) {}
Denoiser makeTunedDenoiser(const DenoiserSettings& settings, const DeviceTuning& tuning) {
    return Denoiser(settings, tuning);
}
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
    return impl_->pipeline.passes();
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
    return impl_->pipeline.debugImage(*impl_->device, view);
}

}  // namespace rtd
