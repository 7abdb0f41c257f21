// The Denoiser: a driver of the method's pipeline (methods/), which declares the passes and the
// images. Here: the frame's buffers bound (or staged onto the device), the matrices, the images
// allocated when the frame size is first seen (or changes), never per frame or per pass.
#include "rtdenoise/denoiser.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <optional>

#include "core/checked_size.h"
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
// only for a frame already known to hold one). fromFloats: the IDs were converted from floats,
// where kUnreadableId marks a value that is not an integer; given as int32, it is INT_MIN.
void checkObjectIds(const std::int32_t* ids, int w, int h, int objectCount, bool fromFloats) {
    std::size_t n = std::size_t(w) * h;
    for (std::size_t i = 0; i < n; ++i) {
        std::int32_t id = ids[i];
        if (fromFloats && id == ConvertInputKernel::kUnreadableId)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: the object ID at pixel ({}, {}) is not an integer",
                                    i % w, i / w));
        if (id < -1 || id >= objectCount)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: object ID {} at pixel ({}, {}) is outside -1..{}", id,
                                    i % w, i / w, objectCount - 1));
    }
}

// The split signal: roughness (and the optional hit distance) go with specular.
void checkSplitSignal(bool specular, bool roughness, bool hitDistance) {
    if (specular && !roughness)
        throw Error(ErrorCode::InvalidInput,
                    "frame: specular is given without roughness (the split signal needs both)");
    if (roughness && !specular)
        throw Error(ErrorCode::InvalidInput,
                    "frame: roughness is given without specular (it is read only with specular)");
    if (hitDistance && !specular)
        throw Error(ErrorCode::InvalidInput,
                    "frame: hitDistance is given without specular (it is read only with specular)");
}

void checkFrame(const Frame& f) {
    int w = f.width(), h = f.height();
    if (w <= 0 || h <= 0) throw Error(ErrorCode::InvalidInput, "frame: empty beauty image");
    checkImage(f.beauty, w, h, 3, "beauty");
    checkImage(f.normal, w, h, 3, "normal");
    checkImage(f.position, w, h, 3, "position");
    checkImage(f.depth, w, h, 1, "depth");
    if (f.albedo) checkImage(*f.albedo, w, h, 3, "albedo");
    if (f.motion && (f.motion->channels < 2 || f.motion->channels > 4))
        throw Error(
            ErrorCode::InvalidInput,
            fmt::format("frame: motion has {} channels, expected 2 to 4", f.motion->channels));
    if (f.motion) checkImage(*f.motion, w, h, f.motion->channels, "motion");
    if (f.confidence) checkImage(*f.confidence, w, h, 1, "confidence");
    if (f.specular) checkImage(*f.specular, w, h, 3, "specular");
    if (f.roughness) checkImage(*f.roughness, w, h, 1, "roughness");
    if (f.hitDistance) checkImage(*f.hitDistance, w, h, 1, "hitDistance");
    checkSplitSignal(bool(f.specular), bool(f.roughness), bool(f.hitDistance));
    if (f.objectId.size() != std::size_t(w) * h)
        throw Error(
            ErrorCode::InvalidInput,
            fmt::format("frame: objectId has {} values, expected {}x{}", f.objectId.size(), w, h));
    // Object IDs are checked on the device, by the ingest (see throwBadObjectId).
}

std::size_t valueBytes(DataType type) {
    return type == DataType::Float16 ? 2 : 4;
}

// One of a frame's images as the caller laid it out, checked, its defaults filled in.
struct InputLayout {
    const char* name = "";
    ImageView view;
    std::size_t spanBytes = 0;  // from the first value to the last one's end
    bool packed = false;        // packed float (IDs: int32) with the image's own channel count
};

