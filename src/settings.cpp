#include <cmath>
#include <string>

#include "rtdenoise/error.h"
#include "rtdenoise/settings.h"

namespace rtd {
namespace {

void require(bool ok, const std::string& what) {
    if (!ok) throw Error(ErrorCode::InvalidArgument, "invalid setting: " + what);
}
bool positive(float v) { return std::isfinite(v) && v > 0.0f; }

}  // namespace

void validate(const DenoiserSettings& s) {
    require(positive(s.edges.sigmaColor), "sigma-color must be > 0");
    require(positive(s.edges.sigmaNormal), "sigma-normal must be > 0");
    require(positive(s.edges.sigmaPlane), "sigma-plane must be > 0");
    require(s.jbf.radius >= 0 && s.jbf.radius <= 64, "jbf radius must be in [0, 64]");
    require(positive(s.jbf.sigmaCoord), "sigma-coord must be > 0");
    require(s.atrous.passes >= 1 && s.atrous.passes <= 10, "atrous passes must be in [1, 10]");
    require(s.outlier.radius >= 1 && s.outlier.radius <= 15, "outlier radius must be in [1, 15]");
    require(positive(s.outlier.k), "outlier k must be > 0");
    require(std::isfinite(s.temporal.alpha) && s.temporal.alpha >= 0.0f &&
                s.temporal.alpha <= 1.0f,
            "alpha must be in [0, 1]");
    require(positive(s.temporal.clampK), "clamp k must be > 0");
    require(s.temporal.clampRadius >= 1 && s.temporal.clampRadius <= 15,
            "clamp radius must be in [1, 15]");
}

const char* toString(Method method) {
    switch (method) {
        case Method::Jbf: return "jbf";
        case Method::Atrous: return "atrous";
        case Method::Temporal: return "temporal";
    }
    return "?";
}

const char* toString(SpatialFilter filter) {
    return filter == SpatialFilter::Jbf ? "jbf" : "atrous";
}

const char* toString(DeviceType device) {
    switch (device) {
        case DeviceType::Cpu: return "cpu";
        case DeviceType::Cuda: return "cuda";
        case DeviceType::Auto: return "auto";
    }
    return "?";
}

}  // namespace rtd
