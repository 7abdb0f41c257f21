// detail: SVGF's variance-guided filter over a history that keeps the detail. The colour history
// is the accumulated, unfiltered illumination (SVGF feeds a blurred iteration back, which bakes
// the blur into every later frame), kept twice as in NVIDIA NRD's ReLAX: a slow history of up to
// max-history frames and a fast one of up to fast-history frames, to which the slow one is
// clamped (lighting changes). The A-Trous iterations' luminance tolerance follows the variance
// of the accumulated mean, so the filter narrows as a pixel's history grows; pixels with a short
// history (disocclusions, lighting changes) get SVGF's 7x7 spatial estimate first.
//
//   ingest -> [outlier] -> geometry -> detail-temporal -> detail-clamp -> detail-variance
//          -> detail-atrous0 .. detail-atrous{iterations-1} (the last one modulated)
//   detail-temporal: reprojection of both histories (3x3 search where the bilinear taps fail),
//   accumulation (scaled by the caller's confidence where given)
#include "methods/method.h"

namespace rtd {

FrameImages declareDetail(Pipeline& p, const DenoiserSettings& settings) {
    const DetailSettings& d = settings.detail;
    FrameImages f = declareIngest(p, settings);
    ResourceId in = declareDespeckle(p, settings, f);

    ResourceId derivatives = p.declare(floatImage("derivatives", 3));  // dz/dx, dz/dy, fwidth(n)
    ResourceId slow = p.declare(floatImage("slowHistory", 3, Lifetime::History));
    ResourceId fast = p.declare(floatImage("fastHistory", 3, Lifetime::History));
    ResourceId moments = p.declare(floatImage("moments", 2, Lifetime::History));
    ResourceId length = p.declare({.name = "historyLength",
                                   .lifetime = Lifetime::History,
                                   .hasDebugView = true,
                                   .debugView = DebugView::HistoryLength,
                                   .debugDivisor = float(d.maxHistory)});
    // rgb + variance, the A-Trous input.
    ResourceId variance = p.declare({.name = "illumination+variance",
                                     .planes = 4,
                                     .hasDebugView = true,
                                     .debugView = DebugView::Variance,
                                     .debugPlane = 3,
                                     .debugShow = DebugShow::StandardDeviation});
    ResourceId filterA = p.declare(floatImage("filterA", 4));
    ResourceId filterB = p.declare(floatImage("filterB", 4));
    ResourceId validity = declareValidity(p);
    const SvgfTerms terms{d.sigmaDepth, d.sigmaNormal, d.sigmaLuminance};

    p.addPass("geometry", StepKind::Geometry, gbufferReads(f), {derivatives}, 2,
              [f, derivatives](const PassContext& c) {
                  c.device().run(GeometryStep{{gbuffer(c, f), c.planeSet(derivatives)}});
              });

    const HistoryTest test = historyTest(settings.history);
    p.addPass("detail-temporal", StepKind::DetailTemporalStage,
              with(reprojectionReads(p, f), {derivatives, previous(slow), previous(fast),
                                             previous(moments), previous(length), in}),
              {slow, fast, moments, length, validity}, 2, [=](const PassContext& c) {
                  GBufferView g = gbuffer(c, f);
                  const FrameBinding& frame = c.frame();
                  DetailReprojectKernel reproject{g,
                                                  previousGeometry(c, f),
                                                  c.objects(),
                                                  frame.objectCount,
                                                  c.planeSet(derivatives),
                                                  test,
                                                  c.planes(previous(slow)),
                                                  c.planes(previous(fast)),
                                                  c.planeSet(previous(moments)),
                                                  c.floats(previous(length)),
                                                  {},
                                                  c.bytes(validity),
                                                  frame.hasHistory};
                  DetailAccumulateKernel accumulate{g,
                                                    c.planes(in),
                                                    {},
                                                    c.bytes(validity),
                                                    frame.confidence,
                                                    c.planes(slow),
                                                    c.planes(fast),
                                                    c.planeSet(moments),
                                                    c.floats(length),
                                                    float(d.maxHistory),
                                                    float(d.fastHistory),
                                                    d.momentsAlpha};
                  c.device().run(DetailTemporalStageStep{reproject, accumulate});
              });

    // The anti-lag runs with a caller's confidence too: the renderer's gradients (A-SVGF) take
    // most of a switched light's change, not all. The fast history's window sums in windowSums
    // (free after the firefly removal).
    ResourceId lagScale = p.declare(floatImage("lagScale", 1));
    ResourceId currentSums = p.declare(floatImage("currentSums", 3));
    constexpr int kWindow = DetailClampKernel::kRadius;
    p.addPass("detail-clamp", StepKind::DetailClamp,
              with(gbufferReads(f), {in, fast, slow, moments, length}),
              {fast, slow, length, variance, lagScale, f.windowSums, currentSums}, kNarrowWindow,
              [=](const PassContext& c) {
                  const GBufferView g = gbuffer(c, f);
                  const bool antiLag = d.antiLag;
                  c.device().run(DetailClampStep{
                      {g, c.planes(fast), c.planeSet(f.windowSums), kWindow},
                      {g, c.planes(in), c.planeSet(currentSums), kWindow},
                      {g, c.planeSet(f.windowSums), c.planeSet(currentSums), c.planes(slow),
                       c.planeSet(moments), c.floats(length), c.planeSet(variance),
                       c.floats(lagScale), d.clampSigma, float(d.fastHistory), antiLag ? 1 : 0},
                      {c.layout(), c.planes(fast), c.floats(lagScale)}});
              });

    // Short histories only (block-sparse): SVGF's 7x7 estimate of the variance and colour, with
    // its wide luminance tolerance (there is no variance yet).
    SvgfTerms wide = terms;
    wide.sigmaLuminance = 10.0f;
    constexpr float kShortHistory = 4.0f;  // frames: below, estimate spatially
    p.addPass("detail-variance", StepKind::SvgfVariance,
              with(gbufferReads(f), {slow, moments, length, derivatives, variance}), {variance},
              kSvgfWindowRadius, [=](const PassContext& c) {
                  c.device().run(SvgfVarianceStep{
                      {gbuffer(c, f), c.planeSet(derivatives), c.planes(slow), c.planeSet(moments),
                       c.floats(length), c.planeSet(variance), wide, kShortHistory}});
              });

    declareGuidedIterations(p, f, "detail-atrous", derivatives, variance, filterA, filterB,
                            d.iterations, terms);
    return f;
}

}  // namespace rtd
