// Settings of every method. Each field: [range] meaning. Defaults are the course assignment's
// (shared/seeds/001): alpha 0.2, sigma_plane 0.1, sigma_color 0.6, sigma_normal 0.1,
// sigma_coord 32, k 1.
#pragma once

#include <string>

namespace rtd {

enum class Method {
    Jbf,       // single frame: brute-force joint bilateral filter
    Atrous,    // single frame: edge-avoiding A-Trous wavelet filter
    Temporal,  // the assignment's pipeline: spatial filter, back-projection, accumulation
    Svgf,      // spatiotemporal variance-guided filtering (Schied et al. 2017)
    Detail,    // detail-preserving history: SVGF's filter over unfiltered, clamped history
    Learned,   // svgf's filter levels weighed per pixel by a small trained network
};

// Whether the method keeps a history (reprojects the last frame's).
inline bool usesHistory(Method method) {
    return method == Method::Temporal || method == Method::Svgf || method == Method::Detail ||
           method == Method::Learned;
}

enum class SpatialFilter { Jbf, Atrous };

// The smallest sigma (and svgf sigma-normal) validate() accepts. Below it a filter keeps every
// pixel as it is anyway, and far below it 1 / (2 sigma^2) overflows, which made the centre tap's
// weight 0 * inf (a black image).
constexpr float kMinSigma = 1e-6f;

enum class DeviceType { Cpu, Cuda, Auto };

// Edge-stopping terms shared by the JBF and the A-Trous filter.
struct EdgeStoppingSettings {
    float sigmaColor =
        0.6f;  // [>=kMinSigma] colour distance (RGB, linear) at which weight falls to e^-0.5
    float sigmaNormal =
        0.1f;  // [>=kMinSigma] angle between normals (radians), D_normal = acos(n_i . n_j)
    float sigmaPlane = 0.1f;      // [>=kMinSigma] D_plane = n_i . (p_j - p_i) / |p_j - p_i|
    bool separateObjects = true;  // pixels of another object ID never contribute (an edge the
                                  // geometry terms alone can miss: touching coplanar objects)
};

struct JbfSettings {
    int radius = 16;  // [0, 64] half width of the square kernel: (2r+1)^2 taps
    float sigmaCoord =
        32.0f;  // [>=kMinSigma] pixel distance at which the spatial weight falls to e^-0.5
};

struct AtrousSettings {
    int passes = 5;  // [1, 10] wavelet levels; pass i uses stride 2^i on the previous pass's output
};

struct OutlierSettings {
    bool enabled = true;  // remove fireflies before filtering
    int radius = 3;       // [1, 15] window half width ((2r+1)^2 pixels)
    float k = 2.0f;       // [>0] luminance is clamped to mean + k * stddev of the window
};

// The energy restoration (every method, last): the light the robust steps discard (firefly
// removal, history clamps, luminance edge-stopping) is given back at a coarse scale, per 16x16
// tile, from the noisy input's mean over the frames (docs/energy.md).
struct EnergySettings {
    bool keep = true;    // scale the output so that each tile keeps the input's light
    float cap = 128.0f;  // [>=1] input samples above cap x the local mean count as that
                         // much (a quarter of it in a first frame): a lone firefly cannot
                         // brighten its tiles much
    float frameShare = 0.005f;  // [0, 1] the light over the tiles' cap is given back over the
                                // whole frame, each sample lifting it by at most this share
                                // (0: not given back)
};

// Which previous-frame pixels may serve as history (temporal and svgf methods).
struct HistorySettings {
    bool geometryTests = true;      // also require depth and normal to agree (else: object ID only)
    float depthTolerance = 10.0f;   // [>0] reject if |dz| > tolerance * (fwidth(z) + 0.01)
    float normalTolerance = 16.0f;  // [>0] reject if |dn| > tolerance * (fwidth(n) + 0.01)
};

// How a frame's motion vectors (FrameView::motion) map to rtdenoise's convention, NVIDIA NRD's:
// previous pixel = current pixel + motion, in pixels, y down.
struct MotionSettings {
    float scaleX = 1.0f;  // [finite] multiplies x: 1 for pixels, the width for UV units
    float scaleY = 1.0f;  // [finite] multiplies y: -1 (or -height in UV units) where y points up
    bool currentMinusPrevious = false;  // the vectors point from the previous frame to this one
                                        // (motion = current - previous): their sign is flipped
};

struct SvgfSettings {
    float alpha = 0.2f;           // [0, 1] colour: weight of the current frame, at least 1/history
    float momentsAlpha = 0.2f;    // [0, 1] the same for the luminance moments
    float sigmaDepth = 1.0f;      // [>=kMinSigma] depth tolerance relative to the local depth slope
    float sigmaNormal = 128.0f;   // [>=kMinSigma] exponent of max(0, n.n')
    float sigmaLuminance = 4.0f;  // [>=kMinSigma] luminance tolerance in standard deviations
    int iterations = 5;           // [1, 10] A-Trous iterations, stride 2^i
    int feedbackIteration = 0;    // [0, iterations-1] its output becomes next frame's colour
                                  // history (0: the first iteration, the paper's choice)
    int maxHistory = 32;          // [1, 1000] history length cap (frames)
    float historyClampK = 1.5f;   // [>=0] anti-lag: colour history clamped to mu +- k sigma of
                                  // the current noisy 7x7 neighbourhood, and history shortened
                                  // where it is off that neighbourhood's mean (0: off, the
                                  // paper; 1.5 chosen on the rendered scenes, see README)
};

// The detail method (methods/detail.cpp): the colour history is the accumulated unfiltered signal
// (a long "slow" one and a short "fast" one beside it, as in NVIDIA NRD's ReLAX); the slow one is
// clamped to the fast one's neighbourhood, and the A-Trous filter's luminance tolerance follows
// the variance of the accumulated mean, so it narrows as the history grows.
struct DetailSettings {
    float sigmaDepth = 1.0f;      // [>=kMinSigma] depth tolerance relative to the local depth slope
    float sigmaNormal = 128.0f;   // [>=kMinSigma] exponent of max(0, n.n')
    float sigmaLuminance = 2.8f;  // [>=kMinSigma] luminance tolerance in standard deviations of
                                  // the accumulated mean
    int iterations = 5;           // [1, 10] A-Trous iterations, stride 2^i
    int specularIterations = 1;   // [1, 10] A-Trous iterations of the split signal's specular
                                  // part (its lobes are at most 0.45 rough: the history does most)
    int maxHistory = 32;          // [1, 1000] slow history cap (frames)
    int fastHistory = 6;          // [1, max-history] fast history cap (frames): the clamp's guide
    float clampSigma = 1.5f;      // [>=0] slow history clamped to the fast one's 5x5 mean +- this
                                  // many standard deviations (0: no clamp)
    float momentsAlpha = 0.2f;    // [0, 1] luminance moments: weight of the current frame
    bool antiLag = true;          // where the current frame's 5x5 mean leaves the fast history's,
                                  // follow it (lighting changed); with a confidence input too
};

// Albedo demodulation (every method): where a frame has an albedo, filter the illumination
// colour / max(albedo, epsilon) and multiply the albedo back at the end, so that texture detail
// is not blurred. Frames without an albedo are filtered as they are.
struct LearnedSettings {
    std::string weights;  // [a weights file, empty: the built-in] the learned method's network
                          // (training/: docs/learned.md)
};

struct AlbedoSettings {
    bool demodulate = true;  // use the frame's albedo when it has one
    float epsilon = 1e-3f;   // [>0] floor of the albedo divided by (black texels)
};

struct TemporalSettings {
    SpatialFilter spatialFilter = SpatialFilter::Atrous;  // filter applied before accumulation
    float alpha = 0.2f;   // [0, 1] weight of the current frame (1 where history is invalid)
    float clampK = 1.0f;  // [>0] history clamped to mu +- k sigma of the current neighbourhood
    int clampRadius = 3;  // [1, 15] neighbourhood half width for mu and sigma (3 -> 7x7)
};

struct DenoiserSettings {
    Method method = Method::Detail;  // the best on every rendered scene (README quality table)
    DeviceType device = DeviceType::Auto;
    EdgeStoppingSettings edges;
    JbfSettings jbf;
    AtrousSettings atrous;
    OutlierSettings outlier;
    EnergySettings energy;
    TemporalSettings temporal;
    HistorySettings history;
    MotionSettings motion;
    SvgfSettings svgf;
    DetailSettings detail;
    LearnedSettings learned;
    AlbedoSettings albedo;
};

// Throws rtd::Error(InvalidArgument) naming the first setting out of its range.
void validate(const DenoiserSettings& settings);

const char* toString(Method method);
const char* toString(SpatialFilter filter);
const char* toString(DeviceType device);

}  // namespace rtd
