// Quality metrics of a denoised sequence against its reference, and contact sheets for looking
// at the difference. Separate from the denoiser library: the renderer's build never needs them.
//
// Which space each metric lives in:
//   - MSE, relMSE and the energy ratio on the linear RGB radiance (what the denoiser estimates);
//   - PSNR, SSIM and the temporal error on the display images, toneMap(x, exposure): values in
//     [0,1], the space a viewer judges (and the one SSIM's constants are defined for).
// "Display" arguments below are such tone-mapped 3-channel images.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "rtdenoise/image.h"

namespace rtd::metrics {

// SSIM constants (Wang et al. 2004) for data in [0,1]: C1 = (0.01 L)^2, C2 = (0.03 L)^2, L = 1.
inline constexpr double kSsimC1 = 0.01 * 0.01;
inline constexpr double kSsimC2 = 0.03 * 0.03;
inline constexpr int kSsimRadius = 5;           // 11x11 window
inline constexpr double kSsimSigma = 1.5;       // Gaussian window sigma, pixels
inline constexpr double kRelMseEpsilon = 0.01;  // relMSE denominator: r^2 + 0.01

// ---- the pixels scored ----

// A reference pixel with a NaN or Inf in any channel has no right answer to score a result
// against: every metric leaves it out, as if the image had no such pixel (the means are over the
// other pixels; SSIM's windows skip it). A mask holds 1 per scored pixel; empty: every pixel.
using PixelMask = std::vector<std::uint8_t>;

// The pixels of `reference` with every channel finite; empty when all of them are.
PixelMask finitePixels(const Image& reference);

// The pixels a mask leaves out (0 for an empty mask).
std::size_t excludedPixels(const PixelMask& scored);

// ---- single metrics ----
// A reference with no finite pixel, or a mask scoring none, leaves nothing to score: InvalidInput.

// Mean over pixels and channels of (x - r)^2, linear values, over the reference's finite pixels.
// NaN in x propagates (a broken result must not look good).
double mse(const Image& result, const Image& reference);

// Mean over pixels and channels of (x - r)^2 / (r^2 + 0.01) (pbrt's relative MSE), linear values,
// over the reference's finite pixels.
double relMse(const Image& result, const Image& reference);

// 10 log10(1 / MSE) in dB of two display images (over the pixels `scored`); +infinity when they
// are identical there.
double psnr(const Image& resultDisplay, const Image& referenceDisplay,
            const PixelMask& scored = {});

// Mean SSIM of two display images: the SSIM map of each of R, G, B with an 11x11 Gaussian window
// (sigma 1.5), averaged over pixels and then over the three channels. At the borders the window
// is restricted to the pixels inside the image and its weights renormalised, so every pixel
// counts and images smaller than the window work. With a mask, likewise: windows and the mean
// are restricted to the pixels scored.
double ssim(const Image& resultDisplay, const Image& referenceDisplay,
            const PixelMask& scored = {});

// Mean over pixels and channels of |(x_t - x_{t-1}) - (r_t - r_{t-1})| on display images (over
// the pixels `scored`): zero when the result changes exactly as the reference does; flicker and
// lag both raise it.
double temporalError(const Image& resultDisplay, const Image& previousResultDisplay,
                     const Image& referenceDisplay, const Image& previousReferenceDisplay,
                     const PixelMask& scored = {});

// ---- per frame and per sequence ----

struct FrameMetrics {
    double mse = 0.0;
    double relMse = 0.0;
    double psnr = 0.0;  // dB; +infinity for identical display images
    double ssim = 1.0;
    std::optional<double> temporalError;  // absent for frame 0 (no previous frame)
    std::size_t excludedPixels = 0;       // reference pixels with NaN/Inf, left out of all above
    // Means over the scored pixels and channels of the linear images: their ratio is the energy
    // ratio (energyRatio), which a denoiser must keep near 1 (it must not trade the image's
    // light for smoothness).
    double resultMean = 0.0;
    double referenceMean = 0.0;
};

// resultMean / referenceMean: 1 where the result holds the reference's light; for a sequence's
// mean (meanOf), the ratio of the frames' summed means. NaN where the reference is black.
double energyRatio(const FrameMetrics& m);

// MSE and relMSE of the linear images; PSNR and SSIM of toneMap(., exposure), all over the
// reference's finite pixels. No temporal error.
FrameMetrics compareFrame(const Image& result, const Image& reference, float exposure = 1.0f);

// Means over frames. The temporal error's mean is over the frames that have one (1..N-1), absent
// when none does. PSNR is the mean of the per-frame dB values, so one identical frame makes the
// mean infinite. excludedPixels: the frames' sum. resultMean, referenceMean: the frames' means,
// so the energy ratio of the mean is the whole sequence's.
FrameMetrics meanOf(const std::vector<FrameMetrics>& frames);

struct SequenceMetrics {
    std::vector<FrameMetrics> frames;
    FrameMetrics mean;
};

// Compares a sequence frame by frame, holding only the previous frame's display images: what a
// caller streaming 4K frames from disk uses.
class SequenceComparer {
  public:
    explicit SequenceComparer(float exposure = 1.0f);

