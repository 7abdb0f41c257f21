// The energy restoration (issue 38, docs/energy.md): every robust step of a method (the firefly
// removal, the history clamps, the luminance edge-stopping) discards some of the bright tail of
// 1-spp noise, and that tail carries much of indirect light, so the output is darker than the
// reference. This last pass gives the light back at a coarse scale: per 16x16 tile, the mean of
// the noisy input over the mean of the output, both averaged over the last frames (an
// exponential average of the tile's sums) and over the 3x3 neighbouring tiles, scales the output
// (interpolated bilinearly between tile centres). The input's samples are capped at `cap` times
// the tiles' mean (the input's or the output's, the larger), less in a tile's first frames, so
// that one firefly cannot brighten its tiles much. The scale is smooth across the image:
// structure, edges and noise are the method's.
// Pixels brighter than the cap (lights seen directly) are neither counted nor scaled.
// What the tiles' cap cuts (the tail of rare bright samples: much of indirect light) is given
// back over the whole frame: the frame's gain, 1 + the averaged cut light over the averaged
// restored output, each sample's cut part bounded so that it lifts the frame by at most
// `frameShare` (EnergySettings::frameShare).
//
// One kernel reads the input after the ingest; four run over the tile grid (one item per tile),
// two over the frame (one item) and one over the pixels at the end:
//   EnergyInput ... EnergyOutputSums -> EnergyAccumulate -> EnergyFrameCap -> EnergyTail
//                   -> EnergyGain -> EnergyFrameGain -> EnergyApply
// Tile data: images of one value per tile (ResourceDecl::tile), a plane per array.
#pragma once

#include "kernels/convert.h"
#include "kernels/views.h"

namespace rtd {

inline constexpr int kEnergyTile = 16;  // pixels per tile side

// The tile grid of a width x height image and where each of its arrays lies.
struct EnergyGrid {
    int across = 0, down = 0;
    // Frame arrays (EnergyOutputSums, EnergyAccumulate, EnergyTail, EnergyGain): 7 x tiles floats.
    float* frame = nullptr;
    // History (EnergyAccumulate): 3 x tiles floats, this frame's and last frame's.
    float* history = nullptr;
    const float* previousHistory = nullptr;
    // The frame's values (EnergyFrameCap, EnergyFrameGain): the cut part's bound, the gain.
    float* whole = nullptr;
    // The frame's history: averaged cut light, averaged restored output, frames averaged.
    float* wholeHistory = nullptr;
    const float* previousWholeHistory = nullptr;

