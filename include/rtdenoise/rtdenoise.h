/* rtdenoise's C API (C99; compiles as C and C++). The only layer with a stable ABI: opaque,
 * reference-counted handles, plain C types, error codes. The C++ API is <rtdenoise/rtdenoise.hpp>.
 *
 *   RTDDevice device = rtdNewDevice(RTD_DEVICE_DEFAULT);
 *   RTDDenoiser den = rtdNewDenoiser(device, "svgf");
 *   rtdSetFloat(den, "sigma-color", 0.6f);                  // the command line's option names
 *   rtdSetImage(den, "color", rgb, RTD_FORMAT_FLOAT3, w, h, 0, 0);   // 0 strides: packed
 *   ... "normal", "position", "depth", "ids", optional "albedo", "motion", "confidence",
 *   "specular", "roughness", "hit_distance"; "output"
 *   rtdSetMatrices(den, objectToWorld, objectCount, worldToCamera, worldToScreen);
 *   if (rtdExecute(den) != RTD_ERROR_NONE) { const char* m; rtdGetDeviceError(device, &m); }
 *   rtdReleaseDenoiser(den); rtdReleaseDevice(device);
 */
#ifndef RTDENOISE_RTDENOISE_H
#define RTDENOISE_RTDENOISE_H

#include <stdbool.h>
#include <stddef.h>

/* The library's version; the package's (find_package(rtdenoise 0.2)) is read from these lines. */
#define RTD_VERSION_MAJOR 0
#define RTD_VERSION_MINOR 2
#define RTD_VERSION_PATCH 0
#define RTD_VERSION (RTD_VERSION_MAJOR * 10000 + RTD_VERSION_MINOR * 100 + RTD_VERSION_PATCH)

#if defined(RTD_STATIC_DEFINE)
#define RTD_API
#elif defined(_WIN32)
#if defined(RTD_C_API_BUILD)
#define RTD_API __declspec(dllexport)
#else
#define RTD_API __declspec(dllimport)
#endif
#else
#define RTD_API __attribute__((visibility("default")))
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef struct RTDDeviceImpl* RTDDevice;     /* where denoisers run; shared by several */
typedef struct RTDDenoiserImpl* RTDDenoiser; /* one sequence's settings, images and history */

typedef enum {
    RTD_DEVICE_DEFAULT = 0, /* a CUDA GPU when there is one, else the CPU */
    RTD_DEVICE_CPU = 1,
    RTD_DEVICE_CUDA = 2
} RTDDeviceType;

typedef enum {
    RTD_ERROR_NONE = 0,
    RTD_ERROR_UNKNOWN = 1,
    RTD_ERROR_INVALID_ARGUMENT = 2,  /* a null pointer, unknown name, value out of range, size */
    RTD_ERROR_INVALID_OPERATION = 3, /* a call in the wrong order (execute without an image) */
    RTD_ERROR_INVALID_INPUT = 4,     /* a frame's content: object IDs outside -1..count-1 */
    RTD_ERROR_OUT_OF_MEMORY = 5,
    RTD_ERROR_UNSUPPORTED_DEVICE = 6, /* no CUDA back end in this build, or no GPU */
    RTD_ERROR_DEVICE_FAILURE = 7      /* the GPU reported an error */
} RTDError;

/* A pixel's values: their type and count. */
typedef enum {
    RTD_FORMAT_UNDEFINED = 0,
    RTD_FORMAT_FLOAT = 1, /* 32-bit float, 1 to 4 values */
    RTD_FORMAT_FLOAT2 = 2,
    RTD_FORMAT_FLOAT3 = 3,
    RTD_FORMAT_FLOAT4 = 4,
    RTD_FORMAT_HALF = 5, /* IEEE 754 16-bit float, 1 to 4 values */
    RTD_FORMAT_HALF2 = 6,
    RTD_FORMAT_HALF3 = 7,
    RTD_FORMAT_HALF4 = 8,
    RTD_FORMAT_INT = 9 /* one 32-bit signed integer (object IDs) */
} RTDFormat;

