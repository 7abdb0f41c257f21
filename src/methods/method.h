// The methods (one file each: jbf.cpp, atrous.cpp, temporal.cpp, svgf.cpp) and the passes they
// share (shared_passes.cpp): the ingest, the firefly removal, the spatial filters, the modulation.
#pragma once

#include <vector>

#include "methods/pipeline.h"
#include "rtdenoise/settings.h"

namespace rtd {

// What the ingest writes: every method's inputs in the device's padded planar layout.
struct FrameImages {
    ResourceId noisy;       // 3 planes: the beauty, demodulated by the albedo
    ResourceId albedo;      // 3 planes: the factor (1 without an albedo)
    ResourceId guide;       // history, 4 planes: normal and depth (the device picks the layout)
    ResourceId position;    // 3 planes
    ResourceId objectId;    // history, int32: -1 for background and the border
    ResourceId filterKeys;  // int32: GBufferView::filterKey
    ResourceId inputFlags;  // bytes, unpadded: IngestKernel::inputFlags
    ResourceId windowSums;  // 7 planes: window statistics of the firefly removal and clamps
    ResourceId motion;      // temporal methods, 3 planes: MotionIngestKernel's (frames with motion)
    ResourceId energyInput;  // 1 plane: the input's luminance (EnergySettings::keep)
};

// What the frames give beyond the required buffers, where it changes the passes.
struct MethodInputs {
    bool specular = false;  // the split signal (FrameBinding::specular): detail filters it apart
};

// Declares `settings.method` into `pipeline`; returns the ingest's images.
FrameImages declareMethod(Pipeline& pipeline, const DenoiserSettings& settings,
                          const MethodInputs& inputs = {});

FrameImages declareJbf(Pipeline& pipeline, const DenoiserSettings& settings);
FrameImages declareAtrous(Pipeline& pipeline, const DenoiserSettings& settings);
FrameImages declareTemporal(Pipeline& pipeline, const DenoiserSettings& settings);
FrameImages declareSvgf(Pipeline& pipeline, const DenoiserSettings& settings);
// mix: the learned method's network, which replaces detail's A-Trous chain (its diffuse signal's)
// with a per-pixel mix of the chain's levels (learned.cpp).
FrameImages declareDetail(Pipeline& pipeline, const DenoiserSettings& settings,
                          const MethodInputs& inputs, const LearnedNetwork* mix = nullptr);
FrameImages declareLearned(Pipeline& pipeline, const DenoiserSettings& settings,
                           const MethodInputs& inputs);

// What the learned mix reads of detail's passes.
struct LearnedLevels {
    ResourceId derivatives;       // 3 planes: dz/dx, dz/dy, fwidth(n)
    ResourceId illumination;      // rgb + variance: detail's variance pass's, the filters' input
    ResourceId length;            // history: frames accumulated per pixel
    ResourceId filterA, filterB;  // 4 planes each, free for the levels
    SvgfTerms terms;
};
// The five A-Trous levels of `illumination`, each kept, and the network's mix of the six
// candidates (demodulated, 3 planes): returns the mix's image.
ResourceId declareLearnedMix(Pipeline& pipeline, const FrameImages& images,
                             const LearnedLevels& levels, const LearnedNetwork& network);

// svgf's passes up to its A-Trous iterations (svgf.cpp).
struct SvgfFront {
    FrameImages images;
    ResourceId derivatives;   // 3 planes: dz/dx, dz/dy, fwidth(n)
    ResourceId illumination;  // rgb + variance: the accumulated illumination, the filters' input
    ResourceId length;        // history: frames accumulated per pixel
    ResourceId feedback;      // history: the feedback iteration's output (next frame's colour)
    ResourceId filterA, filterB;  // 4 planes each: the iterations' ping-pong images
    SvgfTerms terms;
};
SvgfFront declareSvgfFront(Pipeline& pipeline, const DenoiserSettings& settings);

// ---- shared passes ----

// The frame's images and the "ingest" pass that writes them.
FrameImages declareIngest(Pipeline& pipeline, const DenoiserSettings& settings);
// The resources a GBufferView reads (this frame's guide, position, IDs and filter keys).
std::vector<ResourceId> gbufferReads(const FrameImages& images);
std::vector<ResourceId> with(std::vector<ResourceId> ids, std::initializer_list<ResourceId> more);
GBufferView gbuffer(const PassContext& context, const FrameImages& images);
// What a reprojection reads besides its history: this frame's G-buffer, the last frame's IDs and
// guide, the matrices and the frame (object count, whether there is history).
std::vector<ResourceId> reprojectionReads(const Pipeline& pipeline, const FrameImages& images);
// Per pixel, why history was used or not (ReprojectionCode): the Reprojection debug view.
ResourceId declareValidity(Pipeline& pipeline);
// The last frame's IDs and guide, for the history test.
PreviousGeometry previousGeometry(const PassContext& context, const FrameImages& images);
HistoryTest historyTest(const HistorySettings& settings);

// The "outlier" pass where firefly removal is on; returns the image the filters read (the
// despeckled one, or the noisy one). clampSums: it also leaves the colour row sums of its result
// over SVGF's clamp window in windowSums. signal: a suffix of its names (a second signal's).
ResourceId declareDespeckle(Pipeline& pipeline, const DenoiserSettings& settings,
                            const FrameImages& images, bool clampSums = false,
                            const std::string& signal = "", ResourceId above = {});
// The spatial filter of `in` into `out`; modulateLast: its last A-Trous level writes the output
// (times the albedo) instead. `scratch`: the A-Trous levels' second image.
void declareSpatialFilter(Pipeline& pipeline, const DenoiserSettings& settings,
                          const FrameImages& images, SpatialFilter filter, ResourceId in,
                          ResourceId out, ResourceId scratch, bool modulateLast);
// The variance-guided A-Trous iterations (svgf's and detail's) of `in` (rgb + variance), named
// prefix0, prefix1, ...: they ping-pong between filterA and filterB, iteration
// `feedbackIteration` (-1: none) writing `feedback` instead (and the next one reading it from
// there); the last one writes the output times the albedo, unless it is the feedback one: then
// a modulate pass follows. toOutput false: the last one writes filterA or filterB like the
// others. onlyKeyed: pixels whose filter key is < 0 may be skipped, their outputs left
// unspecified (the split signal's specular passes). levels: where given (one per iteration,
// with toOutput false), iteration i writes levels[i] instead of the ping-pong, so every level is
// kept (the learned mix). Returns what the last one wrote.
ResourceId declareGuidedIterations(Pipeline& pipeline, const FrameImages& images,
                                   const std::string& prefix, ResourceId derivatives, ResourceId in,
                                   ResourceId filterA, ResourceId filterB, int iterations,
                                   SvgfTerms terms, int feedbackIteration = -1,
                                   ResourceId feedback = {}, bool toOutput = true,
                                   bool onlyKeyed = false,
                                   const std::vector<ResourceId>& levels = {});
// "modulate": the albedo multiplied back into `source` (its first three planes), written into
// the output.
void declareModulate(Pipeline& pipeline, const FrameImages& images, ResourceId source);

// An image of `planes` float planes, zero (its border too).
ResourceDecl floatImage(std::string name, int planes, Lifetime lifetime = Lifetime::Frame);

}  // namespace rtd