InputLayout inputLayout(const char* name, const ImageView& v, int width, int height,
                        int ownChannels, int maxChannels, bool ids) {
    InputLayout l{name, v};
    ImageView& view = l.view;
    if (view.channels == 0) view.channels = ownChannels;
    const bool typeOk = view.type == DataType::Float32 || view.type == DataType::Float16 ||
                        (ids && view.type == DataType::Int32);
    if (!typeOk)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("frame: {}: int32 values are for object IDs only", name));
    if (view.channels < ownChannels || view.channels > maxChannels)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("frame: {} has {} channels, expected {} to {}", name, view.channels,
                                ownChannels, maxChannels));
    const std::size_t pixelBytes = std::size_t(view.channels) * valueBytes(view.type);
    if (view.pixelStride == 0) view.pixelStride = pixelBytes;
    const std::optional<std::size_t> packedRow =
        checkedProduct(std::size_t(width), view.pixelStride);
    if (view.rowStride == 0 && packedRow) view.rowStride = *packedRow;
    const std::optional<std::size_t> span =
        packedRow ? imageSpanBytes(std::size_t(width), std::size_t(height), view.pixelStride,
                                   view.rowStride, pixelBytes)
                  : std::nullopt;
    if (!span || !fitsAddressSpace(view.data, *span))
        throw Error(
            ErrorCode::InvalidArgument,
            fmt::format("frame: {}: strides of {} bytes per pixel and {} per row over {}x{} "
                        "pixels reach past the end of memory",
                        name, view.pixelStride, view.rowStride, width, height));
    // Within the span just checked: no product below overflows.
    if (view.pixelStride < pixelBytes ||
        view.rowStride < (width - 1) * view.pixelStride + pixelBytes)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("frame: {}: strides of {} bytes per pixel and {} per row are too "
                                "small for {} values of {} bytes in rows of {} pixels",
                                name, view.pixelStride, view.rowStride, view.channels,
                                valueBytes(view.type), width));
    l.spanBytes = *span;
    const std::size_t ownBytes = std::size_t(ownChannels) * 4;
    l.packed = view.type == (ids ? DataType::Int32 : DataType::Float32) &&
               view.channels == ownChannels && view.pixelStride == ownBytes &&
               view.rowStride == std::size_t(width) * ownBytes &&
               reinterpret_cast<std::uintptr_t>(view.data) % 4 == 0;
    return l;
}

// The camera's world-space position: worldToCamera's inverse applied to the origin.
Float3 cameraPosition(const Matrix4& worldToCamera) {
    Mat4 inverse;
    if (!invert(toMat4(worldToCamera), inverse)) return {};
    const float w = inverse.m[3][3] != 0.0f ? inverse.m[3][3] : 1.0f;
    return {inverse.m[0][3] / w, inverse.m[1][3] / w, inverse.m[2][3] / w};
}

InputSpan spanOf(const ImageView& v, const void* data) {
    return {static_cast<const unsigned char*>(data), int(v.type), v.channels,
            std::int64_t(v.pixelStride), std::int64_t(v.rowStride)};
}

}  // namespace

// A frame input as the ingest reads it (packed floats, or int32 IDs, in device memory): the
// caller's buffer itself where it is packed and the device reads its memory, else a copy of its
// bytes in `staging` and/or a packed conversion in `converted`. Both grow only.
struct InputBuffer {
    DeviceBuffer<unsigned char> staging;  // only for devices that cannot read host memory
    DeviceBuffer<float> converted;        // only for layouts other than packed float
    const void* device = nullptr;
    InputSpan span;  // the caller's layout, as the device reads it (staged or not)
};

struct ComputeDevice::Impl {
    std::shared_ptr<DeviceContext> context;
    std::string name;
};

ComputeDevice::ComputeDevice(DeviceType type) : impl_(std::make_shared<Impl>()) {
    impl_->context = createDeviceContext(type);
    impl_->name = createDevice(impl_->context)->name();
}

ComputeDevice ComputeDevice::fromCudaStream(void* stream) {
    ComputeDevice device(DeviceType::Cpu);
    device.impl_->context = createDeviceContext(DeviceType::Cuda, true, stream);
    device.impl_->name = createDevice(device.impl_->context)->name();
    return device;
}

DeviceType ComputeDevice::type() const {
    return impl_->context->type;
}
std::string ComputeDevice::name() const {
    return impl_->name;
}
void ComputeDevice::synchronize() {
    impl_->context->synchronize();
}

