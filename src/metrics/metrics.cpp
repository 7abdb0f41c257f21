// Quality metrics (MSE, relMSE, PSNR, SSIM, temporal error), the error heat map and contact
// sheets. Sums are in double: frames are compared at 4K, where float sums of millions of terms
// lose digits, and SSIM's variances are differences of nearly equal numbers. One file of ~500
// lines: the metrics share their accumulation helpers, and the sheets draw with the heat map's.
#include "metrics/metrics.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd::metrics {
namespace {

// Below this many values a loop runs on one thread: waking the team costs more than it saves.
constexpr std::ptrdiff_t kParallelThreshold = 1 << 15;

std::string sizeText(const Image& image) {
    return fmt::format("{}x{}", image.width, image.height);
}

void requireComparable(const Image& a, const Image& b, const char* what) {
    if (a.channels != 3 || b.channels != 3)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: needs 3-channel images, got {} and {} channels", what,
                                a.channels, b.channels));
    if (a.width != b.width || a.height != b.height)
        throw Error(ErrorCode::InvalidArgument, fmt::format("{}: image sizes differ ({} and {})",
                                                            what, sizeText(a), sizeText(b)));
    if (a.empty()) throw Error(ErrorCode::InvalidArgument, fmt::format("{}: empty images", what));
}

void requireMask(const PixelMask& scored, const Image& image, const char* what) {
    if (!scored.empty() && scored.size() != image.pixelCount())
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: a mask of {} pixels for a {} image", what, scored.size(),
                                sizeText(image)));
}

Error nothingScored(const char* what) {
    return Error(
        ErrorCode::InvalidInput,
        fmt::format("{}: every pixel of the reference holds NaN/Inf: nothing to score", what));
}

// Mean of term(i) for i in [0, count), summed in double across threads; with a mask, over the
// values of the pixels scored (`channels` values a pixel).
template <class Term>
double meanOverValues(std::size_t count, Term term, const PixelMask& scored = {}, int channels = 3,
                      const char* what = "") {
    const auto n = static_cast<std::ptrdiff_t>(count);
    double sum = 0.0;
    if (scored.empty()) {
#pragma omp parallel for schedule(static) reduction(+ : sum) if (n > kParallelThreshold)
        for (std::ptrdiff_t i = 0; i < n; ++i) sum += term(i);
        return sum / static_cast<double>(count);
    }
    const std::uint8_t* mask = scored.data();
    std::ptrdiff_t used = 0;
#pragma omp parallel for schedule(static) reduction(+ : sum, used) if (n > kParallelThreshold)
    for (std::ptrdiff_t i = 0; i < n; ++i) {
        if (!mask[i / channels]) continue;
        sum += term(i);
        ++used;
    }
    if (used == 0) throw nothingScored(what);
    return sum / static_cast<double>(used);
}

double meanSquaredError(const Image& a, const Image& b, const PixelMask& scored, const char* what) {
    const float* x = a.pixels.data();
    const float* r = b.pixels.data();
    return meanOverValues(
        a.pixels.size(),
        [=](std::ptrdiff_t i) {
            const double d = double(x[i]) - double(r[i]);
            return d * d;
        },
        scored, a.channels, what);
}

double relativeSquaredError(const Image& result, const Image& reference, const PixelMask& scored) {
    const float* x = result.pixels.data();
    const float* r = reference.pixels.data();
    return meanOverValues(
        result.pixels.size(),
        [=](std::ptrdiff_t i) {
            const double d = double(x[i]) - double(r[i]);
            return d * d / (double(r[i]) * double(r[i]) + kRelMseEpsilon);
        },
        scored, result.channels, "relMse");
}

// The 11-tap Gaussian (sigma 1.5), normalised to sum 1.
std::array<double, 2 * kSsimRadius + 1> ssimWeights() {
    std::array<double, 2 * kSsimRadius + 1> w{};
    double sum = 0.0;
    for (int k = -kSsimRadius; k <= kSsimRadius; ++k) {
        w[k + kSsimRadius] = std::exp(-double(k * k) / (2.0 * kSsimSigma * kSsimSigma));
        sum += w[k + kSsimRadius];
    }
    for (double& v : w) v /= sum;
    return w;
}

