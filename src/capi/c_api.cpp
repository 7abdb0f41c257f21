// The C API (include/rtdenoise/rtdenoise.h) over the C++ Denoiser: handles, settings by name,
// images by name, and the error boundary (no exception leaves an rtd* function).
#include <fmt/format.h>

#include <atomic>
#include <climits>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/checked_size.h"
#include "devices/device.h"
#include "rtdenoise/rtdenoise.h"
#include "rtdenoise/rtdenoise.hpp"

using rtd::DenoiserSettings;

// Named (not anonymous): the handle structs below hold its types.
namespace rtd::capi {

// ---- errors ----

RTDError toCode(rtd::ErrorCode code) {
    switch (code) {
        case rtd::ErrorCode::InvalidArgument:
            return RTD_ERROR_INVALID_ARGUMENT;
        case rtd::ErrorCode::InvalidInput:
            return RTD_ERROR_INVALID_INPUT;
        case rtd::ErrorCode::DeviceFailure:
            return RTD_ERROR_DEVICE_FAILURE;
        case rtd::ErrorCode::OutOfMemory:
            return RTD_ERROR_OUT_OF_MEMORY;
        default:
            return RTD_ERROR_UNKNOWN;
    }
}

// A failure inside a call, with the code the caller gets.
struct CallError {
    RTDError code;
    std::string message;
};

[[noreturn]] void fail(RTDError code, std::string message) {
    throw CallError{code, std::move(message)};
}

struct ErrorSlot {
    RTDError code = RTD_ERROR_NONE;
    std::string message;
    std::string readMessage;  // what rtdGetDeviceError handed out, valid until the next call
};

// Errors of calls without a usable device (a failed rtdNewDevice, a NULL handle).
thread_local ErrorSlot threadError;

}  // namespace rtd::capi

using namespace rtd::capi;

struct RTDDeviceImpl {
    std::atomic<int> references{1};
    std::optional<rtd::ComputeDevice> device;
    std::string name;
    std::mutex mutex;  // guards the error slot, the callback and the denoiser list
    ErrorSlot error;
    RTDErrorFunction errorFunction = nullptr;
    void* errorUserPtr = nullptr;
    std::vector<RTDDenoiserImpl*> denoisers;  // for rtdSynchronize (not owned)
};

