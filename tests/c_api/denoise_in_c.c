/* Built as C99 (tests/CMakeLists.txt sets LANGUAGE C): the C API must be usable from C. */
#include "denoise_in_c.h"

#include <rtdenoise/rtdenoise.h>
#include <stdio.h>
#include <string.h>

static int failed(RTDDevice device, char* message, int messageSize) {
    const char* text = "";
    RTDError code = rtdGetDeviceError(device, &text);
    snprintf(message, (size_t)messageSize, "%s", text);
    return code == RTD_ERROR_NONE ? RTD_ERROR_UNKNOWN : (int)code;
}

int denoiseInC(const char* method, const CFrame* frames, int count, float** outputs, char* message,
               int messageSize) {
    RTDDevice device = rtdNewDevice(RTD_DEVICE_CPU);
    if (!device) return failed(NULL, message, messageSize);
    RTDDenoiser denoiser = rtdNewDenoiser(device, method);
    int result = 0;
    if (!denoiser) {
        result = failed(device, message, messageSize);
        rtdReleaseDevice(device);
        return result;
    }
    for (int i = 0; i < count && result == 0; ++i) {
        const CFrame* f = &frames[i];
        size_t w = (size_t)f->width, h = (size_t)f->height;
        RTDError e = RTD_ERROR_NONE;
        e |= rtdSetImage(denoiser, "color", f->color, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        e |= rtdSetImage(denoiser, "normal", f->normal, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        e |= rtdSetImage(denoiser, "position", f->position, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        e |= rtdSetImage(denoiser, "depth", f->depth, RTD_FORMAT_FLOAT, w, h, 0, 0);
        e |= rtdSetImage(denoiser, "ids", f->ids, RTD_FORMAT_INT, w, h, 0, 0);
        e |= rtdSetImage(denoiser, "albedo", f->albedo, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        e |= rtdSetImage(denoiser, "output", outputs[i], RTD_FORMAT_FLOAT3, w, h, 0, 0);
        e |= rtdSetMatrices(denoiser, f->objectToWorld, f->objectCount, f->worldToCamera,
                            f->worldToScreen);
        if (e != RTD_ERROR_NONE || rtdExecute(denoiser) != RTD_ERROR_NONE)
            result = failed(device, message, messageSize);
    }
    rtdReleaseDenoiser(denoiser);
    rtdReleaseDevice(device);
    return result;
}

int compiledAsC(void) {
#ifdef __cplusplus
    return 0;
#else
    return 1;
#endif
}
