// The denoiser: a method (a list of named passes) run on a device, keeping its history there
// across frames.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rtdenoise/image.h"
#include "rtdenoise/settings.h"

namespace rtd {

struct DeviceTuning;  // comparisons and tests only (not installed: src/tuning.h)

// One pass of a method's pipeline, with the buffers it reads and writes (for reading the
// pipeline and timing it).
struct PassInfo {
    std::string name;
    std::vector<std::string> inputs;
    std::vector<std::string> outputs;
};

struct FrameStats {
    std::vector<double> passMilliseconds;  // one per pass, same order as passes()
    // The whole pipeline on the device, from the first pass's start to the last one's end: what
    // the denoiser adds to a frame whose work is queued on the GPU (no host waits or launches).
    double deviceMilliseconds = 0.0;
    double uploadMilliseconds = 0.0;    // host -> device (including format conversion)
    double downloadMilliseconds = 0.0;  // device -> host
    long long nonFiniteReplaced = 0;    // NaN/Inf values in the beauty set to 0
    long long radianceClamped = 0;      // beauty values beyond +-kMaxRadiance clamped to it
    long long missingNormals = 0;       // object pixels with a zero or non-finite normal: their
                                        // normal terms neutral (filtered by colour and position)
};

// Debug images (Denoiser::debugImage).
enum class DebugView {
    Reprojection,  // why history was accepted or rejected: used green, outside the screen red,
                   // other object or depth/normal mismatch yellow, background blue, none black
    Variance,  // svgf: luminance standard deviation after the variance pass (grey, clipped at 1)
    HistoryLength,  // svgf: frames accumulated per pixel, grey = length / max history
};

class Denoiser {
  public:
    explicit Denoiser(const DenoiserSettings& settings = {});
    ~Denoiser();
    Denoiser(Denoiser&&) noexcept;
    Denoiser& operator=(Denoiser&&) noexcept;

    // Denoises one frame; temporal methods use (and update) the history of the previous call.
    // Throws rtd::Error if the frame is inconsistent (sizes, IDs, matrices).
    Image processFrame(const Frame& frame);
    // Same, writing into `output` (reused across frames: no allocation once sized).
    void processFrame(const Frame& frame, Image& output);
    // The same from buffers the caller owns, host or (on a GPU device) device memory;
    // `outputRgb` (width * height interleaved RGB floats) is in the same memory space. Sizes
    // are the caller's to get right; IDs are checked in either space (the ingest flags them).
    void processFrame(const FrameView& frame, float* outputRgb);
    // Same, the result in the caller's layout (float or half, 3 or 4 channels, strides).
    void processFrame(const FrameView& frame, const OutputView& output);

    // Forgets the history (e.g. at a camera cut).
    void reset();

    const DenoiserSettings& settings() const;
    const std::vector<PassInfo>& passes() const;
    const FrameStats& lastFrameStats() const;
    std::string deviceName() const;
    // Device memory this denoiser holds for the current frame size: history, G-buffer copies,
    // intermediate images, staging (0 before the first frame).
    std::size_t deviceMemoryBytes() const;

    // A debug view of the last frame (black where the method has no such data).
    Image debugImage(DebugView view) const;
    Image reprojectionDebugImage() const { return debugImage(DebugView::Reprojection); }

  private:
    friend Denoiser makeTunedDenoiser(const DenoiserSettings&, const DeviceTuning&);
    Denoiser(const DenoiserSettings& settings, const DeviceTuning& tuning);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The GPU --device cuda would use ("" in a build without CUDA or on a machine without a GPU).
std::string gpuName();

}  // namespace rtd