namespace rtd::capi {

// Keeps the first error until it is read (as OIDN does); the callback hears every one.
void report(RTDDeviceImpl* device, RTDError code, const std::string& message) {
    if (!device) {
        if (threadError.code == RTD_ERROR_NONE) {
            threadError.code = code;
            threadError.message = message;
        }
        return;
    }
    RTDErrorFunction function = nullptr;
    void* user = nullptr;
    {
        std::lock_guard<std::mutex> lock(device->mutex);
        if (device->error.code == RTD_ERROR_NONE) {
            device->error.code = code;
            device->error.message = message;
        }
        function = device->errorFunction;
        user = device->errorUserPtr;
    }
    if (function) function(user, code, message.c_str());
}

// Runs `body`, turning every exception into an error code reported on `device` and returned.
template <class Body>
RTDError guarded(RTDDeviceImpl* device, const char* call, Body&& body) {
    try {
        body();
        return RTD_ERROR_NONE;
    } catch (const CallError& e) {
        report(device, e.code, fmt::format("{}: {}", call, e.message));
        return e.code;
    } catch (const rtd::Error& e) {
        RTDError code = toCode(e.code());
        if (e.code() == rtd::ErrorCode::DeviceFailure && device == nullptr)
            code = RTD_ERROR_UNSUPPORTED_DEVICE;
        report(device, code, fmt::format("{}: {}", call, e.what()));
        return code;
    } catch (const std::bad_alloc&) {
        report(device, RTD_ERROR_OUT_OF_MEMORY, fmt::format("{}: out of memory", call));
        return RTD_ERROR_OUT_OF_MEMORY;
    } catch (const std::exception& e) {
        report(device, RTD_ERROR_UNKNOWN, fmt::format("{}: {}", call, e.what()));
        return RTD_ERROR_UNKNOWN;
    } catch (...) {
        report(device, RTD_ERROR_UNKNOWN, fmt::format("{}: unknown failure", call));
        return RTD_ERROR_UNKNOWN;
    }
}

// ---- settings by name ----

enum class ValueKind { Float, Int, Bool, String };

const char* kindName(ValueKind kind) {
    switch (kind) {
        case ValueKind::Float:
            return "float";
        case ValueKind::Int:
            return "int";
        case ValueKind::Bool:
            return "bool";
        case ValueKind::String:
            return "string";
    }
    return "?";
}

// One setting: the command line's long option name and the field it sets.
struct SettingEntry {
    const char* name;
    ValueKind kind;
    void* (*field)(DenoiserSettings&);  // float*, int*, bool*; String entries: the enum
};

#define RTD_SETTING(NAME, KIND, PATH)                                               \
    {                                                                               \
        NAME, ValueKind::KIND, [](DenoiserSettings& s) -> void* { return &s.PATH; } \
    }

const SettingEntry kSettings[] = {
    RTD_SETTING("method", String, method),
    RTD_SETTING("spatial-filter", String, temporal.spatialFilter),
    RTD_SETTING("sigma-color", Float, edges.sigmaColor),
    RTD_SETTING("sigma-normal", Float, edges.sigmaNormal),
    RTD_SETTING("sigma-plane", Float, edges.sigmaPlane),
    RTD_SETTING("separate-objects", Bool, edges.separateObjects),
    RTD_SETTING("radius", Int, jbf.radius),
    RTD_SETTING("sigma-coord", Float, jbf.sigmaCoord),
    RTD_SETTING("atrous-passes", Int, atrous.passes),
    RTD_SETTING("alpha", Float, temporal.alpha),
    RTD_SETTING("clamp-k", Float, temporal.clampK),
    RTD_SETTING("clamp-radius", Int, temporal.clampRadius),
    RTD_SETTING("geometry-tests", Bool, history.geometryTests),
    RTD_SETTING("depth-tolerance", Float, history.depthTolerance),
    RTD_SETTING("normal-tolerance", Float, history.normalTolerance),
    RTD_SETTING("motion-scale-x", Float, motion.scaleX),
    RTD_SETTING("motion-scale-y", Float, motion.scaleY),
    RTD_SETTING("motion-current-minus-previous", Bool, motion.currentMinusPrevious),
    RTD_SETTING("svgf-alpha", Float, svgf.alpha),
    RTD_SETTING("svgf-moments-alpha", Float, svgf.momentsAlpha),
    RTD_SETTING("svgf-sigma-depth", Float, svgf.sigmaDepth),
    RTD_SETTING("svgf-sigma-normal", Float, svgf.sigmaNormal),
    RTD_SETTING("svgf-sigma-luminance", Float, svgf.sigmaLuminance),
    RTD_SETTING("svgf-iterations", Int, svgf.iterations),
    RTD_SETTING("svgf-feedback", Int, svgf.feedbackIteration),
    RTD_SETTING("svgf-max-history", Int, svgf.maxHistory),
    RTD_SETTING("svgf-clamp-k", Float, svgf.historyClampK),
    RTD_SETTING("detail-sigma-depth", Float, detail.sigmaDepth),
    RTD_SETTING("detail-sigma-normal", Float, detail.sigmaNormal),
    RTD_SETTING("detail-sigma-luminance", Float, detail.sigmaLuminance),
    RTD_SETTING("detail-iterations", Int, detail.iterations),
    RTD_SETTING("detail-specular-iterations", Int, detail.specularIterations),
    RTD_SETTING("detail-max-history", Int, detail.maxHistory),
    RTD_SETTING("detail-fast-history", Int, detail.fastHistory),
    RTD_SETTING("detail-clamp-sigma", Float, detail.clampSigma),
    RTD_SETTING("detail-moments-alpha", Float, detail.momentsAlpha),
    RTD_SETTING("detail-anti-lag", Bool, detail.antiLag),
    RTD_SETTING("albedo", Bool, albedo.demodulate),
    RTD_SETTING("albedo-epsilon", Float, albedo.epsilon),
    RTD_SETTING("outlier", Bool, outlier.enabled),
    RTD_SETTING("outlier-radius", Int, outlier.radius),
    RTD_SETTING("outlier-k", Float, outlier.k),
    RTD_SETTING("energy", Bool, energy.keep),
    RTD_SETTING("energy-cap", Float, energy.cap),
    RTD_SETTING("energy-frame-share", Float, energy.frameShare),
    RTD_SETTING("weights", String, learned.weights),
};
#undef RTD_SETTING

// "depth-kind" is the frame's (FrameView::depthKind), set once on the denoiser here.
constexpr std::string_view kDepthKind = "depth-kind";

std::string settingNames() {
    std::string names;
    for (const SettingEntry& e : kSettings)
        names += std::string(names.empty() ? "" : ", ") + e.name;
    return names + ", " + std::string(kDepthKind);
}

const SettingEntry& findSetting(const char* name) {
    if (!name) fail(RTD_ERROR_INVALID_ARGUMENT, "the setting name is NULL");
    for (const SettingEntry& e : kSettings)
        if (std::strcmp(e.name, name) == 0) return e;
    fail(RTD_ERROR_INVALID_ARGUMENT,
         fmt::format("unknown setting '{}' (settings: {})", name, settingNames()));
}

void requireKind(const SettingEntry& e, ValueKind given) {
    if (e.kind != given)
        fail(RTD_ERROR_INVALID_ARGUMENT, fmt::format("'{}' is a {} setting, not a {} one", e.name,
                                                     kindName(e.kind), kindName(given)));
}

template <class Enum>
Enum enumNamed(const char* setting, const char* value, std::initializer_list<Enum> values) {
    std::string allowed;
    for (Enum v : values) {
        if (value && std::strcmp(rtd::toString(v), value) == 0) return v;
        allowed += std::string(allowed.empty() ? "" : ", ") + rtd::toString(v);
    }
    fail(RTD_ERROR_INVALID_ARGUMENT,
         fmt::format("{}: '{}' is not one of {}", setting, value ? value : "NULL", allowed));
}

rtd::Method methodNamed(const char* name) {
    return enumNamed("method", name,
                     {rtd::Method::Jbf, rtd::Method::Atrous, rtd::Method::Temporal,
                      rtd::Method::Svgf, rtd::Method::Detail, rtd::Method::Learned});
}

// ---- images by name ----

enum ImageSlot {
    kColor,
    kNormal,
    kPosition,
    kDepth,
    kIds,
    kAlbedo,
    kMotion,
    kConfidence,
    kSpecular,
    kRoughness,
    kHitDistance,
    kOutput,
    kSlots
};
const char* const kImageNames[kSlots] = {"color",    "normal",    "position",     "depth",
                                         "ids",      "albedo",    "motion",       "confidence",
                                         "specular", "roughness", "hit_distance", "output"};

struct BoundImage {
    const void* data = nullptr;
    RTDFormat format = RTD_FORMAT_UNDEFINED;
    int width = 0;
    int height = 0;
    std::size_t pixelStride = 0;
    std::size_t rowStride = 0;
};

int channelsOf(RTDFormat f) {
    if (f >= RTD_FORMAT_FLOAT && f <= RTD_FORMAT_FLOAT4) return int(f - RTD_FORMAT_FLOAT) + 1;
    if (f >= RTD_FORMAT_HALF && f <= RTD_FORMAT_HALF4) return int(f - RTD_FORMAT_HALF) + 1;
    if (f == RTD_FORMAT_INT) return 1;
    return 0;
}
rtd::DataType typeOf(RTDFormat f) {
    return f == RTD_FORMAT_INT                               ? rtd::DataType::Int32
           : (f >= RTD_FORMAT_HALF && f <= RTD_FORMAT_HALF4) ? rtd::DataType::Float16
                                                             : rtd::DataType::Float32;
}
std::size_t valueBytes(RTDFormat f) {
    return typeOf(f) == rtd::DataType::Float16 ? 2 : 4;
}

// The formats each image takes: value counts, and whether int32 is one.
void checkFormat(ImageSlot slot, RTDFormat format) {
    const int channels = channelsOf(format);
    if (channels == 0)
        fail(RTD_ERROR_INVALID_ARGUMENT,
             fmt::format("{}: format {} is not an RTDFormat", kImageNames[slot], int(format)));
    int lowest = 3, highest = 4;
    const char* expected = "3 or 4 float or half values (RTD_FORMAT_FLOAT3/4, HALF3/4)";
    if (slot == kDepth || slot == kConfidence || slot == kRoughness || slot == kHitDistance) {
        lowest = highest = 1;
        expected = "1 float or half value (RTD_FORMAT_FLOAT, HALF)";
    } else if (slot == kIds) {
        lowest = highest = 1;
        expected = "1 int32 or float value (RTD_FORMAT_INT, FLOAT)";
    } else if (slot == kMotion) {
        lowest = 2;
        highest = 3;
        expected = "2 or 3 float or half values (RTD_FORMAT_FLOAT2/3, HALF2/3)";
    }
    const bool intOk = slot == kIds;
    if (channels < lowest || channels > highest || (format == RTD_FORMAT_INT && !intOk) ||
        (slot == kIds && typeOf(format) == rtd::DataType::Float16))
        fail(RTD_ERROR_INVALID_ARGUMENT, fmt::format("{}: format {} does not fit, expected {}",
                                                     kImageNames[slot], int(format), expected));
}

}  // namespace rtd::capi

