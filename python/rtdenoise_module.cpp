// rtdenoise._rtdenoise: the Python module's native part. The denoiser is reached through the C
// API (rtdenoise.h) alone, as any other language reaches it; the readers (io.h) and the metrics
// of `rtdenoise compare` (src/metrics) are bound directly. Argument checks, layouts and keyword
// names live in the pure-Python layer (python/rtdenoise/__init__.py).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "metrics/metrics.h"
#include "rtdenoise/error.h"
#include "rtdenoise/image.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.h"

namespace py = pybind11;

namespace {

// Error codes the readers and writers raise beyond the C API's (rtdenoise.ErrorCode mirrors them).
constexpr int kMissingFile = 100;
constexpr int kIoFailure = 101;
constexpr int kMissingTool = 102;

// Sets the Python error rtdenoise.Error (or its subclass for `code`) without throwing: what an
// exception translator must do. The classes are Python's (rtdenoise/_errors.py), so that they
// carry docstrings and an ErrorCode enum like the rest of the package.
void setPythonError(int code, const std::string& message) {
    py::object error = py::module_::import("rtdenoise._errors").attr("error_for")(code, message);
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
}

[[noreturn]] void raiseError(int code, const std::string& message) {
    setPythonError(code, message);
    throw py::error_already_set();
}

int pythonCodeOf(rtd::ErrorCode code) {
    switch (code) {
        case rtd::ErrorCode::InvalidArgument:
            return RTD_ERROR_INVALID_ARGUMENT;
        case rtd::ErrorCode::InvalidInput:
            return RTD_ERROR_INVALID_INPUT;
        case rtd::ErrorCode::DeviceFailure:
            return RTD_ERROR_DEVICE_FAILURE;
        case rtd::ErrorCode::OutOfMemory:
            return RTD_ERROR_OUT_OF_MEMORY;
        case rtd::ErrorCode::MissingFile:
            return kMissingFile;
        case rtd::ErrorCode::IoFailure:
            return kIoFailure;
        case rtd::ErrorCode::MissingTool:
            return kMissingTool;
    }
    return RTD_ERROR_UNKNOWN;
}

// ---- the denoiser, over the C API ----

// The double a float setting reads as: 0.6f gives 0.6, not 0.6000000238418579 (the float's
// shortest decimal form, parsed as a double).
double shortestDouble(float value) {
    char text[32];
    const auto [end, ec] = std::to_chars(text, text + sizeof text, value);
    if (ec != std::errc()) return double(value);
    return std::strtod(std::string(text, end).c_str(), nullptr);
}

// One RTDDevice and one RTDDenoiser, with the arrays bound to its images kept alive while bound
// (the C API reads the caller's buffers at rtdExecute, it does not copy them).
class CApiDenoiser {
  public:
    CApiDenoiser(const std::optional<std::string>& method, int deviceType) {
        device_ = rtdNewDevice(static_cast<RTDDeviceType>(deviceType));
        if (!device_) raiseLastError(nullptr, RTD_ERROR_UNKNOWN, "rtdNewDevice failed");
        denoiser_ = rtdNewDenoiser(device_, method ? method->c_str() : nullptr);
        if (!denoiser_) {
            // Read the message before the device (which holds it) goes.
            const char* message = nullptr;
            RTDError code = rtdGetDeviceError(device_, &message);
            std::string text = message ? message : "rtdNewDenoiser failed";
            rtdReleaseDevice(device_);
            device_ = nullptr;
            raiseError(code != RTD_ERROR_NONE ? code : RTD_ERROR_UNKNOWN, text);
        }
    }
    ~CApiDenoiser() {
        if (denoiser_) rtdReleaseDenoiser(denoiser_);
        if (device_) rtdReleaseDevice(device_);
    }
    CApiDenoiser(const CApiDenoiser&) = delete;
    CApiDenoiser& operator=(const CApiDenoiser&) = delete;