// 1 / (sum of the window weights that fall inside [0, size)) at each position: the restricted
// window's renormalisation, 1 away from the borders.
std::vector<double> windowNorms(int size, const std::array<double, 2 * kSsimRadius + 1>& w) {
    std::vector<double> norms(size);
    for (int i = 0; i < size; ++i) {
        double sum = 0.0;
        for (int k = std::max(-kSsimRadius, -i); k <= std::min(kSsimRadius, size - 1 - i); ++k)
            sum += w[k + kSsimRadius];
        norms[i] = 1.0 / sum;
    }
    return norms;
}

// The five local moments SSIM needs, as planes: E[a], E[b], E[a^2], E[b^2], E[ab].
constexpr int kMoments = 5;

// Horizontal pass of one row of one channel: moments of a and b over the restricted window.
// out holds kMoments planes of `width` values. With a mask row `m` (a and b already zero where
// it is), a sixth plane holds the window's weight over the pixels scored, and the caller divides
// by it instead of renormalising at the borders (`norms` then all 1).
void horizontalMoments(const double* a, const double* b, const double* m, int width,
                       const std::array<double, 2 * kSsimRadius + 1>& w,
                       const std::vector<double>& norms, double* out) {
    double* ma = out;
    double* mb = out + width;
    double* maa = out + 2 * width;
    double* mbb = out + 3 * width;
    double* mab = out + 4 * width;
    double* mm = m ? out + kMoments * width : nullptr;
    const auto windowAt = [&](int x, int kFrom, int kTo, double norm) {
        double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
        for (int k = kFrom; k <= kTo; ++k) {
            const double wk = w[k + kSsimRadius];
            const double va = a[x + k], vb = b[x + k];
            sa += wk * va;
            sb += wk * vb;
            saa += wk * va * va;
            sbb += wk * vb * vb;
            sab += wk * va * vb;
        }
        ma[x] = sa * norm;
        mb[x] = sb * norm;
        maa[x] = saa * norm;
        mbb[x] = sbb * norm;
        mab[x] = sab * norm;
        if (m) {
            double sm = 0;
            for (int k = kFrom; k <= kTo; ++k) sm += w[k + kSsimRadius] * m[x + k];
            mm[x] = sm;
        }
    };
    for (int x = 0; x < width; ++x) {
        const bool interior = x >= kSsimRadius && x < width - kSsimRadius;
        if (interior) {
            windowAt(x, -kSsimRadius, kSsimRadius, 1.0);
        } else {
            windowAt(x, std::max(-kSsimRadius, -x), std::min(kSsimRadius, width - 1 - x), norms[x]);
        }
    }
}

double ssimValue(double muA, double muB, double eAA, double eBB, double eAB) {
    const double varA = eAA - muA * muA;
    const double varB = eBB - muB * muB;
    const double cov = eAB - muA * muB;
    return ((2.0 * muA * muB + kSsimC1) * (2.0 * cov + kSsimC2)) /
           ((muA * muA + muB * muB + kSsimC1) * (varA + varB + kSsimC2));
}

// ---- a 3x5 pixel font for the legend's labels ----

struct Glyph {
    char c;
    std::array<const char*, 5> rows;
};
constexpr std::array<Glyph, 15> kGlyphs{{
    {'0', {"###", "#.#", "#.#", "#.#", "###"}},
    {'1', {".#.", "##.", ".#.", ".#.", "###"}},
    {'2', {"###", "..#", "###", "#..", "###"}},
    {'3', {"###", "..#", "###", "..#", "###"}},
    {'4', {"#.#", "#.#", "###", "..#", "..#"}},
    {'5', {"###", "#..", "###", "..#", "###"}},
    {'6', {"###", "#..", "###", "#.#", "###"}},
    {'7', {"###", "..#", "..#", "..#", "..#"}},
    {'8', {"###", "#.#", "###", "#.#", "###"}},
    {'9', {"###", "#.#", "###", "..#", "###"}},
    {'.', {"...", "...", "...", "...", ".#."}},
    {'%', {"#.#", "..#", ".#.", "#..", "#.#"}},
    {'e', {"...", "###", "###", "#..", "###"}},
    {'+', {"...", ".#.", "###", ".#.", "..."}},
    {'-', {"...", "...", "###", "...", "..."}},
}};
constexpr int kGlyphAdvance = 4;  // 3 columns + 1 of spacing, in font pixels