/* Called with every error (besides the stored code): userPtr as given, the code, a message that
 * names the call, the setting or image, and the problem. */
typedef void (*RTDErrorFunction)(void* userPtr, RTDError code, const char* message);

/* RTD_VERSION of the library loaded (may differ from the header's at a newer minor version). */
RTD_API int rtdGetVersion(void);

/* ---- devices ---- */

/* NULL on failure (rtdGetDeviceError(NULL, ...) says why). */
RTD_API RTDDevice rtdNewDevice(RTDDeviceType type);
/* A CUDA device that queues its work on the caller's stream (a cudaStream_t; NULL: the default
 * stream), after the caller's own: rtdExecute on device-memory images only enqueues, and
 * rtdSynchronize waits. NULL on failure. */
RTD_API RTDDevice rtdNewCUDADevice(void* stream);
RTD_API void rtdRetainDevice(RTDDevice device);
RTD_API void rtdReleaseDevice(RTDDevice device); /* freed with its last reference */

/* The first error not yet read, and clears it; *outMessage (if outMessage is not NULL) is valid
 * until the next call on this device. NULL device: this thread's last error from a call without
 * a usable device (rtdNewDevice failed, a NULL handle). */
RTD_API RTDError rtdGetDeviceError(RTDDevice device, const char** outMessage);
RTD_API void rtdSetDeviceErrorFunction(RTDDevice device, RTDErrorFunction function, void* userPtr);
/* "cpu (avx512)", "cuda (NVIDIA H100 80GB HBM3)"; valid while the device lives. */
RTD_API const char* rtdGetDeviceName(RTDDevice device);
/* Waits for the work queued by the device's denoisers; reports what the queued frames found
 * (an object ID out of range). */
RTD_API RTDError rtdSynchronize(RTDDevice device);

/* ---- denoisers ---- */

/* method: "jbf", "atrous", "temporal", "svgf", "detail", "learned" (NULL: the default, detail).
 * NULL on failure. */
RTD_API RTDDenoiser rtdNewDenoiser(RTDDevice device, const char* method);
RTD_API void rtdRetainDenoiser(RTDDenoiser denoiser);
RTD_API void rtdReleaseDenoiser(RTDDenoiser denoiser);

/* Settings by the command line's long option names, without "--" ("sigma-color",
 * "svgf-iterations", "outlier"; rtdenoise denoise --help lists them with their ranges), plus
 * "motion-scale-x", "motion-scale-y" (--motion-scale X,Y) and "depth-kind" ("view-z",
 * "ray-distance"), and "weights" (rtdSetString: the learned method's weights file, NULL or "" the
 * built-in; a missing, truncated or mismatched file is refused here, naming the problem). A value
 * out of range is refused here, naming it. After the first rtdExecute a
 * setting takes effect at the next frame; the history is kept (setting a value again, or a new
 * sigma, alpha or tolerance, is cheap) unless the change alters the method's passes: the method,
 * an iteration count, a radius, "outlier" or "albedo" start a new history. rtdSetInt also sets a
 * float setting. */
RTD_API RTDError rtdSetFloat(RTDDenoiser denoiser, const char* name, float value);
RTD_API RTDError rtdSetInt(RTDDenoiser denoiser, const char* name, int value);
RTD_API RTDError rtdSetBool(RTDDenoiser denoiser, const char* name, bool value);
RTD_API RTDError rtdSetString(RTDDenoiser denoiser, const char* name, const char* value);
/* 0, false or NULL (and an error) for an unknown name or the wrong type. rtdGetString's text is
 * valid until the denoiser's next setting change or release. */
RTD_API float rtdGetFloat(RTDDenoiser denoiser, const char* name);
RTD_API int rtdGetInt(RTDDenoiser denoiser, const char* name);
RTD_API bool rtdGetBool(RTDDenoiser denoiser, const char* name);
RTD_API const char* rtdGetString(RTDDenoiser denoiser, const char* name);

