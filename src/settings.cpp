#include "rtdenoise/settings.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "methods/learned_weights.h"
#include "rtdenoise/error.h"
#include "tuning.h"

namespace rtd {
namespace {

void require(bool ok, const std::string& what) {
    if (!ok) throw Error(ErrorCode::InvalidArgument, "invalid setting: " + what);
}
bool positive(float v) {
    return std::isfinite(v) && v > 0.0f;
}
void requireSigma(float v, const std::string& name) {
    require(std::isfinite(v) && v >= kMinSigma,
            fmt::format("{} must be >= {:g} (got {:g})", name, kMinSigma, v));
}

}  // namespace

void validate(const DenoiserSettings& s) {
    requireSigma(s.edges.sigmaColor, "sigma-color");
    requireSigma(s.edges.sigmaNormal, "sigma-normal");
    requireSigma(s.edges.sigmaPlane, "sigma-plane");
    require(s.jbf.radius >= 0 && s.jbf.radius <= 64, "radius must be in [0, 64]");
    requireSigma(s.jbf.sigmaCoord, "sigma-coord");
    require(s.atrous.passes >= 1 && s.atrous.passes <= 10, "atrous-passes must be in [1, 10]");
    require(s.outlier.radius >= 1 && s.outlier.radius <= 15, "outlier-radius must be in [1, 15]");
    require(positive(s.outlier.k), "outlier-k must be > 0");
    require(std::isfinite(s.energy.cap) && s.energy.cap >= 1.0f, "energy-cap must be >= 1");
    require(std::isfinite(s.energy.frameShare) && s.energy.frameShare >= 0.0f &&
                s.energy.frameShare <= 1.0f,
            "energy-frame-share must be in [0, 1]");
    require(std::isfinite(s.temporal.alpha) && s.temporal.alpha >= 0.0f && s.temporal.alpha <= 1.0f,
            "alpha must be in [0, 1]");
    require(positive(s.temporal.clampK), "clamp-k must be > 0");
    require(s.temporal.clampRadius >= 1 && s.temporal.clampRadius <= 15,
            "clamp-radius must be in [1, 15]");
    require(positive(s.history.depthTolerance), "depth-tolerance must be > 0");
    require(positive(s.history.normalTolerance), "normal-tolerance must be > 0");
    require(std::isfinite(s.motion.scaleX) && std::isfinite(s.motion.scaleY),
            "motion-scale must be finite");
    auto unit = [](float v) { return std::isfinite(v) && v >= 0.0f && v <= 1.0f; };
    require(unit(s.svgf.alpha), "svgf-alpha must be in [0, 1]");
    require(unit(s.svgf.momentsAlpha), "svgf-moments-alpha must be in [0, 1]");
    requireSigma(s.svgf.sigmaDepth, "svgf-sigma-depth");
    requireSigma(s.svgf.sigmaNormal, "svgf-sigma-normal");
    requireSigma(s.svgf.sigmaLuminance, "svgf-sigma-luminance");
    require(s.svgf.iterations >= 1 && s.svgf.iterations <= 10,
            "svgf-iterations must be in [1, 10]");
    require(s.svgf.feedbackIteration >= 0 && s.svgf.feedbackIteration < s.svgf.iterations,
            "svgf-feedback must be in [0, svgf-iterations - 1]");
    require(std::isfinite(s.svgf.historyClampK) && s.svgf.historyClampK >= 0.0f,
            "svgf-clamp-k must be >= 0");
    require(s.svgf.maxHistory >= 1 && s.svgf.maxHistory <= 1000,
            "svgf-max-history must be in [1, 1000]");
    requireSigma(s.detail.sigmaDepth, "detail-sigma-depth");
    requireSigma(s.detail.sigmaNormal, "detail-sigma-normal");
    requireSigma(s.detail.sigmaLuminance, "detail-sigma-luminance");
    require(s.detail.iterations >= 1 && s.detail.iterations <= 10,
            "detail-iterations must be in [1, 10]");
    require(s.detail.specularIterations >= 1 && s.detail.specularIterations <= 10,
            "detail-specular-iterations must be in [1, 10]");
    require(s.detail.maxHistory >= 1 && s.detail.maxHistory <= 1000,
            "detail-max-history must be in [1, 1000]");
    require(s.detail.fastHistory >= 1 && s.detail.fastHistory <= s.detail.maxHistory,
            "detail-fast-history must be in [1, detail-max-history]");
    require(std::isfinite(s.detail.clampSigma) && s.detail.clampSigma >= 0.0f,
            "detail-clamp-sigma must be >= 0");
    require(unit(s.detail.momentsAlpha), "detail-moments-alpha must be in [0, 1]");
    require(positive(s.albedo.epsilon), "albedo-epsilon must be > 0");
    // A user's weights file is read and checked now, before any frame: the error names it.
    if (!s.learned.weights.empty()) learnedNetwork(s.learned.weights);
}

const char* toString(Method method) {
    switch (method) {
        case Method::Jbf:
            return "jbf";
        case Method::Atrous:
            return "atrous";
        case Method::Temporal:
            return "temporal";
        case Method::Svgf:
            return "svgf";
        case Method::Detail:
            return "detail";
        case Method::Learned:
            return "learned";
    }
    return "?";
}

const char* toString(SpatialFilter filter) {
    return filter == SpatialFilter::Jbf ? "jbf" : "atrous";
}

const char* toString(CpuIsa isa) {
    switch (isa) {
        case CpuIsa::Auto:
            return "auto";
        case CpuIsa::Scalar:
            return "scalar";
        case CpuIsa::Sse2:
            return "sse2";
        case CpuIsa::Avx2:
            return "avx2";
        case CpuIsa::Avx512:
            return "avx512";
    }
    return "?";
}

const char* toString(TilePasses tilePasses) {
    switch (tilePasses) {
        case TilePasses::Auto:
            return "auto";
        case TilePasses::On:
            return "on";
        case TilePasses::Off:
            return "off";
    }
    return "?";
}

const char* toString(DeviceType device) {
    switch (device) {
        case DeviceType::Cpu:
            return "cpu";
        case DeviceType::Cuda:
            return "cuda";
        case DeviceType::Auto:
            return "auto";
    }
    return "?";
}

}  // namespace rtd