int textWidth(const std::string& text, int scale) {
    return text.empty() ? 0 : (int(text.size()) * kGlyphAdvance - 1) * scale;
}

void fillRect(Image& image, int x0, int y0, int w, int h, const float rgb[3]) {
    const int xBegin = std::max(0, x0), xEnd = std::min(image.width, x0 + w);
    for (int y = std::max(0, y0); y < std::min(image.height, y0 + h); ++y) {
        float* row = &image.pixels[std::size_t(y) * image.width * 3];
        for (int x = xBegin; x < xEnd; ++x) std::copy_n(rgb, 3, row + std::size_t(x) * 3);
    }
}

void drawText(Image& image, int x0, int y0, const std::string& text, int scale,
              const float rgb[3]) {
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto glyph = std::find_if(kGlyphs.begin(), kGlyphs.end(),
                                        [&](const Glyph& g) { return g.c == text[i]; });
        if (glyph == kGlyphs.end()) continue;  // unknown characters leave a blank
        const int gx = x0 + int(i) * kGlyphAdvance * scale;
        for (int row = 0; row < 5; ++row)
            for (int col = 0; col < 3; ++col)
                if (glyph->rows[row][col] == '#')
                    fillRect(image, gx + col * scale, y0 + row * scale, scale, scale, rgb);
    }
}

constexpr float kBackground[3] = {0.12f, 0.12f, 0.12f};  // grey (the sheet is filled with [0])
constexpr float kTextColour[3] = {0.9f, 0.9f, 0.9f};
constexpr float kNonFiniteColour[3] = {1.0f, 0.0f, 1.0f};  // magenta: not on the colour map

// Font pixel size: labels stay legible on 4K panels and fit on tiny test images.
int legendScale(int panelWidth, int panelHeight) {
    return std::max(1, std::min(panelWidth / 256, panelHeight / 160));
}

// Legend rows under the panels: gap, colour bar (4 s), 2 s, labels (5 s), s.
int legendRows(int gap, int scale) {
    return gap + 12 * scale;
}

void copyPanel(Image& sheet, const Image& panel, int x0) {
    for (int y = 0; y < panel.height; ++y)
        std::copy_n(&panel.pixels[std::size_t(y) * panel.width * 3], std::size_t(panel.width) * 3,
                    &sheet.pixels[(std::size_t(y) * sheet.width + x0) * 3]);
}

// Colour bar from minError to maxError under the heat map panel, labelled at the powers of ten.
void drawLegend(Image& sheet, const ContactSheetLayout& layout, int panel,
                const HeatMapScale& scale) {
    const int s = legendScale(layout.panelWidth, layout.panelHeight);
    const int x0 = layout.panelX(panel);
    const int barTop = layout.panelHeight + layout.gap;
    const int barHeight = 4 * s;
    const int width = layout.panelWidth;
    for (int x = 0; x < width; ++x) {
        float rgb[3];
        viridis(width > 1 ? double(x) / double(width - 1) : 0.0, rgb);
        fillRect(sheet, x0 + x, barTop, 1, barHeight, rgb);
    }
    const double logMin = std::log10(scale.minError);
    const double logMax = std::log10(scale.maxError);
    const int labelTop = barTop + barHeight + 2 * s;
    int freeFrom = x0;  // labels never overlap: each starts right of the previous one's end
    for (int e = int(std::ceil(logMin - 1e-9)); e <= int(std::floor(logMax + 1e-9)); ++e) {
        const double t = (double(e) - logMin) / (logMax - logMin);
        const int tickX = x0 + int(std::lround(t * double(width - 1)));
        const std::string label = fmt::format("{:g}%", std::pow(10.0, e) * 100.0);
        const int labelWidth = textWidth(label, s);
        const int left = std::clamp(tickX - labelWidth / 2, x0, x0 + width - labelWidth);
        fillRect(sheet, tickX, barTop + barHeight, std::max(1, s / 2), 2 * s, kTextColour);
        if (left < freeFrom || left + labelWidth > x0 + width) continue;
        drawText(sheet, left, labelTop, label, s, kTextColour);
        freeFrom = left + labelWidth + 2 * s;
    }
}

}  // namespace