    RTD_HOST_DEVICE RTD_INLINE int tiles() const { return across * down; }
    RTD_HOST_DEVICE RTD_INLINE int tile(int tx, int ty) const { return ty * across + tx; }
    // frame: output luminance sum, foreground count, gain, bright threshold, input luminance sum
    RTD_HOST_DEVICE RTD_INLINE float& outputSum(int t) const { return frame[t]; }
    RTD_HOST_DEVICE RTD_INLINE float& count(int t) const { return frame[tiles() + t]; }
    RTD_HOST_DEVICE RTD_INLINE float& gain(int t) const { return frame[2 * tiles() + t]; }
    RTD_HOST_DEVICE RTD_INLINE float& threshold(int t) const { return frame[3 * tiles() + t]; }
    RTD_HOST_DEVICE RTD_INLINE float& inputSum(int t) const { return frame[4 * tiles() + t]; }
    // this frame's output sum over the counted pixels; the light the tile's cap cut there
    RTD_HOST_DEVICE RTD_INLINE float& countedOutput(int t) const { return frame[5 * tiles() + t]; }
    RTD_HOST_DEVICE RTD_INLINE float& tail(int t) const { return frame[6 * tiles() + t]; }
    // history: averaged input sum, averaged output sum, frames averaged
    RTD_HOST_DEVICE RTD_INLINE float& input(int t) const { return history[t]; }
    RTD_HOST_DEVICE RTD_INLINE float& output(int t) const { return history[tiles() + t]; }
    RTD_HOST_DEVICE RTD_INLINE float& frames(int t) const { return history[2 * tiles() + t]; }
    RTD_HOST_DEVICE RTD_INLINE float previousInput(int t) const { return previousHistory[t]; }
    RTD_HOST_DEVICE RTD_INLINE float previousOutput(int t) const {
        return previousHistory[tiles() + t];
    }
    RTD_HOST_DEVICE RTD_INLINE float previousFrames(int t) const {
        return previousHistory[2 * tiles() + t];
    }
};

RTD_HOST_DEVICE RTD_INLINE int energyTilesAcross(int width) {
    return (width + kEnergyTile - 1) / kEnergyTile;
}

// The caller's interleaved output at pixel (x, y).
RTD_HOST_DEVICE RTD_INLINE Float3 loadInterleaved(const float* rgb, int width, int x, int y) {
    const PixelIndex s = PixelIndex(y) * width + x;
    return {rgb[3 * s], rgb[3 * s + 1], rgb[3 * s + 2]};
}
// Its luminance, a negative one as 0: what every tile sum counts.
RTD_HOST_DEVICE RTD_INLINE float outputLuminance(const float* rgb, int width, int x, int y) {
    return maxf(luminance(loadInterleaved(rgb, width, x, y)), 0.0f);
}

// The pixels of tile (tx, ty): [x0, x1) x [y0, y1), clipped to the image.
struct EnergyTilePixels {
    int x0, y0, x1, y1;
};
RTD_HOST_DEVICE RTD_INLINE EnergyTilePixels energyTilePixels(const Layout& layout, int tx, int ty) {
    return {tx * kEnergyTile, ty * kEnergyTile, mini(tx * kEnergyTile + kEnergyTile, layout.width),
            mini(ty * kEnergyTile + kEnergyTile, layout.height)};
}

// Per pixel, right after the ingest (before any step changes its images, or the output overwrites
// a caller's input in place): the input radiance's luminance, noisy x albedo.
struct EnergyInputKernel {
    Layout layout;
    Planes3 noisy, albedo;
    float* inputLuminance;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const PixelIndex i = layout.index(x, y);
        inputLuminance[i] = luminance(noisy.load(i) * albedo.load(i));
    }
};

// Per tile: the output's and the input's luminance sums and the count over foreground pixels.
struct EnergyOutputSumsKernel {
    Layout layout;
    const std::int32_t* filterKey;
    const float* rgbOut;
    const float* inputLuminance;  // EnergyInputKernel's
    EnergyGrid grid;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int tx, int ty) const {
        float sum = 0.0f, count = 0.0f, input = 0.0f;
        const EnergyTilePixels p = energyTilePixels(layout, tx, ty);
        for (int y = p.y0; y < p.y1; ++y)
            for (int x = p.x0; x < p.x1; ++x) {
                const bool foreground = filterKey[layout.index(x, y)] >= 0;
                const float out = outputLuminance(rgbOut, layout.width, x, y);
                sum += foreground ? out : 0.0f;
                input += foreground ? maxf(inputLuminance[layout.index(x, y)], 0.0f) : 0.0f;
                count += foreground ? 1.0f : 0.0f;
            }
        const int t = grid.tile(tx, ty);
        grid.outputSum(t) = sum;
        grid.count(t) = count;
        grid.inputSum(t) = input;
    }
};

// Per tile: the cap (`cap` times the input's or output's mean over the 3x3 tiles around), the
// capped input's and the output's sums over pixels under it, averaged with the tile's history (1 /
// frames, at least 1 / maxFrames; temporal 0 or no history: this frame alone).
struct EnergyAccumulateKernel {
    Layout layout;
    const std::int32_t* filterKey;
    const float* rgbOut;
    const float* inputLuminance;  // EnergyInputKernel's
    InputSpan confidence;         // the caller's history confidence (data null: none)
    EnergyGrid grid;
    int temporal = 0;  // 1: average over frames (temporal methods)
    int hasHistory = 0;
    float maxFrames = 4.0f;   // frames averaged at most
    float capScale = 128.0f;  // EnergySettings::cap