struct RTDDenoiserImpl {
    std::atomic<int> references{1};
    RTDDeviceImpl* device = nullptr;  // retained
    DenoiserSettings settings;
    rtd::DepthKind depthKind = rtd::DepthKind::ViewZ;
    std::optional<rtd::Denoiser> denoiser;  // made at the first execute, again after a setting
    rtd::capi::BoundImage images[rtd::capi::kSlots];
    std::vector<rtd::Matrix4> objectToWorld;
    rtd::Matrix4 worldToCamera = rtd::Matrix4::identity();
    rtd::Matrix4 worldToScreen = rtd::Matrix4::identity();
    bool hasMatrices = false;
    int objectCount = 0;
    // Set while a call uses the denoiser: a second thread's call is refused, not run into it.
    std::atomic<bool> inUse{false};
    std::string frameWarning;  // rtdGetFrameWarning's, valid until the next call
};

namespace rtd::capi {

RTDDeviceImpl* deviceOf(RTDDenoiser denoiser) {
    return denoiser ? denoiser->device : nullptr;
}

void requireDenoiser(RTDDenoiser denoiser) {
    if (!denoiser) fail(RTD_ERROR_INVALID_ARGUMENT, "the denoiser is NULL");
}

// A call's hold on its denoiser: one thread at a time (as documented); a call from a second
// thread meanwhile fails with INVALID_OPERATION and leaves the first one's work untouched.
class ExclusiveUse {
  public:
    explicit ExclusiveUse(RTDDenoiser denoiser) : denoiser_(denoiser) {
        requireDenoiser(denoiser);
        if (denoiser->inUse.exchange(true, std::memory_order_acquire))
            fail(RTD_ERROR_INVALID_OPERATION,
                 "the denoiser is in use by another thread (a denoiser takes one call at a "
                 "time: use one per thread, or serialise the calls)");
    }
    ~ExclusiveUse() { denoiser_->inUse.store(false, std::memory_order_release); }
    ExclusiveUse(const ExclusiveUse&) = delete;
    ExclusiveUse& operator=(const ExclusiveUse&) = delete;