    void setFloat(const std::string& name, float value) {
        check(rtdSetFloat(denoiser_, name.c_str(), value));
    }
    void setInt(const std::string& name, int value) {
        check(rtdSetInt(denoiser_, name.c_str(), value));
    }
    void setBool(const std::string& name, bool value) {
        check(rtdSetBool(denoiser_, name.c_str(), value));
    }
    void setString(const std::string& name, const std::string& value) {
        check(rtdSetString(denoiser_, name.c_str(), value.c_str()));
    }

    // The C API has one getter per type and says "wrong type" (an error) for the others: a
    // setting's type is the first getter that succeeds. An unknown name fails all four; the
    // first getter's message is then the one raised.
    py::object get(const std::string& name) {
        std::string first;
        RTDError firstCode = RTD_ERROR_NONE;
        auto failed = [&]() {
            const char* message = nullptr;
            RTDError code = rtdGetDeviceError(device_, &message);
            if (code == RTD_ERROR_NONE) return false;
            if (firstCode == RTD_ERROR_NONE) {
                firstCode = code;
                first = message ? message : "";
            }
            return true;
        };
        bool asBool = rtdGetBool(denoiser_, name.c_str());
        if (!failed()) return py::bool_(asBool);
        int asInt = rtdGetInt(denoiser_, name.c_str());
        if (!failed()) return py::int_(asInt);
        float asFloat = rtdGetFloat(denoiser_, name.c_str());
        if (!failed()) return py::float_(shortestDouble(asFloat));
        const char* asString = rtdGetString(denoiser_, name.c_str());
        if (!failed()) return asString ? py::object(py::str(asString)) : py::object(py::none());
        // The message names the first getter tried ("rtdGetBool: unknown setting 'x' ..."), not
        // a call the Python caller made: that prefix is left out.
        const std::size_t prefixEnd = first.find(": ");
        if (prefixEnd != std::string::npos && first.rfind("rtdGet", 0) == 0)
            first = first.substr(prefixEnd + 2);
        raiseError(firstCode, first.empty() ? "unknown setting '" + name + "'" : first);
    }

    // Binds `array` (None: unbinds) to image `name` in the layout the Python layer worked out.
    void setImage(const std::string& name, const py::object& array, int format,
                  std::size_t pixelStride, std::size_t rowStride) {
        if (array.is_none()) {
            bound_.erase(name);
            check(rtdSetImage(denoiser_, name.c_str(), nullptr, static_cast<RTDFormat>(format), 0,
                              0, 0, 0));
            return;
        }
        auto buffer = py::reinterpret_borrow<py::array>(array);
        if (buffer.ndim() < 2)
            raiseError(RTD_ERROR_INVALID_ARGUMENT,
                       name + ": expected an (height, width[, channels]) array");
        const void* data = name == "output" ? buffer.mutable_data() : buffer.data();
        const auto height = static_cast<std::size_t>(buffer.shape(0));
        const auto width = static_cast<std::size_t>(buffer.shape(1));
        // Kept before the call: a failed call leaves the C API's binding unknown, and a binding
        // the C API may still hold must not outlive its array.
        bound_[name] = buffer;
        check(rtdSetImage(denoiser_, name.c_str(), data, static_cast<RTDFormat>(format), width,
                          height, pixelStride, rowStride));
    }

    void setMatrices(const py::array_t<float, py::array::c_style>& objectToWorld,
                     const py::array_t<float, py::array::c_style>& worldToCamera,
                     const py::array_t<float, py::array::c_style>& worldToScreen) {
        const auto count = static_cast<int>(objectToWorld.size() / 16);
        check(rtdSetMatrices(denoiser_, count > 0 ? objectToWorld.data() : nullptr, count,
                             worldToCamera.data(), worldToScreen.data()));
    }

    // Forgets the matrices an earlier frame set (rtdSetMatrices with none).
    void unsetMatrices() { check(rtdSetMatrices(denoiser_, nullptr, 0, nullptr, nullptr)); }

    void setObjectCount(int count) { check(rtdSetObjectCount(denoiser_, count)); }

    // The filters run without the GIL: other Python threads go on meanwhile (the bound arrays
    // are held by bound_, so they stay alive).
    void execute() {
        RTDError result = RTD_ERROR_NONE;
        {
            py::gil_scoped_release released;
            result = rtdExecute(denoiser_);
        }
        check(result);
    }

