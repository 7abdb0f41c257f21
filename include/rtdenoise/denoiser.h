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
    long long nonFiniteGeometry = 0;    // object pixels whose position or depth is NaN/Inf: read
                                        // as background
    long long backgroundPixels = 0;     // pixels passed through unfiltered: ID -1, an ID out of
                                        // range, or nonFiniteGeometry
    long long pixels = 0;  // the frame's (after synchronize(): the queued frames', as the counts)
};

// What looked broken in the frame these statistics are of, though it was denoised (empty where
// nothing did): most of the frame without usable geometry (a depth or position pass of NaN/Inf,
// every object ID -1, normals all zero), which leaves it as noisy as it came. A frame of sky alone
// reads so too: such a frame has nothing to denoise either.
std::string inputWarning(const FrameStats& stats);

// Debug images (Denoiser::debugImage).
enum class DebugView {
    Reprojection,  // why history was accepted or rejected: used green, outside the screen red,
                   // other object or depth/normal mismatch yellow, background blue, none black
    Variance,  // svgf: luminance standard deviation after the variance pass (grey, clipped at 1)
    HistoryLength,  // svgf: frames accumulated per pixel, grey = length / max history
    LearnedInputs,  // learned: the network's 29 inputs per pixel, for training
                    // (docs/learned.md): candidates L0..L5 (rgb + variance), history, albedo,
                    // foreground
};

// Where denoisers run, shared by several of them (as OIDN's device): on a GPU one CUDA stream
// (the caller's, or one of its own) and one set of pinned staging buffers for them all. Copies
// share the state; it lives as long as its last copy or denoiser.
class ComputeDevice {
  public:
    // Throws rtd::Error(DeviceFailure) if `type` is not available (Auto: a GPU, else the CPU).
    explicit ComputeDevice(DeviceType type = DeviceType::Auto);
    // A CUDA device queuing its work on the caller's `stream` (a cudaStream_t; nullptr: the
    // default stream), after the caller's own work there; frames in device memory are then
    // queued without a host wait.
    static ComputeDevice fromCudaStream(void* stream);

    DeviceType type() const;  // Cpu or Cuda
    std::string name() const;
    // Waits for all work queued on the device (its denoisers' and, on a caller's stream,
    // the caller's).
    void synchronize();

  private:
    friend class Denoiser;
    struct Impl;
    std::shared_ptr<Impl> impl_;
};

class Denoiser {
  public:
    explicit Denoiser(const DenoiserSettings& settings = {});
    // On a shared device (settings.device is not used).
    Denoiser(const DenoiserSettings& settings, const ComputeDevice& device);
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
    // On a ComputeDevice::fromCudaStream device with device-memory buffers
    // (MemorySpace::Device) it only queues the work on the caller's stream: the output is
    // complete after the caller's stream reaches it, the frame's statistics and ID check are
    // known after synchronize().
    void processFrame(const FrameView& frame, const OutputView& output);
    // Waits for this denoiser's queued frames; throws rtd::Error(InvalidInput) if one of them
    // held an object ID out of range (read as background: the history is then reset).
    void synchronize();

    // Forgets the history (e.g. at a camera cut).
    void reset();
    // Takes new settings (validated first: rtd::Error(InvalidArgument) leaves them as they were).
    // The history is kept, and the values take effect at the next frame, where the method's
    // passes and images stay the same (sigmas, alphas, tolerances, clamp widths); a change of
    // method, iteration count, radius, firefly removal on/off or albedo demodulation starts a
    // new history. settings.device is not read (the denoiser stays where it is). Returns whether
    // the history was kept.
    bool changeSettings(const DenoiserSettings& settings);

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
    Denoiser(const DenoiserSettings& settings, const DeviceTuning& tuning,
             const ComputeDevice* device = nullptr);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The GPU --device cuda would use ("" in a build without CUDA or on a machine without a GPU).
std::string gpuName();

}  // namespace rtd
