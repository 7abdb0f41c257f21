// jbf: one frame, the brute-force joint bilateral filter, then the albedo multiplied back.
//
//   ingest -> [outlier] -> jbf -> modulate
#include "methods/method.h"

namespace rtd {

FrameImages declareJbf(Pipeline& p, const DenoiserSettings& settings) {
    FrameImages f = declareIngest(p, settings);
    ResourceId in = declareDespeckle(p, settings, f);
    ResourceId filtered = p.declare(floatImage("filtered", 3));
    declareSpatialFilter(p, settings, f, SpatialFilter::Jbf, in, filtered, {}, false);
    // A pass of its own: under 1 % of the JBF's time.
    declareModulate(p, f, filtered);
    return f;
}

}  // namespace rtd
