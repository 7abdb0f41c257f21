// atrous: one frame, the edge-avoiding A-Trous wavelet filter (Dammertz et al. 2010); its last
// level writes the output times the albedo.
//
//   ingest -> [outlier] -> atrous0 .. atrous{passes-1}
#include "methods/method.h"

namespace rtd {

FrameImages declareAtrous(Pipeline& p, const DenoiserSettings& settings) {
    FrameImages f = declareIngest(p, settings);
    ResourceId in = declareDespeckle(p, settings, f);
    ResourceId filtered = p.declare(floatImage("filtered", 3));
    ResourceId scratch = p.declare(floatImage("scratch", 3));
    declareSpatialFilter(p, settings, f, SpatialFilter::Atrous, in, filtered, scratch, true);
    return f;
}

}  // namespace rtd