  private:
    RTDDenoiser denoiser_;
};

// Applies a change to a copy of the settings, keeps it if it validates. A denoiser already made
// takes it at its next frame, keeping its history unless the method's passes change (an engine
// that sets every parameter before every frame must still get temporal filtering).
template <class Change>
void changeSettings(RTDDenoiser d, Change&& change) {
    DenoiserSettings next = d->settings;
    change(next);
    rtd::validate(next);
    if (d->denoiser) d->denoiser->changeSettings(next);
    d->settings = next;
}

rtd::ImageView viewOf(const BoundImage& b) {
    if (!b.data) return {};
    return rtd::ImageView(b.data, typeOf(b.format), channelsOf(b.format), b.pixelStride,
                          b.rowStride);
}

rtd::Matrix4 matrixOf(const float* m) {
    rtd::Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m[i * 4 + j];
    return r;
}

bool reprojects(rtd::Method method) {
    return rtd::usesHistory(method);
}

void execute(RTDDenoiser d) {
    for (ImageSlot slot : {kColor, kNormal, kPosition, kDepth, kIds, kOutput})
        if (!d->images[slot].data)
            fail(RTD_ERROR_INVALID_OPERATION,
                 fmt::format("the image '{}' is not set (rtdSetImage)", kImageNames[slot]));
    const BoundImage& color = d->images[kColor];
    for (int slot = 0; slot < kSlots; ++slot) {
        const BoundImage& b = d->images[slot];
        if (b.data && (b.width != color.width || b.height != color.height))
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("the image '{}' is {}x{}, but 'color' is {}x{}", kImageNames[slot],
                             b.width, b.height, color.width, color.height));
    }
    const bool motion = d->images[kMotion].data != nullptr;
    if (reprojects(d->settings.method) && !motion && !d->hasMatrices)
        fail(RTD_ERROR_INVALID_OPERATION,
             fmt::format("method {} reprojects the previous frame: set the matrices "
                         "(rtdSetMatrices) or a 'motion' image",
                         rtd::toString(d->settings.method)));
    // On a GPU, the buffers are either all host memory or all the GPU's.
    rtd::MemorySpace space = rtd::MemorySpace::Host;
    if (d->device->device->type() == rtd::DeviceType::Cuda) {
        const bool onDevice = rtd::isCudaDeviceMemory(color.data);
        for (int slot = 0; slot < kSlots; ++slot)
            if (d->images[slot].data && rtd::isCudaDeviceMemory(d->images[slot].data) != onDevice)
                fail(RTD_ERROR_INVALID_ARGUMENT,
                     fmt::format("the image '{}' is in {} memory, 'color' in {}: give all "
                                 "images in the same memory",
                                 kImageNames[slot], onDevice ? "host" : "GPU",
                                 onDevice ? "GPU" : "host"));
        if (onDevice) space = rtd::MemorySpace::Device;
    }
    if (!d->denoiser) d->denoiser.emplace(d->settings, *d->device->device);

