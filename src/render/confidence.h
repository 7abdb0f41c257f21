// History confidence from temporal gradients, the A-SVGF way (Schied et al. 2018, "Gradient
// Estimation for Real-Time Adaptive Temporal Filtering"): where re-shading last frame's sample
// in this frame's scene changes its value, the lighting changed and the history is stale.
#pragma once

#include "render/path_tracer.h"
#include "render/scene.h"
#include "rtdenoise/image.h"

namespace rtd::render {

struct ConfidenceSettings {
    // [0, 16] strata on each side of a stratum whose gradients are pooled (2: 5x5 strata, 15x15
    // pixels): 25 one-sample gradients make a ratio that noise barely moves.
    int filterRadius = 2;
    // [0, inf) k in confidence = 1 - k * lambda: 1 maps a light switched off (lambda near 1) to 0
    // and a 10% change of the lighting to 0.9, as A-SVGF's history weight does.
    float gain = 1.0f;
};

// The confidence of frame `trace.frameIndex` (>= 1; scene `current`, G-buffer `gbuffer`) in the
// history of the frame before it (scene `previous`): 1 channel in [0, 1], one value per 3x3
// pixel stratum. In each stratum of the previous frame one pixel (a hash of seed, frame and
// stratum) has its 1-spp beauty sample traced again in the previous scene and, with the same
// random numbers, from its first hit's surface point forward-projected into the current scene
// (traceGradientSamples); the pair lands in the stratum that point falls in now. lambda =
// sum |L_new - L_old| / sum max(L_new, L_old) (luminance) over the (2 filterRadius + 1)^2
// neighbouring strata on the same surface (normals within ~25 degrees, depths within 10%); 0
// where none has light. confidence = clamp(1 - gain lambda). Costs 2 paths per 9 pixels.
Image historyConfidence(const Scene& previous, const Scene& current, const Frame& gbuffer,
                        const TraceSettings& trace, const ConfidenceSettings& settings = {});

}  // namespace rtd::render