    RTD_HOST_DEVICE RTD_INLINE void operator()(int tx, int ty) const {
        float sum = 0.0f, count = 0.0f, inputSum = 0.0f;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int ux = tx + dx, uy = ty + dy;
                const bool inside = ux >= 0 && uy >= 0 && ux < grid.across && uy < grid.down;
                const int u = grid.tile(inside ? ux : tx, inside ? uy : ty);
                sum += inside ? grid.outputSum(u) : 0.0f;
                count += inside ? grid.count(u) : 0.0f;
                inputSum += inside ? grid.inputSum(u) : 0.0f;
            }
        // One sample's sway is bounded alike whatever the average's length: the cap grows with
        // the frames the tile has averaged (a firefly in a first frame counts a quarter as much).
        const int t = grid.tile(tx, ty);
        const float averaged =
            temporal && hasHistory ? minf(grid.previousFrames(t) + 1.0f, maxFrames) : 1.0f;
        // The larger of the input's and the output's means: the output's alone is as low as the
        // method's loss, which would cap the light that restores it.
        const float cap = capScale * averaged / maxFrames * maxf(sum, inputSum) / maxf(count, 1.0f);
        float input = 0.0f, output = 0.0f, confident = 0.0f, pixels = 0.0f;
        const EnergyTilePixels p = energyTilePixels(layout, tx, ty);
        for (int y = p.y0; y < p.y1; ++y)
            for (int x = p.x0; x < p.x1; ++x) {
                const PixelIndex i = layout.index(x, y);
                const float out = outputLuminance(rgbOut, layout.width, x, y);
                const bool counted = filterKey[i] >= 0 && out <= cap;
                const float in = clampf(inputLuminance[i], 0.0f, cap);
                input += counted ? in : 0.0f;
                output += counted ? out : 0.0f;
                confident += loadConfidence(confidence, x, y);
                pixels += 1.0f;
            }
        // The caller's confidence shortens the tile's average as it does the history.
        const float kept = grid.previousFrames(t) * confident / maxf(pixels, 1.0f);
        const float frames = temporal && hasHistory ? minf(kept + 1.0f, maxFrames) : 1.0f;
        const float a = 1.0f / frames;
        grid.input(t) =
            frames > 1.0f ? grid.previousInput(t) + a * (input - grid.previousInput(t)) : input;
        grid.output(t) =
            frames > 1.0f ? grid.previousOutput(t) + a * (output - grid.previousOutput(t)) : output;
        grid.frames(t) = frames;
        grid.threshold(t) = cap;
        grid.countedOutput(t) = output;
    }
};

// One item: the bound of a sample's cut part, frameShare x the frame's counted output x the
// frames averaged (the average's weight of one frame is their reciprocal), so that one sample
// lifts the frame's gain by at most frameShare however long the average.
struct EnergyFrameCapKernel {
    EnergyGrid grid;
    int temporal = 0;  // 1: average over frames (EnergyAccumulate's)
    int hasHistory = 0;
    float maxFrames = 16.0f;
    float frameShare = 0.0f;  // EnergySettings::frameShare

    RTD_HOST_DEVICE RTD_INLINE void operator()(int, int) const {
        float output = 0.0f;
        for (int t = 0; t < grid.tiles(); ++t) output += grid.countedOutput(t);
        const float frames =
            temporal && hasHistory ? minf(grid.previousWholeHistory[2] + 1.0f, maxFrames) : 1.0f;
        grid.whole[0] = frameShare * output * frames;
        grid.wholeHistory[2] = frames;
    }
};

// Per tile: the light its cap cut from the counted pixels' input, each sample's part bounded by
// EnergyFrameCap's.
struct EnergyTailKernel {
    Layout layout;
    const std::int32_t* filterKey;
    const float* rgbOut;
    const float* inputLuminance;  // EnergyInputKernel's
    EnergyGrid grid;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int tx, int ty) const {
        const int t = grid.tile(tx, ty);
        const float cap = grid.threshold(t), bound = grid.whole[0];
        float tail = 0.0f;
        const EnergyTilePixels p = energyTilePixels(layout, tx, ty);
        for (int y = p.y0; y < p.y1; ++y)
            for (int x = p.x0; x < p.x1; ++x) {
                const PixelIndex i = layout.index(x, y);
                const float out = outputLuminance(rgbOut, layout.width, x, y);
                const bool counted = filterKey[i] >= 0 && out <= cap;
                tail += counted ? minf(maxf(inputLuminance[i] - cap, 0.0f), bound) : 0.0f;
            }
        grid.tail(t) = tail;
    }
};

