// Firefly removal as one tile pass (tile.h): the window statistics' row sums stay in the tile
// rather than going through 3 planes in memory (LuminanceRowSums, then Outlier). With
// ClampRadius > 0 (SVGF's history clamp) it also leaves the row sums of the despeckled colour
// over a (2 ClampRadius + 1)-pixel row window, as ColorRowSums would from the despeckled planes,
// for the temporal stage's column half: the despeckled colour of the tile's halo columns is
// computed in the tile too, so the pass replaces three.
//
// Results are those of the separate passes (the same sums in the same order, up to the
// compiler's reassociation). Pixels outside the image count as background: the separate passes'
// taps there read the border (ID -1), and their row sums outside the image stay 0.
#pragma once

#include "kernels/outlier.h"
#include "kernels/tile.h"
#include "kernels/window_sums.h"

namespace rtd {

template <int ClampRadius, int TileWidth = 32, int TileHeight = 8>
struct OutlierTile {
    static constexpr int kRadius = kNarrowWindow;  // the firefly window's largest radius
    static constexpr int kTileWidth = TileWidth, kTileHeight = TileHeight;
    static constexpr int kPhases = ClampRadius > 0 ? 4 : 3;

    // Phase 0: luminance and object mask over the tile and every halo (the inputs' footprint).
    static constexpr int kLoadU = -(ClampRadius + kRadius), kLoadV = -kRadius;
    static constexpr int kLoadWidth = TileWidth - 2 * kLoadU, kLoadHeight = TileHeight - 2 * kLoadV;
    // Phase 1: luminance row sums, for the columns whose despeckled colour is needed.
    static constexpr int kSumU = -ClampRadius, kSumV = -kRadius;
    static constexpr int kSumWidth = TileWidth - 2 * kSumU, kSumHeight = TileHeight - 2 * kSumV;
    static constexpr int kSumPlane = kSumWidth * kSumHeight;
    // Phase 2: the despeckled colour of the tile's rows, its clamp halo included.
    static constexpr int kKeepWidth = ClampRadius > 0 ? kSumWidth : 1;
    static constexpr int kKeepPlane = ClampRadius > 0 ? kSumWidth* TileHeight : 1;

    struct Shared {
        float luminance[kLoadWidth * kLoadHeight];
        float mask[kLoadWidth * kLoadHeight];  // 1 for object pixels, 0 for background
        float sums[3 * kSumPlane];             // count, sum, sum of squares
        float despeckled[3 * kKeepPlane];      // ClampRadius > 0 only
    };

    static constexpr PhaseExtent phaseExtent(int phase) {
        switch (phase) {
            case 0:
                return {kLoadU, kLoadV, kLoadWidth, kLoadHeight};
            case 1:
                return {kSumU, kSumV, kSumWidth, kSumHeight};
            case 2:
                return {ClampRadius > 0 ? kSumU : 0, 0, ClampRadius > 0 ? kSumWidth : TileWidth,
                        TileHeight};
            default:
                return {0, 0, TileWidth, TileHeight};
        }
    }

    GBufferView g;
    Planes3 in, out;
    PlaneSet clampSums;  // ColorRowSums' 7 planes; ClampRadius > 0 only
    int radius;          // the firefly window's, <= kRadius
    float k;
    float* above = nullptr;  // out, optional: as Outlier's

    template <int Phase>
    RTD_HOST_DEVICE RTD_INLINE void item(Shared& s, int tileX, int tileY, int u, int v) const {
        const Layout& L = g.layout;
        const int x = tileX + u, y = tileY + v;
        const bool rowInside = y >= 0 && y < L.height;
        const bool inside = rowInside && x >= 0 && x < L.width;
        const int load = (v - kLoadV) * kLoadWidth + (u - kLoadU);
        if constexpr (Phase == 0) {
            float l = 0.0f, m = 0.0f;
            if (inside) {
                PixelIndex i = L.index(x, y);
                m = foregroundMask(g.objectId[i]);
                l = luminance(in.load(i));
            }
            s.luminance[load] = l;
            s.mask[load] = m;
        } else if constexpr (Phase == 1) {
            // As LuminanceRowSums; rows outside the image sum to 0, as their planes stay.
            LuminanceSums row;
            if (rowInside)
                row = luminanceRowSums<kRadius>(
                    radius, [&](int dx) { return s.mask[load + dx]; },
                    [&](int dx) { return s.luminance[load + dx]; });
            row.storeTo(sumPlanes(s), sumIndex(u, v));
        } else if constexpr (Phase == 2) {
            const PlaneSet sums = sumPlanes(s);
            const int at = sumIndex(u, v);
            const PixelIndex i = L.index(x, y);
            // Read at a pixel of the image, then zeroed outside it per component: a select of a
            // whole Float3 is an aggregate the CPU's vectoriser gives up on (the phase ran scalar).
            // This phase's rows are the tile's own, so y >= 0 needs no clamp.
            const PixelIndex atImage =
                L.index(mini(maxi(x, 0), L.width - 1), mini(y, L.height - 1));
            Float3 c = in.load(atImage);
            c.x = inside ? c.x : 0.0f;
            c.y = inside ? c.y : 0.0f;
            c.z = inside ? c.z : 0.0f;
            const FireflyLimit f =
                fireflyLimit(luminance(c), columnSum<kRadius>(sums, 0, at, kSumWidth, radius),
                             columnSum<kRadius>(sums, 1, at, kSumWidth, radius),
                             columnSum<kRadius>(sums, 2, at, kSumWidth, radius), k);
            Float3 d =
                despeckle(c, s.mask[load] > 0.0f, f, brightLikeItsObject(g, in, atImage, f.limit));
            if (inside && u >= 0 && u < TileWidth) {
                out.store(i, d);
                if (above) above[i] = aboveLimit(c, s.mask[load] > 0.0f, f);
            }
            if constexpr (ClampRadius > 0) keptPlanes(s).store(keepIndex(u, v), d);
        } else {
            static_assert(Phase == 3 && ClampRadius > 0, "phase 3: the clamp's row sums");
            // As ColorRowSums over the despeckled colour (radius ClampRadius).
            const int keep = keepIndex(u, v);
            const Planes3 kept = keptPlanes(s);
            ColorSums row = colorRowSums<ClampRadius>(
                ClampRadius, [&](int dx) { return s.mask[load + dx]; },
                [&](int dx) { return kept.load(keep + dx); });
            if (inside) row.storeTo(clampSums, L.index(x, y));
        }
    }

  private:
    // Shared's arrays as planes, for the helpers that take planes.
    RTD_HOST_DEVICE static PlaneSet sumPlanes(Shared& s) { return {s.sums, kSumPlane}; }
    RTD_HOST_DEVICE static Planes3 keptPlanes(Shared& s) { return {s.despeckled, kKeepPlane}; }
    RTD_HOST_DEVICE static constexpr int sumIndex(int u, int v) {
        return (v - kSumV) * kSumWidth + (u - kSumU);
    }
    RTD_HOST_DEVICE static constexpr int keepIndex(int u, int v) {
        return v * kKeepWidth + (u - kSumU);
    }
};
// The other methods' firefly removal (its narrow window, radius <= 3: every default).
using OutlierTileKernel = OutlierTile<0>;
// SVGF's, with its history clamp's row sums (radius kSvgfWindowRadius, svgf.h).
using OutlierClampTileKernel = OutlierTile<3>;

}  // namespace rtd
