// temporal: the course assignment's pipeline. Each frame is filtered spatially (JBF or A-Trous),
// then blended with the back-projected history, which is clamped to the current neighbourhood's
// mu +- k sigma first.
//
//   ingest -> [outlier] -> jbf | atrous0..4 -> temporal
//   temporal: clamp-window row sums, history test slopes, back-projection, accumulation (the
//   device picks: split on the CPU, one fused pass on a GPU)
#include <algorithm>

#include "methods/method.h"

namespace rtd {

FrameImages declareTemporal(Pipeline& p, const DenoiserSettings& settings) {
    const TemporalSettings& t = settings.temporal;
    FrameImages f = declareIngest(p, settings);
    ResourceId in = declareDespeckle(p, settings, f);
    ResourceId filtered = p.declare(floatImage("filtered", 3));
    ResourceId scratch;
    if (t.spatialFilter == SpatialFilter::Atrous) scratch = p.declare(floatImage("scratch", 3));
    declareSpatialFilter(p, settings, f, t.spatialFilter, in, filtered, scratch, false);

    ResourceId history = p.declare(floatImage("history", 3, Lifetime::History));
    ResourceId validity = declareValidity(p);
    const HistoryTest test = historyTest(settings.history);
    const float alpha = t.alpha, k = t.clampK;
    const int radius = t.clampRadius;
    // The slopes read 1 pixel away, the reprojection's taps reach 2 past the screen.
    const int reach = std::max(2, radius <= kNarrowWindow ? kNarrowWindow : kWideWindow);
    p.addPass("temporal", StepKind::TemporalStage,
              with(reprojectionReads(p, f), {previous(history), filtered, f.albedo}),
              {f.windowSums, history, validity, p.output()}, reach, [=](const PassContext& c) {
                  GBufferView g = gbuffer(c, f);
                  const FrameBinding& frame = c.frame();
                  ReprojectKernel reproject{g,
                                            previousGeometry(c, f),
                                            c.objects(),
                                            frame.objectCount,
                                            {},
                                            test,
                                            c.planes(previous(history)),
                                            {},
                                            c.bytes(validity),
                                            frame.hasHistory};
                  AccumulateModulatedKernel accumulate{g,
                                                       c.planeSet(f.windowSums),
                                                       c.planes(filtered),
                                                       {},
                                                       c.bytes(validity),
                                                       c.planes(history),
                                                       alpha,
                                                       k,
                                                       radius,
                                                       c.planes(f.albedo),
                                                       c.output()};
                  c.device().run(TemporalStageStep{reproject, accumulate});
              });
    return f;
}

}  // namespace rtd