struct Denoiser::Impl {
    DenoiserSettings settings;
    std::shared_ptr<DeviceContext> context;  // shared with the ComputeDevice, if any
    std::unique_ptr<Device> device;
    int queuedFrames = 0;  // frames queued without a wait since the last synchronize()
    Pipeline pipeline;
    FrameImages images;
    FrameStats stats;
    bool hasHistory = false;

    DeviceBuffer<float> stageOutput;  // the result, where it is not written in place
    std::vector<float> hostOutput;    // the result on the host, for a strided or half host output
    DeviceBuffer<ObjectReprojection> objects;
    std::vector<ObjectReprojection> hostObjects;
    // The previous frame's matrices (for back-projection).
    std::vector<Matrix4> previousObjectToWorld;
    Matrix4 previousWorldToScreen;
    // Per frame: the caller's buffers as the device sees them.
    InputBuffer inBeauty, inNormal, inPosition, inDepth, inId, inAlbedo, inMotion, inConfidence;
    InputBuffer inSpecular, inRoughness, inHitDistance;
    // What the pipeline was declared for (detail declares its specular passes only for frames
    // with the split signal).
    MethodInputs declaredInputs;

    Impl(const DenoiserSettings& s, const DeviceTuning& tuning,
         std::shared_ptr<DeviceContext> sharedContext)
        : settings(s), context(std::move(sharedContext)) {
        validate(settings);
        if (!context) context = createDeviceContext(settings.device);
        device = createDevice(context, tuning.cpuIsa, tuning.tilePasses);
        images = declareMethod(pipeline, settings);
        stats.passMilliseconds.assign(pipeline.passes().size(), 0.0);
    }

    // Declares the method again for frames that give (or stop giving) what changes its passes;
    // the images are allocated at the next frame (a new history).
    void declareFor(const FrameView& f) {
        MethodInputs inputs;
        inputs.specular = settings.method == Method::Detail && bool(f.specular);
        if (inputs.specular == declaredInputs.specular) return;
        pipeline = Pipeline();
        images = declareMethod(pipeline, settings, inputs);
        declaredInputs = inputs;
        stats.passMilliseconds.assign(pipeline.passes().size(), 0.0);
    }

    // The passes declared anew for `next`; the images, and with them the history, kept where
    // the passes and their resources are the same (a sigma, an alpha: values the passes read).
    bool changeSettings(DenoiserSettings next) {
        validate(next);
        next.device = settings.device;  // the device is chosen once, at construction
        Pipeline nextPipeline;
        FrameImages nextImages = declareMethod(nextPipeline, next, declaredInputs);
        // Demodulation changes what the history holds (illumination or radiance).
        const bool sameHistoryMeaning = next.albedo.demodulate == settings.albedo.demodulate;
        const bool kept =
            sameHistoryMeaning && layout().width > 0 && nextPipeline.adoptImages(pipeline);
        // The old images are freed below: frames queued on a GPU stream may still use them.
        if (!kept) device->synchronize();
        settings = next;
        pipeline = std::move(nextPipeline);
        images = nextImages;
        stats.passMilliseconds.assign(pipeline.passes().size(), 0.0);
        // Otherwise the next frame allocates the images anew (its size differs from the empty
        // layout's), which starts a new history.
        return kept;
    }

    const Layout& layout() const { return pipeline.layout(); }
    std::size_t pixels() const { return std::size_t(layout().width) * layout().height; }

    void allocate(int w, int h) {
        pipeline.allocate(*device, w, h);
        for (auto* in : {&inBeauty, &inNormal, &inPosition, &inDepth, &inId, &inAlbedo, &inMotion,
                         &inConfidence, &inSpecular, &inRoughness, &inHitDistance})
            *in = InputBuffer{};
        stageOutput = DeviceBuffer<float>();  // made at the first frame that needs it
        hasHistory = false;
    }