// Per tile: the gain, the 3x3 tent-weighted averaged input over output, within [kMin, kMax]
// (1 where the tiles hold no light).
struct EnergyGainKernel {
    static constexpr float kMin = 0.2f, kMax = 5.0f;
    EnergyGrid grid;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int tx, int ty) const {
        float input = 0.0f, output = 0.0f;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                // Clamped to the grid: the edge tiles count twice (as an edge-padded tent).
                const int ux = mini(maxi(tx + dx, 0), grid.across - 1);
                const int uy = mini(maxi(ty + dy, 0), grid.down - 1);
                const float w = float((dx == 0 ? 2 : 1) * (dy == 0 ? 2 : 1));
                input += w * grid.input(grid.tile(ux, uy));
                output += w * grid.output(grid.tile(ux, uy));
            }
        // 1 where the tiles hold no light in the output (nothing to scale).
        const float gain = output > 1e-20f ? input / output : 1.0f;
        grid.gain(grid.tile(tx, ty)) = clampf(gain, kMin, kMax);
    }
};

// One item: the frame's gain, 1 + the cut light over the output the tiles' gains give, both
// averaged over EnergyFrameCap's frames, within [1, kMax].
struct EnergyFrameGainKernel {
    static constexpr float kMax = 1.25f;
    EnergyGrid grid;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int, int) const {
        float tail = 0.0f, restored = 0.0f;
        for (int t = 0; t < grid.tiles(); ++t) {
            tail += grid.tail(t);
            restored += grid.gain(t) * grid.countedOutput(t);
        }
        const float frames = grid.wholeHistory[2], a = 1.0f / frames;
        const float* before = grid.previousWholeHistory;
        const float averagedTail = frames > 1.0f ? before[0] + a * (tail - before[0]) : tail;
        const float averagedOutput =
            frames > 1.0f ? before[1] + a * (restored - before[1]) : restored;
        grid.wholeHistory[0] = averagedTail;
        grid.wholeHistory[1] = averagedOutput;
        grid.whole[1] = averagedOutput > 1e-20f
                            ? clampf(1.0f + averagedTail / averagedOutput, 1.0f, kMax)
                            : 1.0f;
    }
};

// Per pixel: the output times the gain interpolated between the tile centres and the frame's gain
// (foreground pixels under their tile's cap).
struct EnergyApplyKernel {
    Layout layout;
    const std::int32_t* filterKey;
    float* rgbOut;
    EnergyGrid grid;

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const float fx = (float(x) + 0.5f) / float(kEnergyTile) - 0.5f;
        const float fy = (float(y) + 0.5f) / float(kEnergyTile) - 0.5f;
        const int x0 = mini(int(fx + 1.0f) - 1 < 0 ? 0 : int(fx + 1.0f) - 1, grid.across - 1);
        const int y0 = mini(int(fy + 1.0f) - 1 < 0 ? 0 : int(fy + 1.0f) - 1, grid.down - 1);
        const int x1 = mini(x0 + 1, grid.across - 1), y1 = mini(y0 + 1, grid.down - 1);
        const float wx = clampf(fx - float(x0), 0.0f, 1.0f);
        const float wy = clampf(fy - float(y0), 0.0f, 1.0f);
        const float top = grid.gain(grid.tile(x0, y0)) +
                          wx * (grid.gain(grid.tile(x1, y0)) - grid.gain(grid.tile(x0, y0)));
        const float bottom = grid.gain(grid.tile(x0, y1)) +
                             wx * (grid.gain(grid.tile(x1, y1)) - grid.gain(grid.tile(x0, y1)));
        const float gain = (top + wy * (bottom - top)) * grid.whole[1];
        const PixelIndex s = PixelIndex(y) * layout.width + x;
        const Float3 c = {rgbOut[3 * s], rgbOut[3 * s + 1], rgbOut[3 * s + 2]};
        const bool scaled =
            filterKey[layout.index(x, y)] >= 0 &&
            luminance(c) <= grid.threshold(grid.tile(x / kEnergyTile, y / kEnergyTile));
        const float k = scaled ? gain : 1.0f;
        rgbOut[3 * s] = c.x * k;
        rgbOut[3 * s + 1] = c.y * k;
        rgbOut[3 * s + 2] = c.z * k;
    }
};

}  // namespace rtd