    // Metrics of the next frame (temporal error against the frame added before it, over the
    // pixels finite in both frames' references).
    const FrameMetrics& addFrame(const Image& result, const Image& reference);

    const std::vector<FrameMetrics>& frames() const { return frames_; }
    SequenceMetrics metrics() const { return {frames_, meanOf(frames_)}; }

  private:
    float exposure_;
    std::vector<FrameMetrics> frames_;
    Image previousResult_;  // display images of the previous frame
    Image previousReference_;
    PixelMask previousScored_;  // the previous reference's finite pixels
};

// All frames at once; `results` and `references` must have the same length.
SequenceMetrics compareSequence(const std::vector<Image>& results,
                                const std::vector<Image>& references, float exposure = 1.0f);

// ---- images ----

// Per-pixel relative error e = sqrt(mean_c (x - r)^2 / (r^2 + 0.01)) (the root of relMSE's
// per-pixel term) on a log scale: minError and below map to the colour map's dark end,
// maxError and above to its bright end. Colour map: viridis (perceptually uniform, readable in
// grey and by colour-blind viewers).
struct HeatMapScale {
    double minError = 1e-3;  // 0.1 %
    double maxError = 1.0;   // 100 %
};

// Viridis at t in [0,1] (clamped), display-encoded RGB.
void viridis(double t, float rgb[3]);

// The heat map of `result` against `reference` (linear images), display-encoded.
Image errorHeatMap(const Image& result, const Image& reference, const HeatMapScale& scale = {});

struct ContactSheetOptions {
    float exposure = 1.0f;
    int gap = 4;         // pixels between panels, and above the legend
    bool legend = true;  // a colour bar with the heat map's scale under its panel
    HeatMapScale scale;
};

// Where the panels of a contact sheet lie: panel p's top-left corner is (p * (width + gap), 0).
struct ContactSheetLayout {
    int panelWidth = 0;
    int panelHeight = 0;
    int panels = 0;
    int gap = 0;
    int legendHeight = 0;  // rows below the panels (0 without legend), gap included
    int width() const { return panels * panelWidth + (panels - 1) * gap; }
    int height() const { return panelHeight + legendHeight; }
    int panelX(int panel) const { return panel * (panelWidth + gap); }
};
ContactSheetLayout contactSheetLayout(int panelWidth, int panelHeight, int panels,
                                      const ContactSheetOptions& options = {});

// input | result | reference | error heat map, side by side (input, when null, is left out: three
// panels), each tone-mapped with options.exposure; the gaps and the legend strip are dark grey.
// Display-encoded, ready for rtd::writePng. All images must have the same size.
Image contactSheet(const Image* input, const Image& result, const Image& reference,
                   const ContactSheetOptions& options = {});

}  // namespace rtd::metrics