    // Where the device reads `l` from: its bytes (staged where the device cannot read them),
    // then, unless packed (or keepLayout: the kernel reads the caller's layout itself), packed
    // floats or IDs. copy: packed floats in any case (the view depth is written over them).
    void bindInput(InputBuffer& in, const InputLayout& l, MemorySpace space, int ownChannels,
                   bool ids, bool keepLayout = false, bool copy = false) {
        const void* bytes = l.view.data;
        if (!device->sharesHostMemory() && space == MemorySpace::Host) {
            if (in.staging.size() < l.spanBytes)
                in.staging = DeviceBuffer<unsigned char>(*device, l.spanBytes);
            device->copyToDevice(in.staging.data(), bytes, l.spanBytes);
            bytes = in.staging.data();
        }
        in.span = spanOf(l.view, bytes);
        if (keepLayout || (l.packed && !copy)) {
            in.device = bytes;
            return;
        }
        if (in.converted.size() < ownChannels * pixels())
            in.converted = DeviceBuffer<float>(*device, ownChannels * pixels());
        ConvertStep convert;
        convert.input = {in.span, layout().width, ownChannels, in.converted.data(), ids ? 1 : 0};
        device->run(convert);
        in.device = in.converted.data();
    }

    void bindInputs(const FrameView& f) {
        const int w = f.width, h = f.height;
        const bool useAlbedo = f.albedo && settings.albedo.demodulate;
        // Only the methods that reproject read motion (declareIngest declares it for them).
        const bool reprojects = images.motion.index >= 0;
        const bool useMotion = f.motion && reprojects;
        InputLayout beauty = inputLayout("beauty", f.beauty, w, h, 3, 4, false);
        InputLayout normal = inputLayout("normal", f.normal, w, h, 3, 4, false);
        InputLayout position = inputLayout("position", f.position, w, h, 3, 4, false);
        InputLayout depth = inputLayout("depth", f.depth, w, h, 1, 4, false);
        InputLayout ids = inputLayout("objectId", f.objectId, w, h, 1, 4, true);
        // All checked before any is bound.
        std::optional<InputLayout> albedo, motion, confidence;
        if (useAlbedo) albedo = inputLayout("albedo", f.albedo, w, h, 3, 4, false);
        if (useMotion) motion = inputLayout("motion", f.motion, w, h, 2, 4, false);
        // History confidence weighs the history, so only methods with history read it.
        if (f.confidence && reprojects)
            confidence = inputLayout("confidence", f.confidence, w, h, 1, 4, false);
        // The split signal: only the detail method reads it.
        std::optional<InputLayout> specular, roughness, hitDistance;
        if (settings.method == Method::Detail) {
            if (f.specular) specular = inputLayout("specular", f.specular, w, h, 3, 4, false);
            if (f.roughness) roughness = inputLayout("roughness", f.roughness, w, h, 1, 4, false);
            if (f.hitDistance)
                hitDistance = inputLayout("hitDistance", f.hitDistance, w, h, 1, 4, false);
        }
        // With matrices, back-projection compares view depths: a ray distance is replaced.
        const bool viewDepth = f.depthKind == DepthKind::RayDistance && !useMotion && reprojects;
        bindInput(inBeauty, beauty, f.space, 3, false);
        bindInput(inNormal, normal, f.space, 3, false);
        bindInput(inPosition, position, f.space, 3, false);
        bindInput(inDepth, depth, f.space, 1, false, false, viewDepth);
        bindInput(inId, ids, f.space, 1, true);
        inAlbedo.device = nullptr;
        if (albedo) bindInput(inAlbedo, *albedo, f.space, 3, false);
        inMotion.span = {};
        if (motion) bindInput(inMotion, *motion, f.space, 2, false, true);
        inConfidence.span = {};
        if (confidence) bindInput(inConfidence, *confidence, f.space, 1, false, true);
        inSpecular.span = {};
        if (specular) bindInput(inSpecular, *specular, f.space, 3, false, true);
        inRoughness.span = {};
        if (roughness) bindInput(inRoughness, *roughness, f.space, 1, false, true);
        inHitDistance.span = {};
        if (hitDistance) bindInput(inHitDistance, *hitDistance, f.space, 1, false, true);
        if (viewDepth) {
            ConvertStep convert;
            convert.kind = ConvertStep::Kind::ViewDepth;
            const auto& row = f.worldToScreen.m[3];
            convert.viewDepth = {static_cast<const float*>(inPosition.device),
                                 w,
                                 {row[0], row[1], row[2], row[3]},
                                 static_cast<float*>(const_cast<void*>(inDepth.device))};
            device->run(convert);
        }
        // Host buffers: their upload is timed. Device buffers: nothing to wait for.
        if (f.space == MemorySpace::Host) device->synchronize();
    }

