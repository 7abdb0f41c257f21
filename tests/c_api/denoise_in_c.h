/* The C side of test_c_api: a C99 translation unit (c_api_denoise.c) that denoises frames
 * through the C API alone, called from the C++ test with a rendered scene's buffers. */
#ifndef RTDENOISE_TESTS_DENOISE_IN_C_H
#define RTDENOISE_TESTS_DENOISE_IN_C_H

#ifdef __cplusplus
extern "C" {
#endif

/* One frame's packed buffers (float RGB, float depth, int32 IDs) and row-major matrices. */
typedef struct {
    int width, height;
    const float *color, *normal, *position, *depth, *albedo; /* albedo may be NULL */
    const int* ids;
    int objectCount;
    const float* objectToWorld; /* objectCount * 16 */
    const float* worldToCamera; /* 16 */
    const float* worldToScreen; /* 16 */
} CFrame;

/* Denoises `count` frames in order with `method` on the CPU, frame i's result into outputs[i]
 * (width * height * 3 floats). Returns 0, or the first RTDError with its message in `message`
 * (at most `messageSize` bytes). */
int denoiseInC(const char* method, const CFrame* frames, int count, float** outputs, char* message,
               int messageSize);

/* Whether this file was compiled as C (not C++): __cplusplus undefined there. */
int compiledAsC(void);

#ifdef __cplusplus
}
#endif

#endif