    void reset() { check(rtdReset(denoiser_)); }

    // What looked broken in the last frame's input ("" where nothing did).
    std::string frameWarning() {
        const char* warning = rtdGetFrameWarning(denoiser_);
        if (!warning) raiseLastError(device_, RTD_ERROR_UNKNOWN, "rtdGetFrameWarning failed");
        return warning;
    }

    std::string deviceName() const {
        const char* name = rtdGetDeviceName(device_);
        return name ? name : "";
    }

  private:
    void check(RTDError result) {
        if (result == RTD_ERROR_NONE) return;
        raiseLastError(device_, result, "the call failed");
    }

    [[noreturn]] static void raiseLastError(RTDDevice device, RTDError fallbackCode,
                                            const char* fallbackMessage) {
        const char* message = nullptr;
        RTDError code = rtdGetDeviceError(device, &message);
        if (code == RTD_ERROR_NONE) code = fallbackCode;
        raiseError(code, message && *message ? message : fallbackMessage);
    }

    RTDDevice device_ = nullptr;
    RTDDenoiser denoiser_ = nullptr;
    std::map<std::string, py::object> bound_;
};

// ---- images between numpy and rtd::Image ----

// Hands a vector's storage to numpy without a copy: the array owns it through a capsule.
template <class T>
py::array_t<T> arrayOwning(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
    auto* owned = new std::vector<T>(std::move(values));
    py::capsule owner(owned, [](void* pointer) { delete static_cast<std::vector<T>*>(pointer); });
    return py::array_t<T>(std::move(shape), owned->data(), owner);
}

// (height, width, channels), or (height, width) for a one-channel image when `squeeze`.
py::array_t<float> arrayOf(rtd::Image&& image, bool squeeze = false) {
    std::vector<py::ssize_t> shape{image.height, image.width};
    if (!(squeeze && image.channels == 1)) shape.push_back(image.channels);
    return arrayOwning(std::move(image.pixels), std::move(shape));
}

// A copy of an (height, width, channels) float32 C-contiguous array (the Python layer makes it so).
rtd::Image imageOf(const py::array_t<float, py::array::c_style | py::array::forcecast>& array,
                   const char* what) {
    if (array.ndim() != 3 || array.shape(2) < 1 || array.shape(2) > 4)
        raiseError(RTD_ERROR_INVALID_ARGUMENT,
                   std::string(what) + ": expected an (height, width, 1 to 4) array");
    rtd::Image image(static_cast<int>(array.shape(1)), static_cast<int>(array.shape(0)),
                     static_cast<int>(array.shape(2)));
    std::copy(array.data(), array.data() + array.size(), image.pixels.begin());
    return image;
}

py::array_t<float> matrixArray(const rtd::Matrix4& matrix) {
    std::vector<float> values;
    values.reserve(16);
    for (const auto& row : matrix.m) values.insert(values.end(), row.begin(), row.end());
    return arrayOwning(std::move(values), {4, 4});
}

// A frame as a dict of numpy arrays (rtdenoise.Frame is built from it in Python).
py::dict frameDict(rtd::Frame&& frame) {
    py::dict result;
    const int height = frame.height();
    const int width = frame.width();
    result["color"] = arrayOf(std::move(frame.beauty));
    result["normal"] = arrayOf(std::move(frame.normal));
    result["position"] = arrayOf(std::move(frame.position));
    result["depth"] = arrayOf(std::move(frame.depth), true);
    result["depth_kind"] =
        frame.depthKind == rtd::DepthKind::RayDistance ? "ray-distance" : "view-z";
    result["ids"] = arrayOwning(std::move(frame.objectId), {height, width});
    result["albedo"] = frame.albedo ? py::object(arrayOf(std::move(*frame.albedo))) : py::none();
    result["motion"] = frame.motion ? py::object(arrayOf(std::move(*frame.motion))) : py::none();
    result["confidence"] =
        frame.confidence ? py::object(arrayOf(std::move(*frame.confidence), true)) : py::none();
    result["specular"] =
        frame.specular ? py::object(arrayOf(std::move(*frame.specular))) : py::none();
    result["roughness"] =
        frame.roughness ? py::object(arrayOf(std::move(*frame.roughness), true)) : py::none();
    result["hit_distance"] =
        frame.hitDistance ? py::object(arrayOf(std::move(*frame.hitDistance), true)) : py::none();
    const auto objects = static_cast<py::ssize_t>(frame.objectToWorld.size());
    result["object_count"] = frame.objectCount > 0 ? frame.objectCount : int(objects);
    if (objects > 0) {
        std::vector<float> objectToWorld;
        objectToWorld.reserve(std::size_t(objects) * 16);
        for (const rtd::Matrix4& matrix : frame.objectToWorld)
            for (const auto& row : matrix.m)
                objectToWorld.insert(objectToWorld.end(), row.begin(), row.end());
        py::dict matrices;
        matrices["object_to_world"] = arrayOwning(std::move(objectToWorld), {objects, 4, 4});
        matrices["world_to_camera"] = matrixArray(frame.worldToCamera);
        matrices["world_to_screen"] = matrixArray(frame.worldToScreen);
        result["matrices"] = matrices;
    } else {
        result["matrices"] = py::none();
    }
    return result;
}

class FrameSourceHandle {
  public:
    FrameSourceHandle(const std::filesystem::path& path, const std::string& viewLayer) {
        rtd::FrameSourceOptions options;
        options.viewLayer = viewLayer;
        source_ = rtd::openFrameSource(path, options);
    }
    int frameCount() const { return source_->frameCount(); }
    py::dict readFrame(int index) const {
        if (index < 0 || index >= source_->frameCount())
            throw py::index_error("frame " + std::to_string(index) + " out of range 0.." +
                                  std::to_string(source_->frameCount() - 1));
        rtd::Frame frame;
        {
            py::gil_scoped_release released;
            frame = source_->readFrame(index);
        }
        return frameDict(std::move(frame));
    }
    std::string describe() const { return source_->describe(); }
    std::vector<std::string> warnings() const { return source_->warnings(); }
    std::string backProjectionProblem() const { return source_->backProjectionProblem(); }
    std::filesystem::path frameFile(int index) const { return source_->frameFile(index); }
    int firstFrameNumber() const { return source_->firstFrameNumber(); }
    // (warm-up, first, end) frame indices of the chunk of frame numbers first..end-1.
    std::tuple<int, int, int> chunk(int firstNumber, int endNumber, int warmup) const {
        const rtd::FrameChunk chunk = rtd::chunkOf(*source_, firstNumber, endNumber, warmup);
        return {chunk.warmupIndex, chunk.firstIndex, chunk.endIndex};
    }