    rtd::FrameView view;
    view.width = color.width;
    view.height = color.height;
    view.space = space;
    view.beauty = viewOf(d->images[kColor]);
    view.normal = viewOf(d->images[kNormal]);
    view.position = viewOf(d->images[kPosition]);
    view.depth = viewOf(d->images[kDepth]);
    view.depthKind = d->depthKind;
    view.objectId = viewOf(d->images[kIds]);
    view.albedo = viewOf(d->images[kAlbedo]);
    view.motion = viewOf(d->images[kMotion]);
    view.confidence = viewOf(d->images[kConfidence]);
    view.specular = viewOf(d->images[kSpecular]);
    view.roughness = viewOf(d->images[kRoughness]);
    view.hitDistance = viewOf(d->images[kHitDistance]);
    view.objectCount = d->objectCount;
    // Without matrices (motion vectors, or a single-frame method) objectCount alone bounds the
    // IDs: no per-object matrix is built, whatever the count.
    view.objectToWorld =
        d->hasMatrices && !d->objectToWorld.empty() ? d->objectToWorld.data() : nullptr;
    if (!motion && d->hasMatrices) view.objectCount = int(d->objectToWorld.size());
    view.worldToCamera = d->worldToCamera;
    view.worldToScreen = d->worldToScreen;
    const BoundImage& out = d->images[kOutput];
    rtd::OutputView output{const_cast<void*>(out.data), typeOf(out.format), channelsOf(out.format),
                           out.pixelStride, out.rowStride};
    d->denoiser->processFrame(view, output);
}

}  // namespace rtd::capi

extern "C" {

int rtdGetVersion(void) {
    return RTD_VERSION;
}

// ---- devices ----

namespace {
RTDDevice newDevice(const char* call, bool callerStream, const RTDDeviceType& given, void* stream) {
    RTDDevice made = nullptr;
    // The caller's value may be outside the enum's (a C caller's int): read as one, not the enum.
    int type = 0;
    std::memcpy(&type, &given, sizeof type);
    guarded(nullptr, call, [&] {
        if (!callerStream && type != RTD_DEVICE_DEFAULT && type != RTD_DEVICE_CPU &&
            type != RTD_DEVICE_CUDA)
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("device type {} is not RTD_DEVICE_DEFAULT, CPU or CUDA", int(type)));
        auto device = std::make_unique<RTDDeviceImpl>();
        try {
            if (callerStream)
                device->device = rtd::ComputeDevice::fromCudaStream(stream);
            else
                device->device.emplace(type == RTD_DEVICE_CPU    ? rtd::DeviceType::Cpu
                                       : type == RTD_DEVICE_CUDA ? rtd::DeviceType::Cuda
                                                                 : rtd::DeviceType::Auto);
        } catch (const rtd::Error& e) {
            fail(e.code() == rtd::ErrorCode::DeviceFailure ? RTD_ERROR_UNSUPPORTED_DEVICE
                                                           : toCode(e.code()),
                 e.what());
        }
        device->name = device->device->name();
        made = device.release();
    });
    return made;
}
}  // namespace

RTDDevice rtdNewDevice(RTDDeviceType type) {
    return newDevice("rtdNewDevice", false, type, nullptr);
}

RTDDevice rtdNewCUDADevice(void* stream) {
    return newDevice("rtdNewCUDADevice", true, RTD_DEVICE_CUDA, stream);
}

void rtdRetainDevice(RTDDevice device) {
    if (device)
        device->references.fetch_add(1);
    else
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT, "rtdRetainDevice: the device is NULL");
}

void rtdReleaseDevice(RTDDevice device) {
    if (!device) {
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT, "rtdReleaseDevice: the device is NULL");
        return;
    }
    if (device->references.fetch_sub(1) == 1) delete device;
}

RTDError rtdGetDeviceError(RTDDevice device, const char** outMessage) {
    ErrorSlot* slot = &threadError;
    std::unique_lock<std::mutex> lock;
    if (device) {
        lock = std::unique_lock<std::mutex>(device->mutex);
        slot = &device->error;
    }
    const RTDError code = slot->code;
    slot->readMessage = code == RTD_ERROR_NONE ? std::string() : slot->message;
    slot->code = RTD_ERROR_NONE;
    slot->message.clear();
    if (outMessage) *outMessage = slot->readMessage.c_str();
    return code;
}