// ---- the pixels scored ----

PixelMask finitePixels(const Image& reference) {
    const std::size_t pixels = reference.pixelCount();
    const auto channels = std::size_t(reference.channels);
    const float* values = reference.pixels.data();
    const auto finite = [&](std::size_t pixel) {
        for (std::size_t c = 0; c < channels; ++c)
            if (!std::isfinite(values[pixel * channels + c])) return false;
        return true;
    };
    std::size_t first = 0;
    while (first < pixels && finite(first)) ++first;
    if (first == pixels) return {};  // the usual case: no mask, every metric as without one
    PixelMask scored(pixels, 1);
    for (std::size_t i = first; i < pixels; ++i) scored[i] = std::uint8_t(finite(i));
    return scored;
}

std::size_t excludedPixels(const PixelMask& scored) {
    return std::size_t(std::count(scored.begin(), scored.end(), std::uint8_t(0)));
}

// ---- single metrics ----

double mse(const Image& result, const Image& reference) {
    requireComparable(result, reference, "mse");
    return meanSquaredError(result, reference, finitePixels(reference), "mse");
}

double relMse(const Image& result, const Image& reference) {
    requireComparable(result, reference, "relMse");
    return relativeSquaredError(result, reference, finitePixels(reference));
}

double psnr(const Image& resultDisplay, const Image& referenceDisplay, const PixelMask& scored) {
    requireComparable(resultDisplay, referenceDisplay, "psnr");
    requireMask(scored, resultDisplay, "psnr");
    const double m = meanSquaredError(resultDisplay, referenceDisplay, scored, "psnr");
    if (m == 0.0) return std::numeric_limits<double>::infinity();
    return 10.0 * std::log10(1.0 / m);
}