    // One matrix per object: current world -> object -> previous world (-> previous screen).
    // With motion vectors: one identity, which the kernels read for every object
    // (objectEntry; the previous position is the pixel's own, normals are compared unrotated).
    void uploadObjectMatrices(const FrameView& f) {
        const bool fromMotion = bool(f.motion);
        const std::size_t count = fromMotion ? 1 : std::size_t(f.objectCount);
        hostObjects.resize(count);
        for (std::size_t k = 0; k < count; ++k) {
            ObjectReprojection& o = hostObjects[k];
            o = ObjectReprojection{};
            if (fromMotion) {
                o.currentWorldToPreviousScreen = toMat4(Matrix4::identity());
                o.currentWorldToPreviousWorld = o.currentWorldToPreviousScreen;
                o.valid = hasHistory ? 1 : 0;
                continue;
            }
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

    void process(const Frame& f, Image& output) {
        checkFrame(f);
        if (output.width != f.width() || output.height != f.height() || output.channels != 3)
            output = Image(f.width(), f.height(), 3);
        process(viewOf(f), OutputView{output.pixels.data()});
    }

    void process(const FrameView& f, const OutputView& out) {
        checkView(f, out);
        declareFor(f);
        if (f.width != layout().width || f.height != layout().height) allocate(f.width, f.height);

        auto start = Clock::now();
        stats.pixels = (long long)pixels();
        bindInputs(f);
        // The single-frame methods keep the guide and IDs too, but read no matrices.
        const bool temporal = pipeline.keepsHistory();
        if (usesHistory(settings.method)) uploadObjectMatrices(f);
        stats.uploadMilliseconds = millisecondsSince(start);

        const bool direct = device->sharesHostMemory() || f.space == MemorySpace::Device;
        const std::size_t outPixelBytes = out.channels * valueBytes(out.type);
        const std::size_t outPixelStride = out.pixelStride ? out.pixelStride : outPixelBytes;
        const std::size_t outRowStride =
            out.rowStride ? out.rowStride : std::size_t(f.width) * outPixelStride;
        const bool packedRgb = out.type == DataType::Float32 && out.channels == 3 &&
                               outPixelStride == 12 && outRowStride == std::size_t(f.width) * 12 &&
                               reinterpret_cast<std::uintptr_t>(out.data) % 4 == 0;
        const bool inPlace = direct && packedRgb;
        if (!inPlace && stageOutput.size() < 3 * pixels())
            stageOutput = DeviceBuffer<float>(*device, 3 * pixels());
        auto floats = [](const InputBuffer& b) { return static_cast<const float*>(b.device); };
        FrameBinding frame{floats(inBeauty),
                           floats(inNormal),
                           floats(inPosition),
                           floats(inDepth),
                           static_cast<const std::int32_t*>(inId.device),
                           floats(inAlbedo),
                           inMotion.span,
                           inConfidence.span,
                           inSpecular.span,
                           inRoughness.span,
                           inHitDistance.span,
                           cameraPosition(f.worldToCamera),
                           f.objectCount,
                           objects.data(),
                           hasHistory ? 1 : 0,
                           inPlace ? static_cast<float*>(out.data) : stageOutput.data()};
        // Each pass's time from device timestamps: one wait for the whole frame, not one per
        // pass (on a GPU a wait costs about as much as a small kernel). A frame of device
        // buffers on a GPU is only queued: its times and flags are read at synchronize().
        pipeline.run(*device, frame);
        const bool queueOnly = f.space == MemorySpace::Device && device->queuesWork();
        if (queueOnly) {
            device->queueInputFlagCount(pipeline.frameBytes(images.inputFlags), pixels());
        } else {
            device->synchronize();
            readTimes();
            Device::InputFlagCounts flags =
                device->countInputFlags(pipeline.frameBytes(images.inputFlags), pixels());
            noteFlags(flags);
            // Bad IDs were read as background; the frame is refused (before it becomes
            // history), naming the first such pixel.
            if (flags.badObjectIds > 0) throwBadObjectId(f);
        }

        start = Clock::now();
        WriteOutputKernel write{stageOutput.data(),
                                f.width,
                                static_cast<unsigned char*>(out.data),
                                out.type == DataType::Float16 ? kSpanFloat16 : kSpanFloat32,
                                out.channels,
                                std::int64_t(outPixelStride),
                                std::int64_t(outRowStride)};
        if (direct && !packedRgb) {
            ConvertStep convert;
            convert.kind = ConvertStep::Kind::Output;
            convert.output = write;
            device->run(convert);
        } else if (!direct && packedRgb) {
            device->copyToHost(out.data, stageOutput.data(), 3 * pixels() * sizeof(float));
        } else if (!direct) {
            // Into host memory in another layout: converted here, after one packed download.
            hostOutput.resize(3 * pixels());
            device->copyToHost(hostOutput.data(), stageOutput.data(), 3 * pixels() * sizeof(float));
            device->synchronize();
            write.rgb = hostOutput.data();
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x) write(x, y);
        }
        if (queueOnly) {
            ++queuedFrames;
        } else {
            device->synchronize();
            stats.downloadMilliseconds = millisecondsSince(start);
        }

        // This frame's geometry and output are the next frame's history.
        if (f.motion || !temporal || !f.objectToWorld)
            previousObjectToWorld.clear();
        else
            previousObjectToWorld.assign(f.objectToWorld, f.objectToWorld + f.objectCount);
        previousWorldToScreen = f.worldToScreen;
        hasHistory = temporal;
        pipeline.endFrame();
    }

    void readTimes() {
        const std::size_t passes = pipeline.passes().size();
        for (std::size_t p = 0; p < passes; ++p)
            stats.passMilliseconds[p] = device->millisecondsBetween(int(p), int(p) + 1);
        stats.deviceMilliseconds = device->millisecondsBetween(0, int(passes));
    }

    void noteFlags(const Device::InputFlagCounts& flags) {
        stats.nonFiniteReplaced = flags.nonFinite;
        stats.radianceClamped = flags.clamped;
        stats.missingNormals = flags.missingNormals;
        stats.nonFiniteGeometry = flags.nonFiniteGeometry;
        stats.backgroundPixels = flags.background;
    }

    // The queued frames' statistics (the last one's times, all their flags summed).
    void synchronize() {
        device->synchronize();
        if (queuedFrames == 0) return;
        const int frames = queuedFrames;
        queuedFrames = 0;
        readTimes();
        stats.uploadMilliseconds = stats.downloadMilliseconds = 0.0;
        Device::InputFlagCounts flags = device->takeQueuedInputFlags();
        noteFlags(flags);
        stats.pixels = (long long)pixels() * frames;  // the flags are those frames' sums
        if (flags.badObjectIds > 0) {
            hasHistory = false;  // a frame with IDs read as background became history
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: {} pixels of the last {} queued frames held an object "
                                    "ID outside -1..objectCount-1 (read as background; the "
                                    "history is reset)",
                                    flags.badObjectIds, frames));
        }
    }

    void checkView(const FrameView& f, const OutputView& out) const {
        if (f.width <= 0 || f.height <= 0)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: size {}x{} is empty", f.width, f.height));
        const char* missing = !f.beauty     ? "beauty"
                              : !f.normal   ? "normal"
                              : !f.position ? "position"
                              : !f.depth    ? "depth"
                              : !f.objectId ? "objectId"
                                            : nullptr;
        if (missing)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("frame: the {} buffer is missing", missing));
        // The single-frame methods read no matrices: objectCount alone bounds their IDs.
        if (f.objectCount < 0 ||
            (f.objectCount > 0 && !f.motion && !f.objectToWorld && usesHistory(settings.method)))
            throw Error(ErrorCode::InvalidInput,
                        "frame: objectToWorld is missing (or give motion vectors)");
        checkSplitSignal(bool(f.specular), bool(f.roughness), bool(f.hitDistance));
        if (!out.data) throw Error(ErrorCode::InvalidInput, "frame: the output buffer is missing");
        const std::size_t outPixelBytes = out.channels * valueBytes(out.type);
        const std::size_t outPixel = out.pixelStride ? out.pixelStride : outPixelBytes;
        const std::optional<std::size_t> outRow = checkedProduct(std::size_t(f.width), outPixel);
        const std::optional<std::size_t> outSpan =
            outRow ? imageSpanBytes(std::size_t(f.width), std::size_t(f.height), outPixel,
                                    out.rowStride ? out.rowStride : *outRow, outPixelBytes)
                   : std::nullopt;
        if (!outSpan || !fitsAddressSpace(out.data, *outSpan))
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("frame: the output's strides of {} bytes per pixel and {} per "
                                    "row over {}x{} pixels reach past the end of memory",
                                    out.pixelStride, out.rowStride, f.width, f.height));
        if ((out.type != DataType::Float32 && out.type != DataType::Float16) ||
            (out.channels != 3 && out.channels != 4) ||
            (out.pixelStride != 0 && out.pixelStride < outPixelBytes) ||
            (out.rowStride != 0 && out.rowStride < (f.width - 1) * outPixel + outPixelBytes))
            throw Error(ErrorCode::InvalidInput,
                        "frame: the output must be float or half, 3 or 4 channels, with strides "
                        "that hold them");
        if (f.space == MemorySpace::Device && device->sharesHostMemory())
            throw Error(ErrorCode::InvalidArgument,
                        "frame: device memory needs a Denoiser on a GPU device (" + device->name() +
                            " reads host memory)");
    }

    [[noreturn]] void throwBadObjectId(const FrameView& f) {
        std::vector<std::int32_t> ids(pixels());
        device->copyToHost(ids.data(), inId.device, ids.size() * sizeof(std::int32_t));
        checkObjectIds(ids.data(), f.width, f.height, f.objectCount,
                       f.objectId.type != DataType::Int32);
        throw Error(ErrorCode::InvalidInput, "frame: an object ID is outside -1..objectCount-1");
    }
};

