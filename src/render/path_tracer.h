// CPU path tracer over the analytic scenes of scene.h: next-event estimation towards area lights
// and the sun combined with BSDF sampling by multiple importance sampling (power heuristic); the
// sky and unsampled emitters are found by BSDF sampling alone; Russian
// roulette, OpenMP over rows. Random numbers come from a hash of (seed, stream, frame, pixel,
// sample), so a frame is the same whatever the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "render/scene.h"
#include "rtdenoise/image.h"

namespace rtd::render {

struct TraceSettings {
    int width = 320;
    int height = 240;
    int samplesPerPixel = 1;
    // Surface interactions per path: emission is counted at the 1st..maxDepth-th hit, so a
    // white furnace of albedo a and emission Le gives Le (1 - a^maxDepth) / (1 - a).
    int maxDepth = 8;
    std::uint32_t seed = 1;
    int frameIndex = 0;
    std::uint32_t stream = 0;  // independent random numbers per stream (0 beauty, 1 reference)
};

// Stream of the noisy beauty and of the reference: the reference never reuses the beauty's
// random numbers.
constexpr std::uint32_t kBeautyStream = 0;
constexpr std::uint32_t kReferenceStream = 1;

// Mean radiance of `samplesPerPixel` camera paths per pixel, each through a uniformly jittered
// point of the pixel; 3 channels. Nothing is clamped; a non-finite sample counts as 0.
// With specularOut, also the split signal into it (3 channels, the same paths): the part of the
// radiance that left each path's first surface through its glossy (Phong or GGX) lobe, split
// exactly by lobe there (next-event estimation at the first surface by BSDF term, everything after
// it in the ratio f_specular / f at the sampled direction). Emission at the first hit and
// background seen by the camera are diffuse; the diffuse part is the radiance minus it. The
// returned radiance (and the random numbers) are the same with or without it.
Image renderRadiance(const Scene& scene, const TraceSettings& settings,
                     Image* specularOut = nullptr);

struct PixelCoord {
    int x = 0;
    int y = 0;
};

// A-SVGF's gradient sample of a pixel: last frame's camera sample 0 (the random numbers of
// `last`: seed, beauty stream, frameIndex of the previous frame) traced in its scene, and the same
// path re-shaded in the current scene from where its first hit's surface point is now (moved
// with its object, seen from the current camera). Invalid where that path starts on background,
// or the point is now off-screen or hidden.
struct GradientSample {
    bool valid = false;
    PixelCoord pixel;  // where the point is now
    Vec3 before;       // the radiance last frame (what the beauty added up)
    Vec3 now;          // the same random numbers from the same surface point, now
};
std::vector<GradientSample> traceGradientSamples(const Scene& previous, const Scene& current,
                                                 const TraceSettings& last,
                                                 const std::vector<PixelCoord>& pixels);

// G-buffer from the primary ray through each pixel centre: normal (world, unit, facing the
// camera), position (the camera position on background), depth (camera z, 0 on background),
// object ID (-1 on background), albedo (diffuse texture times (1 - specular) plus specular times
// the lobe's colour, white for Phong; 0 on background) and the matrices. The beauty is left empty.
// With split (the split signal's G-buffer), also roughness: the first surface's linear roughness
// (GGX: the material's, at least 0.02; Phong exponent n as GGX alpha = sqrt(2 / (n + 2)),
// roughness = sqrt(alpha); 1 without a glossy lobe, 0 on background) and
// hitDistance the distance along the mirror reflection of the pixel-centre ray about the normal
// (deterministic, noise-free; 0 on a miss, on background and without a glossy lobe).
Frame renderGBuffer(const Scene& scene, int width, int height, bool split = false);

// Both of the above: one frame of a sequence; with split also frame.specular (renderRadiance's
// specularOut at the beauty's samples) and the split G-buffer.
Frame renderFrame(const Scene& scene, const TraceSettings& settings, bool split = false);

}  // namespace rtd::render