double ssim(const Image& resultDisplay, const Image& referenceDisplay, const PixelMask& scored) {
    requireComparable(resultDisplay, referenceDisplay, "ssim");
    requireMask(scored, resultDisplay, "ssim");
    const int width = resultDisplay.width;
    const int height = resultDisplay.height;
    const auto w = ssimWeights();
    const bool masked = !scored.empty();
    // With a mask, the window's weight over the pixels scored normalises it (the border too).
    const std::vector<double> columnNorms =
        masked ? std::vector<double>(std::size_t(width), 1.0) : windowNorms(width, w);
    const std::vector<double> rowNorms = windowNorms(height, w);
    const std::size_t planes = masked ? kMoments + 1 : kMoments;

    // Bands of rows, each with its own horizontal-pass rows (halo included): memory stays
    // O(band * width) however large the frame, at the cost of recomputing 2 * radius rows.
    constexpr int kBand = 32;
    const int bands = (height + kBand - 1) / kBand;
    double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0;
#pragma omp parallel if (std::ptrdiff_t(width) * height > kParallelThreshold)
    {
        const std::size_t rowStride = planes * width;
        std::vector<double> moments(std::size_t(kBand + 2 * kSsimRadius) * rowStride);
        std::vector<double> vertical(rowStride);
        std::vector<double> a(width), b(width), m(masked ? width : 0);
#pragma omp for schedule(monotonic : dynamic) reduction(+ : sum0, sum1, sum2)
        for (int band = 0; band < bands; ++band) {
            const int y0 = band * kBand;
            const int y1 = std::min(height, y0 + kBand);
            const int h0 = std::max(0, y0 - kSsimRadius);
            const int h1 = std::min(height, y1 + kSsimRadius);
            for (int c = 0; c < 3; ++c) {
                for (int y = h0; y < h1; ++y) {
                    for (int x = 0; x < width; ++x) {
                        a[x] = resultDisplay.at(x, y, c);
                        b[x] = referenceDisplay.at(x, y, c);
                    }
                    if (masked) {
                        for (int x = 0; x < width; ++x) {
                            m[x] = scored[std::size_t(y) * width + x];
                            a[x] *= m[x];
                            b[x] *= m[x];
                        }
                    }
                    horizontalMoments(a.data(), b.data(), masked ? m.data() : nullptr, width, w,
                                      columnNorms, &moments[std::size_t(y - h0) * rowStride]);
                }
                double channelSum = 0.0;
                for (int y = y0; y < y1; ++y) {
                    std::fill(vertical.begin(), vertical.end(), 0.0);
                    const int kFrom = std::max(-kSsimRadius, -y);
                    const int kTo = std::min(kSsimRadius, height - 1 - y);
                    for (int k = kFrom; k <= kTo; ++k) {
                        const double wk = w[k + kSsimRadius];
                        const double* row = &moments[std::size_t(y + k - h0) * rowStride];
                        for (std::size_t i = 0; i < rowStride; ++i) vertical[i] += wk * row[i];
                    }
                    for (int x = 0; x < width; ++x) {
                        if (masked && !scored[std::size_t(y) * width + x]) continue;
                        // A scored pixel is in its own window: its weight is never 0.
                        const double norm =
                            masked ? 1.0 / vertical[kMoments * width + x] : rowNorms[y];
                        channelSum += ssimValue(vertical[x] * norm, vertical[width + x] * norm,
                                                vertical[2 * width + x] * norm,
                                                vertical[3 * width + x] * norm,
                                                vertical[4 * width + x] * norm);
                    }
                }
                (c == 0 ? sum0 : c == 1 ? sum1 : sum2) += channelSum;
            }
        }
    }
    const double pixels =
        masked ? double(scored.size() - excludedPixels(scored)) : double(width) * double(height);
    if (pixels == 0.0) throw nothingScored("ssim");
    return (sum0 / pixels + sum1 / pixels + sum2 / pixels) / 3.0;
}

double temporalError(const Image& resultDisplay, const Image& previousResultDisplay,
                     const Image& referenceDisplay, const Image& previousReferenceDisplay,
                     const PixelMask& scored) {
    requireComparable(resultDisplay, referenceDisplay, "temporalError");
    requireComparable(resultDisplay, previousResultDisplay, "temporalError (previous result)");
    requireComparable(referenceDisplay, previousReferenceDisplay,
                      "temporalError (previous reference)");
    requireMask(scored, resultDisplay, "temporalError");
    const float* x = resultDisplay.pixels.data();
    const float* xp = previousResultDisplay.pixels.data();
    const float* r = referenceDisplay.pixels.data();
    const float* rp = previousReferenceDisplay.pixels.data();
    return meanOverValues(
        resultDisplay.pixels.size(),
        [=](std::ptrdiff_t i) {
            return std::abs((double(x[i]) - double(xp[i])) - (double(r[i]) - double(rp[i])));
        },
        scored, resultDisplay.channels, "temporalError");
}

// ---- per frame and per sequence ----

namespace {

// The metrics of a frame whose display images are already made, over the pixels `scored` (the
// reference's finite ones).
FrameMetrics frameMetrics(const Image& result, const Image& reference, const Image& resultDisplay,
                          const Image& referenceDisplay, const PixelMask& scored) {
    FrameMetrics m;
    m.mse = meanSquaredError(result, reference, scored, "mse");
    m.relMse = relativeSquaredError(result, reference, scored);
    m.psnr = psnr(resultDisplay, referenceDisplay, scored);
    m.ssim = ssim(resultDisplay, referenceDisplay, scored);
    m.excludedPixels = excludedPixels(scored);
    double resultSum = 0.0, referenceSum = 0.0;
    std::size_t counted = 0;
    for (std::size_t p = 0; p < reference.pixelCount(); ++p) {
        if (!scored.empty() && !scored[p]) continue;
        for (int c = 0; c < reference.channels; ++c) {
            resultSum += result.pixels[p * std::size_t(result.channels) + std::size_t(c)];
            referenceSum += reference.pixels[p * std::size_t(reference.channels) + std::size_t(c)];
        }
        counted += std::size_t(reference.channels);
    }
    m.resultMean = resultSum / double(std::max<std::size_t>(counted, 1));
    m.referenceMean = referenceSum / double(std::max<std::size_t>(counted, 1));
    return m;
}

// Pixels scored in both masks (empty: all).
PixelMask bothScored(const PixelMask& a, const PixelMask& b) {
    if (a.empty()) return b;
    if (b.empty()) return a;
    PixelMask both(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) both[i] = std::uint8_t(a[i] & b[i]);
    return both;
}

}  // namespace