void rtdSetDeviceErrorFunction(RTDDevice device, RTDErrorFunction function, void* userPtr) {
    if (!device) {
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT,
               "rtdSetDeviceErrorFunction: the device is NULL");
        return;
    }
    std::lock_guard<std::mutex> lock(device->mutex);
    device->errorFunction = function;
    device->errorUserPtr = userPtr;
}

const char* rtdGetDeviceName(RTDDevice device) {
    if (!device) {
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT, "rtdGetDeviceName: the device is NULL");
        return "";
    }
    return device->name.c_str();
}

RTDError rtdSynchronize(RTDDevice device) {
    if (!device) {
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT, "rtdSynchronize: the device is NULL");
        return RTD_ERROR_INVALID_ARGUMENT;
    }
    return guarded(device, "rtdSynchronize", [&] {
        device->device->synchronize();
        std::vector<RTDDenoiserImpl*> denoisers;
        {
            std::lock_guard<std::mutex> lock(device->mutex);
            denoisers = device->denoisers;
        }
        for (RTDDenoiserImpl* d : denoisers)
            if (d->denoiser) d->denoiser->synchronize();
    });
}

// ---- denoisers ----

RTDDenoiser rtdNewDenoiser(RTDDevice device, const char* method) {
    RTDDenoiser made = nullptr;
    guarded(device, "rtdNewDenoiser", [&] {
        if (!device) fail(RTD_ERROR_INVALID_ARGUMENT, "the device is NULL");
        auto d = std::make_unique<RTDDenoiserImpl>();
        if (method && *method) d->settings.method = methodNamed(method);
        d->device = device;
        device->references.fetch_add(1);
        {
            std::lock_guard<std::mutex> lock(device->mutex);
            device->denoisers.push_back(d.get());
        }
        made = d.release();
    });
    return made;
}

void rtdRetainDenoiser(RTDDenoiser denoiser) {
    if (denoiser)
        denoiser->references.fetch_add(1);
    else
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT, "rtdRetainDenoiser: the denoiser is NULL");
}

void rtdReleaseDenoiser(RTDDenoiser denoiser) {
    if (!denoiser) {
        report(nullptr, RTD_ERROR_INVALID_ARGUMENT, "rtdReleaseDenoiser: the denoiser is NULL");
        return;
    }
    if (denoiser->references.fetch_sub(1) != 1) return;
    RTDDeviceImpl* device = denoiser->device;
    {
        std::lock_guard<std::mutex> lock(device->mutex);
        auto& list = device->denoisers;
        for (auto it = list.begin(); it != list.end(); ++it)
            if (*it == denoiser) {
                list.erase(it);
                break;
            }
    }
    delete denoiser;  // waits for its queued work (destructors do not throw)
    rtdReleaseDevice(device);
}

RTDError rtdSetFloat(RTDDenoiser d, const char* name, float value) {
    return guarded(deviceOf(d), "rtdSetFloat", [&] {
        const ExclusiveUse use(d);
        const SettingEntry& e = findSetting(name);
        requireKind(e, ValueKind::Float);
        if (!std::isfinite(value))
            fail(RTD_ERROR_INVALID_ARGUMENT, fmt::format("{}: {} is not finite", name, value));
        changeSettings(d, [&](DenoiserSettings& s) { *static_cast<float*>(e.field(s)) = value; });
    });
}

RTDError rtdSetInt(RTDDenoiser d, const char* name, int value) {
    return guarded(deviceOf(d), "rtdSetInt", [&] {
        const ExclusiveUse use(d);
        const SettingEntry& e = findSetting(name);
        if (e.kind == ValueKind::Float) {  // an int is a float value too
            changeSettings(
                d, [&](DenoiserSettings& s) { *static_cast<float*>(e.field(s)) = float(value); });
            return;
        }
        requireKind(e, ValueKind::Int);
        changeSettings(d, [&](DenoiserSettings& s) { *static_cast<int*>(e.field(s)) = value; });
    });
}

RTDError rtdSetBool(RTDDenoiser d, const char* name, bool value) {
    return guarded(deviceOf(d), "rtdSetBool", [&] {
        const ExclusiveUse use(d);
        const SettingEntry& e = findSetting(name);
        requireKind(e, ValueKind::Bool);
        changeSettings(d, [&](DenoiserSettings& s) { *static_cast<bool*>(e.field(s)) = value; });
    });
}