  private:
    std::unique_ptr<rtd::FrameSource> source_;
};

// The channels read_exr reads by default: R, G, B; a one-channel file's channel; else the
// colour of a Blender multilayer file (its first view layer's Combined).
rtd::ChannelChoices defaultChannels(const std::filesystem::path& file) {
    const rtd::ExrContents contents = rtd::readExrContents(file);
    auto has = [&](const char* name) {
        for (const std::string& channel : contents.channels)
            if (channel == name) return true;
        return false;
    };
    if (has("R") && has("G") && has("B")) return {{"R"}, {"G"}, {"B"}};
    if (contents.channels.size() == 1) return {{contents.channels.front()}};
    return rtd::colourChannelsOf(file);
}

py::array_t<float> readExr(const std::filesystem::path& file,
                           const std::optional<std::vector<std::string>>& channels) {
    rtd::ChannelChoices choices;
    if (channels) {
        for (const std::string& name : *channels) choices.push_back({name});
    } else {
        choices = defaultChannels(file);
    }
    rtd::Image image;
    {
        py::gil_scoped_release released;
        image = rtd::readExr(file, choices);
    }
    return arrayOf(std::move(image));
}

void writeExr(const std::filesystem::path& file,
              const py::array_t<float, py::array::c_style | py::array::forcecast>& array, bool half,
              const std::optional<std::string>& compression) {
    rtd::Image image = imageOf(array, "write_exr");
    if (image.channels == 1 || image.channels == 3) {
        rtd::ExrWriteOptions options;
        options.half = half;
        if (compression) options.compression = rtd::exrCompressionNamed(*compression);
        py::gil_scoped_release released;
        rtd::writeExr(file, image, options);
        return;
    }
    if (compression && rtd::exrCompressionNamed(*compression) != rtd::ExrCompression::Zip)
        raiseError(RTD_ERROR_INVALID_ARGUMENT,
                   "write_exr: " + std::to_string(image.channels) +
                       "-channel images are written ZIP-compressed only (compression='" +
                       *compression + "')");
    const std::vector<std::string> names = image.channels == 2
                                               ? std::vector<std::string>{"X", "Y"}
                                               : std::vector<std::string>{"R", "G", "B", "A"};
    py::gil_scoped_release released;
    rtd::writeExrChannels(file, {{&image, names, half}});
}

// ---- metrics ----

py::dict metricsDict(const rtd::metrics::FrameMetrics& metrics) {
    py::dict result;
    result["mse"] = metrics.mse;
    result["relmse"] = metrics.relMse;
    result["psnr"] = metrics.psnr;
    result["ssim"] = metrics.ssim;
    result["temporal_error"] =
        metrics.temporalError ? py::object(py::float_(*metrics.temporalError)) : py::none();
    result["result_mean"] = metrics.resultMean;
    result["reference_mean"] = metrics.referenceMean;
    return result;
}

rtd::metrics::FrameMetrics metricsOf(const py::dict& values) {
    rtd::metrics::FrameMetrics metrics;
    metrics.mse = values["mse"].cast<double>();
    metrics.relMse = values["relmse"].cast<double>();
    metrics.psnr = values["psnr"].cast<double>();
    metrics.ssim = values["ssim"].cast<double>();
    if (!values["temporal_error"].is_none())
        metrics.temporalError = values["temporal_error"].cast<double>();
    metrics.resultMean = values["result_mean"].cast<double>();
    metrics.referenceMean = values["reference_mean"].cast<double>();
    return metrics;
}

void checkSameSize(const rtd::Image& result, const rtd::Image& reference) {
    if (result.width != reference.width || result.height != reference.height ||
        result.channels != 3 || reference.channels != 3)
        raiseError(RTD_ERROR_INVALID_ARGUMENT,
                   "result (" + std::to_string(result.height) + ", " +
                       std::to_string(result.width) + ", " + std::to_string(result.channels) +
                       ") and reference (" + std::to_string(reference.height) + ", " +
                       std::to_string(reference.width) + ", " + std::to_string(reference.channels) +
                       ") must both be (height, width, 3)");
}

class SequenceComparerHandle {
  public:
    explicit SequenceComparerHandle(float exposure) : comparer_(exposure) {}
    py::dict addFrame(
        const py::array_t<float, py::array::c_style | py::array::forcecast>& result,
        const py::array_t<float, py::array::c_style | py::array::forcecast>& reference) {
        rtd::Image resultImage = imageOf(result, "result");
        rtd::Image referenceImage = imageOf(reference, "reference");
        checkSameSize(resultImage, referenceImage);
        const rtd::metrics::FrameMetrics* metrics = nullptr;
        {
            py::gil_scoped_release released;
            metrics = &comparer_.addFrame(resultImage, referenceImage);
        }
        return metricsDict(*metrics);
    }