FrameMetrics compareFrame(const Image& result, const Image& reference, float exposure) {
    requireComparable(result, reference, "compareFrame");
    return frameMetrics(result, reference, toneMap(result, exposure), toneMap(reference, exposure),
                        finitePixels(reference));
}

double energyRatio(const FrameMetrics& m) {
    return m.referenceMean != 0.0 ? m.resultMean / m.referenceMean
                                  : std::numeric_limits<double>::quiet_NaN();
}

FrameMetrics meanOf(const std::vector<FrameMetrics>& frames) {
    if (frames.empty()) throw Error(ErrorCode::InvalidArgument, "meanOf: no frames");
    FrameMetrics mean;
    mean.ssim = 0.0;
    double temporalSum = 0.0;
    int temporalCount = 0;
    for (const FrameMetrics& f : frames) {
        mean.mse += f.mse;
        mean.relMse += f.relMse;
        mean.psnr += f.psnr;
        mean.ssim += f.ssim;
        mean.excludedPixels += f.excludedPixels;
        mean.resultMean += f.resultMean;
        mean.referenceMean += f.referenceMean;
        if (f.temporalError) {
            temporalSum += *f.temporalError;
            ++temporalCount;
        }
    }
    const double n = double(frames.size());
    mean.mse /= n;
    mean.relMse /= n;
    mean.psnr /= n;
    mean.ssim /= n;
    mean.resultMean /= n;
    mean.referenceMean /= n;
    if (temporalCount > 0) mean.temporalError = temporalSum / double(temporalCount);
    return mean;
}

SequenceComparer::SequenceComparer(float exposure) : exposure_(exposure) {}

const FrameMetrics& SequenceComparer::addFrame(const Image& result, const Image& reference) {
    requireComparable(result, reference, "SequenceComparer::addFrame");
    if (!frames_.empty() &&
        (result.width != previousResult_.width || result.height != previousResult_.height))
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("SequenceComparer::addFrame: frame {} is {}, frame {} was {}",
                                frames_.size(), sizeText(result), frames_.size() - 1,
                                sizeText(previousResult_)));
    Image resultDisplay = toneMap(result, exposure_);
    Image referenceDisplay = toneMap(reference, exposure_);
    PixelMask scored = finitePixels(reference);
    FrameMetrics m = frameMetrics(result, reference, resultDisplay, referenceDisplay, scored);
    if (!frames_.empty())
        m.temporalError = temporalError(resultDisplay, previousResult_, referenceDisplay,
                                        previousReference_, bothScored(scored, previousScored_));
    previousResult_ = std::move(resultDisplay);
    previousReference_ = std::move(referenceDisplay);
    previousScored_ = std::move(scored);
    frames_.push_back(m);
    return frames_.back();
}

SequenceMetrics compareSequence(const std::vector<Image>& results,
                                const std::vector<Image>& references, float exposure) {
    if (results.size() != references.size())
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("compareSequence: {} results but {} references", results.size(),
                                references.size()));
    SequenceComparer comparer(exposure);
    for (std::size_t i = 0; i < results.size(); ++i) comparer.addFrame(results[i], references[i]);
    return comparer.metrics();
}

// ---- images ----