RTDError rtdSetString(RTDDenoiser d, const char* name, const char* value) {
    return guarded(deviceOf(d), "rtdSetString", [&] {
        const ExclusiveUse use(d);
        if (name && name == kDepthKind) {
            if (value && std::strcmp(value, "view-z") == 0)
                d->depthKind = rtd::DepthKind::ViewZ;
            else if (value && std::strcmp(value, "ray-distance") == 0)
                d->depthKind = rtd::DepthKind::RayDistance;
            else
                fail(RTD_ERROR_INVALID_ARGUMENT,
                     fmt::format("depth-kind: '{}' is not one of view-z, ray-distance",
                                 value ? value : "NULL"));
            return;
        }
        const SettingEntry& e = findSetting(name);
        requireKind(e, ValueKind::String);
        if (std::strcmp(e.name, "method") == 0) {
            const rtd::Method method = methodNamed(value);
            changeSettings(d, [&](DenoiserSettings& s) { s.method = method; });
        } else if (std::strcmp(e.name, "weights") == 0) {
            // NULL or "": the built-in weights. A bad file is refused here, naming the problem.
            const std::string path = value ? value : "";
            changeSettings(d, [&](DenoiserSettings& s) { s.learned.weights = path; });
        } else {
            const rtd::SpatialFilter filter = enumNamed(
                "spatial-filter", value, {rtd::SpatialFilter::Jbf, rtd::SpatialFilter::Atrous});
            changeSettings(d, [&](DenoiserSettings& s) { s.temporal.spatialFilter = filter; });
        }
    });
}

float rtdGetFloat(RTDDenoiser d, const char* name) {
    float value = 0.0f;
    guarded(deviceOf(d), "rtdGetFloat", [&] {
        const ExclusiveUse use(d);
        const SettingEntry& e = findSetting(name);
        if (e.kind == ValueKind::Int) {
            value = float(*static_cast<int*>(e.field(d->settings)));
            return;
        }
        requireKind(e, ValueKind::Float);
        value = *static_cast<float*>(e.field(d->settings));
    });
    return value;
}

int rtdGetInt(RTDDenoiser d, const char* name) {
    int value = 0;
    guarded(deviceOf(d), "rtdGetInt", [&] {
        const ExclusiveUse use(d);
        const SettingEntry& e = findSetting(name);
        requireKind(e, ValueKind::Int);
        value = *static_cast<int*>(e.field(d->settings));
    });
    return value;
}

bool rtdGetBool(RTDDenoiser d, const char* name) {
    bool value = false;
    guarded(deviceOf(d), "rtdGetBool", [&] {
        const ExclusiveUse use(d);
        const SettingEntry& e = findSetting(name);
        requireKind(e, ValueKind::Bool);
        value = *static_cast<bool*>(e.field(d->settings));
    });
    return value;
}

const char* rtdGetString(RTDDenoiser d, const char* name) {
    const char* value = nullptr;
    guarded(deviceOf(d), "rtdGetString", [&] {
        const ExclusiveUse use(d);
        if (name && name == kDepthKind) {
            value = d->depthKind == rtd::DepthKind::ViewZ ? "view-z" : "ray-distance";
            return;
        }
        const SettingEntry& e = findSetting(name);
        requireKind(e, ValueKind::String);
        value = std::strcmp(e.name, "method") == 0 ? rtd::toString(d->settings.method)
                : std::strcmp(e.name, "weights") == 0
                    ? d->settings.learned.weights.c_str()
                    : rtd::toString(d->settings.temporal.spatialFilter);
    });
    return value;
}