  private:
    rtd::metrics::SequenceComparer comparer_;
};

}  // namespace

PYBIND11_MODULE(_rtdenoise, module) {
    module.doc() = "rtdenoise's native part; use the rtdenoise package.";

    py::register_exception_translator([](std::exception_ptr pointer) {
        try {
            if (pointer) std::rethrow_exception(pointer);
        } catch (const rtd::Error& error) {
            setPythonError(pythonCodeOf(error.code()), error.what());
        }
    });

    module.def("version", &rtdGetVersion);
    module.attr("DEVICE_DEFAULT") = int(RTD_DEVICE_DEFAULT);
    module.attr("DEVICE_CPU") = int(RTD_DEVICE_CPU);
    module.attr("DEVICE_CUDA") = int(RTD_DEVICE_CUDA);
    module.attr("FORMAT_FLOAT") = int(RTD_FORMAT_FLOAT);
    module.attr("FORMAT_HALF") = int(RTD_FORMAT_HALF);
    module.attr("FORMAT_INT") = int(RTD_FORMAT_INT);
    // The clamp the library applies to radiance: the Python layer clamps float64 input to it
    // before the cast to float32 (which would make 1e300 Inf, and so 0).
    module.attr("MAX_RADIANCE") = rtd::kMaxRadiance;

    py::class_<CApiDenoiser>(module, "Denoiser")
        .def(py::init<const std::optional<std::string>&, int>(), py::arg("method"),
             py::arg("device"))
        .def("set_float", &CApiDenoiser::setFloat)
        .def("set_int", &CApiDenoiser::setInt)
        .def("set_bool", &CApiDenoiser::setBool)
        .def("set_string", &CApiDenoiser::setString)
        .def("get", &CApiDenoiser::get)
        .def("set_image", &CApiDenoiser::setImage, py::arg("name"), py::arg("array"),
             py::arg("format"), py::arg("pixel_stride"), py::arg("row_stride"))
        .def("set_matrices", &CApiDenoiser::setMatrices)
        .def("unset_matrices", &CApiDenoiser::unsetMatrices)
        .def("set_object_count", &CApiDenoiser::setObjectCount)
        .def("execute", &CApiDenoiser::execute)
        .def("reset", &CApiDenoiser::reset)
        .def("frame_warning", &CApiDenoiser::frameWarning)
        .def_property_readonly("device_name", &CApiDenoiser::deviceName);

    py::class_<FrameSourceHandle>(module, "FrameSource")
        .def(py::init<const std::filesystem::path&, const std::string&>())
        .def("__len__", &FrameSourceHandle::frameCount)
        .def("read_frame", &FrameSourceHandle::readFrame)
        .def("describe", &FrameSourceHandle::describe)
        .def("warnings", &FrameSourceHandle::warnings)
        .def("back_projection_problem", &FrameSourceHandle::backProjectionProblem)
        .def("frame_file", &FrameSourceHandle::frameFile)
        .def("first_frame_number", &FrameSourceHandle::firstFrameNumber)
        .def("chunk", &FrameSourceHandle::chunk);
    module.attr("DEFAULT_CHUNK_WARMUP") = rtd::kDefaultChunkWarmup;

    module.def("read_exr", &readExr, py::arg("path"), py::arg("channels") = py::none());
    module.def("write_exr", &writeExr, py::arg("path"), py::arg("array"), py::arg("half"),
               py::arg("compression") = py::none());

    module.def(
        "compare_frame",
        [](const py::array_t<float, py::array::c_style | py::array::forcecast>& result,
           const py::array_t<float, py::array::c_style | py::array::forcecast>& reference,
           float exposure) {
            rtd::Image resultImage = imageOf(result, "result");
            rtd::Image referenceImage = imageOf(reference, "reference");
            checkSameSize(resultImage, referenceImage);
            rtd::metrics::FrameMetrics metrics;
            {
                py::gil_scoped_release released;
                metrics = rtd::metrics::compareFrame(resultImage, referenceImage, exposure);
            }
            return metricsDict(metrics);
        },
        py::arg("result"), py::arg("reference"), py::arg("exposure"));
    module.def(
        "mean_of",
        [](const std::vector<py::dict>& frames) {
            std::vector<rtd::metrics::FrameMetrics> metrics;
            for (const py::dict& frame : frames) metrics.push_back(metricsOf(frame));
            return metricsDict(rtd::metrics::meanOf(metrics));
        },
        py::arg("frames"));
    py::class_<SequenceComparerHandle>(module, "SequenceComparer")
        .def(py::init<float>(), py::arg("exposure"))
        .def("add_frame", &SequenceComparerHandle::addFrame, py::arg("result"),
             py::arg("reference"));
}