void viridis(double t, float rgb[3]) {
    // Degree-6 polynomial fit of matplotlib's viridis (endpoints within 0.015 of the table).
    static constexpr double kCoefficients[7][3] = {
        {0.2777273272234177, 0.005407344544966578, 0.3340998053353061},
        {0.1050930431085774, 1.404613529898575, 1.384590162594685},
        {-0.3308618287255563, 0.214847559468213, 0.09509516302823659},
        {-4.634230498983486, -5.799100973351585, -19.33244095627987},
        {6.228269936347081, 14.17993336680509, 56.69055260068105},
        {4.776384997670288, -13.74514537774601, -65.35303263337234},
        {-5.435455855934631, 4.645852612178535, 26.3124352495832},
    };
    t = std::isnan(t) ? 0.0 : std::clamp(t, 0.0, 1.0);
    for (int c = 0; c < 3; ++c) {
        double v = kCoefficients[6][c];
        for (int k = 5; k >= 0; --k) v = v * t + kCoefficients[k][c];
        rgb[c] = float(std::clamp(v, 0.0, 1.0));
    }
}

Image errorHeatMap(const Image& result, const Image& reference, const HeatMapScale& scale) {
    requireComparable(result, reference, "errorHeatMap");
    if (!(scale.minError > 0.0) || !(scale.maxError > scale.minError) ||
        !std::isfinite(scale.maxError))
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("errorHeatMap: the scale needs 0 < minError < maxError, got {} "
                                "and {}",
                                scale.minError, scale.maxError));
    Image map(result.width, result.height, 3);
    const double logMin = std::log10(scale.minError);
    const double logRange = std::log10(scale.maxError) - logMin;
    const auto count = static_cast<std::ptrdiff_t>(result.pixelCount());
#pragma omp parallel for schedule(static) if (count > kParallelThreshold)
    for (std::ptrdiff_t i = 0; i < count; ++i) {
        double sum = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double x = result.pixels[i * 3 + c];
            const double r = reference.pixels[i * 3 + c];
            sum += (x - r) * (x - r) / (r * r + kRelMseEpsilon);
        }
        const double error = std::sqrt(sum / 3.0);
        float* out = &map.pixels[i * 3];
        if (!std::isfinite(error)) {
            std::copy_n(kNonFiniteColour, 3, out);
            continue;
        }
        const double t = error > 0.0 ? (std::log10(error) - logMin) / logRange : 0.0;
        viridis(t, out);
    }
    return map;
}

ContactSheetLayout contactSheetLayout(int panelWidth, int panelHeight, int panels,
                                      const ContactSheetOptions& options) {
    if (panelWidth <= 0 || panelHeight <= 0 || panels <= 0 || options.gap < 0)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("contactSheetLayout: bad layout ({} panels of {}x{}, gap {})",
                                panels, panelWidth, panelHeight, options.gap));
    ContactSheetLayout layout;
    layout.panelWidth = panelWidth;
    layout.panelHeight = panelHeight;
    layout.panels = panels;
    layout.gap = options.gap;
    layout.legendHeight =
        options.legend ? legendRows(options.gap, legendScale(panelWidth, panelHeight)) : 0;
    return layout;
}

Image contactSheet(const Image* input, const Image& result, const Image& reference,
                   const ContactSheetOptions& options) {
    requireComparable(result, reference, "contactSheet");
    if (input) requireComparable(*input, result, "contactSheet (input)");
    std::vector<Image> panels;
    if (input) panels.push_back(toneMap(*input, options.exposure));
    panels.push_back(toneMap(result, options.exposure));
    panels.push_back(toneMap(reference, options.exposure));
    panels.push_back(errorHeatMap(result, reference, options.scale));

    const ContactSheetLayout layout =
        contactSheetLayout(result.width, result.height, int(panels.size()), options);
    Image sheet(layout.width(), layout.height(), 3, kBackground[0]);  // grey: one value fills
    for (std::size_t p = 0; p < panels.size(); ++p)
        copyPanel(sheet, panels[p], layout.panelX(int(p)));
    if (options.legend) drawLegend(sheet, layout, layout.panels - 1, options.scale);
    return sheet;
}

}  // namespace rtd::metrics