Denoiser::Denoiser(const DenoiserSettings& settings) : Denoiser(settings, DeviceTuning{}) {}
Denoiser::Denoiser(const DenoiserSettings& settings, const ComputeDevice& device)
    : Denoiser(settings, DeviceTuning{}, &device) {}
Denoiser::Denoiser(const DenoiserSettings& settings, const DeviceTuning& tuning,
                   const ComputeDevice* device)
    : impl_(std::make_unique<Impl>(settings, tuning, device ? device->impl_->context : nullptr)) {}
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
    impl_->process(frame, OutputView{outputRgb});
}

void Denoiser::processFrame(const FrameView& frame, const OutputView& output) {
    impl_->process(frame, output);
}

void Denoiser::synchronize() {
    impl_->synchronize();
}

void Denoiser::reset() {
    impl_->hasHistory = false;
}
bool Denoiser::changeSettings(const DenoiserSettings& settings) {
    return impl_->changeSettings(settings);
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

std::string inputWarning(const FrameStats& s) {
    if (s.pixels <= 0) return {};
    // A broken pass leaves most of a frame so; a real frame has a few such pixels at most.
    constexpr double kMostOfTheFrame = 0.5;
    // Every pixel (but a few) of ID -1: a broken ID pass, or a frame of sky alone.
    constexpr double kAllOfTheFrame = 0.99;
    const double pixels = double(s.pixels);
    const auto percent = [&](long long count) { return 100.0 * double(count) / pixels; };
    if (double(s.nonFiniteGeometry) > kMostOfTheFrame * pixels)
        return fmt::format(
            "{:.0f} % of the pixels have a NaN or Inf depth or position: read as "
            "background, they pass through undenoised",
            percent(s.nonFiniteGeometry));
    if (double(s.missingNormals) > kMostOfTheFrame * pixels)
        return fmt::format(
            "{:.0f} % of the pixels have a zero or non-finite normal: filtered "
            "without their normal terms",
            percent(s.missingNormals));
    if (double(s.backgroundPixels) >= kAllOfTheFrame * pixels)
        return fmt::format(
            "{:.0f} % of the pixels are background (object ID -1 or out of range): "
            "they pass through undenoised",
            percent(s.backgroundPixels));
    return {};
}

}  // namespace rtd
