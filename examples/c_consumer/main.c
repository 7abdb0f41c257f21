/* The C API: DIR/frame_<i>.raw (README, "From C") denoised into DIR/c_result_<i>.raw (RGB). */
#include <rtdenoise/rtdenoise.h>
#include <stdio.h>
#include <stdlib.h>
int main(int argc, char** argv) {
    if (argc != 3) return fprintf(stderr, "usage: c_consumer DIR FRAMES\n"), 2;
    RTDDevice device = rtdNewDevice(RTD_DEVICE_CPU);
    RTDDenoiser denoiser = rtdNewDenoiser(device, "detail");
    const char* message = "";
    for (int i = 0; i < atoi(argv[2]); ++i) {
        char path[4096];
        int size[3] = {0, 0, 0}; /* width, height, K */
        snprintf(path, sizeof path, "%s/frame_%d.raw", argv[1], i);
        FILE* file = fopen(path, "rb");
        if (!file || fread(size, 4, 3, file) != 3)
            return fprintf(stderr, "%s: unreadable\n", path), 1;
        size_t w = (size_t)size[0], h = (size_t)size[1], n = w * h, k = (size_t)size[2];
        size_t count = 11 * n + 16 * (k + 2); /* the int32 IDs take a float's 4 bytes */
        float *in = malloc(count * 4), *out = malloc(n * 12), *m = in + 11 * n;
        if (fread(in, 4, count, file) != count) return fprintf(stderr, "%s: short\n", path), 1;
        fclose(file);
        rtdSetImage(denoiser, "color", in, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(denoiser, "normal", in + 3 * n, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(denoiser, "position", in + 6 * n, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(denoiser, "depth", in + 9 * n, RTD_FORMAT_FLOAT, w, h, 0, 0);
        rtdSetImage(denoiser, "ids", in + 10 * n, RTD_FORMAT_INT, w, h, 0, 0);
        rtdSetImage(denoiser, "output", out, RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetMatrices(denoiser, m, (int)k, m + 16 * k, m + 16 * k + 16);
        if (rtdExecute(denoiser) != RTD_ERROR_NONE && rtdGetDeviceError(device, &message))
            return fprintf(stderr, "frame %d: %s\n", i, message), 1;
        snprintf(path, sizeof path, "%s/c_result_%d.raw", argv[1], i);
        if (!(file = fopen(path, "wb")) || fwrite(out, 12, n, file) != n || fclose(file))
            return fprintf(stderr, "%s: cannot write\n", path), 1;
        free(in), free(out);
    }
    printf("c consumer ok, %s, version %d\n", rtdGetDeviceName(device), rtdGetVersion());
    rtdReleaseDenoiser(denoiser), rtdReleaseDevice(device);
    return 0;
}