RTDError rtdSetImage(RTDDenoiser d, const char* name, const void* ptr, RTDFormat givenFormat,
                     size_t width, size_t height, size_t pixelStride, size_t rowStride) {
    return guarded(deviceOf(d), "rtdSetImage", [&] {
        int formatValue = 0;  // a C caller's int may be outside the enum (see newDevice)
        std::memcpy(&formatValue, &givenFormat, sizeof formatValue);
        if (ptr && (formatValue <= RTD_FORMAT_UNDEFINED || formatValue > RTD_FORMAT_INT))
            fail(RTD_ERROR_INVALID_ARGUMENT, fmt::format("{}: format {} is not an RTDFormat",
                                                         name ? name : "NULL", formatValue));
        const RTDFormat format = ptr ? RTDFormat(formatValue) : RTD_FORMAT_UNDEFINED;
        const ExclusiveUse use(d);
        if (!name) fail(RTD_ERROR_INVALID_ARGUMENT, "the image name is NULL");
        int slot = 0;
        while (slot < kSlots && std::strcmp(kImageNames[slot], name) != 0) ++slot;
        if (slot == kSlots)
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("unknown image '{}' (images: color, normal, position, depth, ids, "
                             "albedo, motion, confidence, specular, roughness, hit_distance, "
                             "output)",
                             name));
        if (!ptr) {  // unset
            d->images[slot] = BoundImage{};
            return;
        }
        checkFormat(ImageSlot(slot), format);
        if (width == 0 || height == 0 || width > INT_MAX || height > INT_MAX)
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("{}: size {}x{} is empty or too large", name, width, height));
        const std::size_t pixelBytes = std::size_t(channelsOf(format)) * valueBytes(format);
        const std::size_t pixel = pixelStride ? pixelStride : pixelBytes;
        const std::optional<std::size_t> packedRow = rtd::checkedProduct(width, pixel);
        const std::optional<std::size_t> span =
            packedRow ? rtd::imageSpanBytes(width, height, pixel,
                                            rowStride ? rowStride : *packedRow, pixelBytes)
                      : std::nullopt;
        if (!span || !rtd::fitsAddressSpace(ptr, *span))
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("{}: strides of {} bytes per pixel and {} per row over {}x{} pixels "
                             "reach past the end of memory",
                             name, pixelStride, rowStride, width, height));
        // Within the span just checked: no product below overflows.
        if (pixel < pixelBytes || (rowStride != 0 && rowStride < (width - 1) * pixel + pixelBytes))
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("{}: strides of {} bytes per pixel and {} per row are too small for "
                             "{} bytes per pixel in rows of {} pixels",
                             name, pixelStride, rowStride, pixelBytes, width));
        d->images[slot] = BoundImage{ptr, format, int(width), int(height), pixelStride, rowStride};
    });
}

RTDError rtdSetMatrices(RTDDenoiser d, const float* objectToWorld, int objectCount,
                        const float* worldToCamera, const float* worldToScreen) {
    return guarded(deviceOf(d), "rtdSetMatrices", [&] {
        const ExclusiveUse use(d);
        if (!objectToWorld && objectCount == 0 && !worldToCamera && !worldToScreen) {
            d->objectToWorld.clear();
            d->hasMatrices = false;
            return;
        }
        if (objectCount < 0 || (objectCount > 0 && !objectToWorld))
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("objectToWorld is NULL or objectCount {} is negative", objectCount));
        if (!worldToCamera || !worldToScreen)
            fail(RTD_ERROR_INVALID_ARGUMENT, "worldToCamera or worldToScreen is NULL");
        for (std::size_t i = 0; i < std::size_t(objectCount) * 16; ++i)
            if (!std::isfinite(objectToWorld[i]))
                fail(RTD_ERROR_INVALID_ARGUMENT,
                     fmt::format("objectToWorld[{}] is not finite", i / 16));
        for (int i = 0; i < 16; ++i)
            if (!std::isfinite(worldToCamera[i]) || !std::isfinite(worldToScreen[i]))
                fail(RTD_ERROR_INVALID_ARGUMENT, "worldToCamera or worldToScreen is not finite");
        d->objectToWorld.resize(std::size_t(objectCount));
        for (int k = 0; k < objectCount; ++k)
            d->objectToWorld[std::size_t(k)] = matrixOf(objectToWorld + 16 * k);
        d->worldToCamera = matrixOf(worldToCamera);
        d->worldToScreen = matrixOf(worldToScreen);
        d->objectCount = objectCount;
        d->hasMatrices = true;
    });
}

RTDError rtdSetObjectCount(RTDDenoiser d, int objectCount) {
    return guarded(deviceOf(d), "rtdSetObjectCount", [&] {
        const ExclusiveUse use(d);
        if (objectCount < 0)
            fail(RTD_ERROR_INVALID_ARGUMENT,
                 fmt::format("objectCount {} is negative", objectCount));
        d->objectCount = objectCount;
    });
}

RTDError rtdExecute(RTDDenoiser d) {
    return guarded(deviceOf(d), "rtdExecute", [&] {
        const ExclusiveUse use(d);
        execute(d);
    });
}

const char* rtdGetFrameWarning(RTDDenoiser d) {
    const char* warning = nullptr;
    guarded(deviceOf(d), "rtdGetFrameWarning", [&] {
        const ExclusiveUse use(d);
        d->frameWarning = d->denoiser ? rtd::inputWarning(d->denoiser->lastFrameStats()) : "";
        warning = d->frameWarning.c_str();
    });
    return warning;
}

RTDError rtdReset(RTDDenoiser d) {
    return guarded(deviceOf(d), "rtdReset", [&] {
        const ExclusiveUse use(d);
        if (d->denoiser) d->denoiser->reset();
    });
}

}  // extern "C"
