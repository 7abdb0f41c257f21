// svgf: spatiotemporal variance-guided filtering (Schied et al. 2017), with an anti-lag history
// clamp. The illumination is accumulated over time with its luminance moments, its variance
// estimated (spatially where the history is short), then filtered by A-Trous iterations whose
// luminance term is scaled by that variance; one iteration's output is next frame's history.
//
//   ingest -> [outlier (+ clamp-window row sums)] -> geometry -> svgf-temporal -> svgf-variance
//          -> svgf-atrous0 .. svgf-atrous{iterations-1} -> [modulate]
//   svgf-temporal: reprojection (3x3 search where the bilinear taps fail) and accumulation (the
//   device picks: split on the CPU, one fused pass on a GPU)
#include <algorithm>

#include "methods/method.h"

namespace rtd {

SvgfFront declareSvgfFront(Pipeline& p, const DenoiserSettings& settings) {
    const SvgfSettings& sv = settings.svgf;
    const bool clamp = sv.historyClampK > 0.0f;
    FrameImages f = declareIngest(p, settings);
    // The history clamp's window sums of the despeckled image come with the firefly removal.
    ResourceId in = declareDespeckle(p, settings, f, clamp);
    const bool clampRowsHere = clamp && !settings.outlier.enabled;

    ResourceId derivatives = p.declare(floatImage("derivatives", 3));  // dz/dx, dz/dy, fwidth(n)
    ResourceId illumination = p.declare(floatImage("illumination", 3));
    // rgb + variance, the A-Trous input: written by the accumulation, revised by the variance.
    ResourceId variance = p.declare({.name = "illumination+variance",
                                     .planes = 4,
                                     .hasDebugView = true,
                                     .debugView = DebugView::Variance,
                                     .debugPlane = 3,
                                     .debugShow = DebugShow::StandardDeviation});
    ResourceId filterA = p.declare(floatImage("filterA", 4));
    ResourceId filterB = p.declare(floatImage("filterB", 4));
    ResourceId moments = p.declare(floatImage("moments", 2, Lifetime::History));
    ResourceId length = p.declare({.name = "historyLength",
                                   .lifetime = Lifetime::History,
                                   .hasDebugView = true,
                                   .debugView = DebugView::HistoryLength,
                                   .debugDivisor = float(sv.maxHistory)});
    // The feedback iteration's output: next frame's colour history.
    ResourceId feedback = p.declare(floatImage("feedback", 4, Lifetime::History));
    ResourceId validity = declareValidity(p);
    const SvgfTerms terms{sv.sigmaDepth, sv.sigmaNormal, sv.sigmaLuminance};

    // Derivatives read 1 pixel away; the reprojection's 3x3 taps reach 2 past the screen.
    p.addPass("geometry", StepKind::Geometry, gbufferReads(f), {derivatives}, 2,
              [f, derivatives](const PassContext& c) {
                  c.device().run(GeometryStep{{gbuffer(c, f), c.planeSet(derivatives)}});
              });

    const HistoryTest test = historyTest(settings.history);
    std::vector<ResourceId> temporalOut = {illumination, moments, length, variance, validity};
    if (clampRowsHere) temporalOut.push_back(f.windowSums);
    p.addPass("svgf-temporal", StepKind::SvgfTemporalStage,
              with(reprojectionReads(p, f), {derivatives, previous(feedback), previous(moments),
                                             previous(length), in, f.windowSums}),
              temporalOut, std::max(2, kSvgfWindowRadius), [=](const PassContext& c) {
                  GBufferView g = gbuffer(c, f);
                  const FrameBinding& frame = c.frame();
                  SvgfReprojectKernel reproject{g,
                                                previousGeometry(c, f),
                                                c.objects(),
                                                frame.objectCount,
                                                c.planeSet(derivatives),
                                                test,
                                                c.planeSet(previous(feedback)),
                                                c.planeSet(previous(moments)),
                                                c.floats(previous(length)),
                                                {},
                                                c.bytes(validity),
                                                frame.hasHistory};
                  SvgfAccumulateKernel accumulate{g,
                                                  c.planes(in),
                                                  c.planeSet(f.windowSums),
                                                  kSvgfWindowRadius,
                                                  sv.historyClampK,
                                                  {},
                                                  c.bytes(validity),
                                                  c.planes(illumination),
                                                  c.planeSet(moments),
                                                  c.floats(length),
                                                  c.planeSet(variance),
                                                  sv.alpha,
                                                  sv.momentsAlpha,
                                                  float(sv.maxHistory)};
                  c.device().run(SvgfTemporalStageStep{reproject, accumulate, clampRowsHere});
              });

    // Short histories only (block-sparse): the accumulation wrote the rest. It uses Falcor's
    // wider luminance tolerance: there is no variance yet.
    SvgfTerms wide = terms;
    wide.sigmaLuminance = 10.0f;
    constexpr float kShortHistory = 4.0f;  // frames: below, estimate spatially
    p.addPass("svgf-variance", StepKind::SvgfVariance,
              with(gbufferReads(f), {illumination, moments, length, derivatives, variance}),
              {variance}, kSvgfWindowRadius, [=](const PassContext& c) {
                  c.device().run(SvgfVarianceStep{{gbuffer(c, f), c.planeSet(derivatives),
                                                   c.planes(illumination), c.planeSet(moments),
                                                   c.floats(length), c.planeSet(variance), wide,
                                                   kShortHistory}});
              });

    return {f, derivatives, variance, length, feedback, filterA, filterB, terms};
}

FrameImages declareSvgf(Pipeline& p, const DenoiserSettings& settings) {
    const SvgfSettings& sv = settings.svgf;
    const SvgfFront s = declareSvgfFront(p, settings);
    // The iterations read the variance pass's output (kept for the debug view); the feedback
    // iteration writes next frame's colour history.
    declareGuidedIterations(p, s.images, "svgf-atrous", s.derivatives, s.illumination, s.filterA,
                            s.filterB, sv.iterations, s.terms, sv.feedbackIteration, s.feedback);
    return s.images;
}

}  // namespace rtd