/* Binds the caller's buffer to an image name until it is set again (ptr NULL unsets it):
 *   "color"    noisy linear radiance, 3 or 4 values (a 4th ignored), float or half
 *   "normal"   world-space unit normal, (0,0,0) on background; "position" world-space position
 *   "depth"    1 value: view depth ("depth-kind" view-z) or ray distance ("ray-distance")
 *   "ids"      object IDs: RTD_FORMAT_INT or FLOAT (rounded), -1 on background
 *   "albedo"   optional, as color
 *   "motion"   optional, 2 or 3 values, pixels: previous = current + motion (NVIDIA NRD's
 *              convention; "motion-scale-x/y", "motion-current-minus-previous" convert others);
 *              with it no matrices are needed, rtdSetObjectCount bounds the IDs
 *   "confidence" optional, 1 float or half value in [0, 1]: how far each pixel's history still
 *              holds (NVIDIA NRD's IN_DIFF_CONFIDENCE; 0 where the lighting changed); values
 *              outside are clamped, NaN reads as 1. Read by the methods with history
 *   "specular" optional, as color: the part of color that left the first surface through its
 *              glossy lobe (the split signal, NVIDIA NRD's diffuse/specular inputs).
 *              Read by method "detail" only; needs "roughness"
 *   "roughness" with "specular", 1 float or half value in [0, 1] (sqrt of GGX alpha)
 *   "hit_distance" optional, with "specular": 1 float or half value, world units from the
 *              first surface to what its specular ray hit (0: unknown)
 *   "output"   the result, written: 3 or 4 values (alpha 1), float or half
 * Pixel (x, y) is at ptr + y * rowStride + x * pixelStride bytes, rows top to bottom; strides 0
 * mean packed. All images are width x height, in host memory, or all in the GPU's memory on a
 * CUDA device. */
RTD_API RTDError rtdSetImage(RTDDenoiser denoiser, const char* name, const void* ptr,
                             RTDFormat format, size_t width, size_t height, size_t pixelStride,
                             size_t rowStride);
/* This frame's matrices, row-major (m[row * 4 + col]) on column vectors: objectToWorld holds
 * objectCount of them (object k's local-to-world), worldToCamera and worldToScreen one each
 * ((s.x / s.w, s.y / s.w): the pixel, its centre at +0.5). Copied; kept until set again.
 * All NULL with objectCount 0 unsets them (then rtdSetObjectCount bounds the IDs again). */
RTD_API RTDError rtdSetMatrices(RTDDenoiser denoiser, const float* objectToWorld, int objectCount,
                                const float* worldToCamera, const float* worldToScreen);
/* With motion vectors and no matrices: IDs are -1..objectCount-1. */
RTD_API RTDError rtdSetObjectCount(RTDDenoiser denoiser, int objectCount);

/* Denoises one frame into "output" and keeps it as the next frame's history. It returns with the
 * output written, except on an rtdNewCUDADevice device with device-memory images: there it only
 * enqueues on the caller's stream (rtdSynchronize waits, and reports an object ID out of range in
 * the frames queued, which resets the history). A refused frame leaves the history as is. */
RTD_API RTDError rtdExecute(RTDDenoiser denoiser);
/* Forgets the history (a camera cut). */
RTD_API RTDError rtdReset(RTDDenoiser denoiser);
/* What looked broken in the last frame's input though rtdExecute succeeded, "" where nothing
 * did: most of the frame without usable geometry (a "depth" or "position" of NaN/Inf, every ID
 * -1, zero normals), which passes it through as noisy as it came. Valid until the next call on
 * the denoiser; NULL (and an error) for a NULL denoiser. On an rtdNewCUDADevice device with
 * device-memory images, known after rtdSynchronize. */
RTD_API const char* rtdGetFrameWarning(RTDDenoiser denoiser);

#ifdef __cplusplus
}
#endif

#endif /* RTDENOISE_RTDENOISE_H */
