// detail: SVGF's variance-guided filter over a history that keeps the detail. The colour history
// is the accumulated, unfiltered illumination (SVGF feeds a blurred iteration back, which bakes
// the blur into every later frame), kept twice as in NVIDIA NRD's ReLAX: a slow history of up to
// max-history frames and a fast one of up to fast-history frames, to which the slow one is
// clamped (lighting changes). The A-Trous iterations' luminance tolerance follows the variance
// of the accumulated mean, so the filter narrows as a pixel's history grows; pixels with a short
// history (disocclusions, lighting changes) get SVGF's 7x7 spatial estimate first, fading out over
// the first 3 frames and written back into the history (ReLAX's history fix).
//
//   ingest -> [outlier] -> geometry -> detail-temporal -> detail-clamp -> detail-variance
//          -> detail-atrous0 .. detail-atrous{iterations-1} -> detail-stabilise (modulated)
//   detail-temporal: reprojection of both histories (3x3 search where the bilinear taps fail),
//   accumulation (scaled by the caller's confidence where given; the raw sample where the pixel
//   was far above its firefly limit in recent frames too: a light, DetailAccumulate)
//   detail-stabilise: the result blended with the previous frame's, clamped to the current
//   3x3 neighbourhood (NVIDIA NRD ReBLUR's temporal stabilisation), where nothing moved much
//
// With the split signal (a specular input, NVIDIA NRD's diffuse/specular), the two are filtered
// apart, each with its own histories, and added at the end:
//   ingest -> detail-split -> [outlier, outlier-specular] -> geometry
//          -> diffuse:  detail-temporal .. detail-atrous{last}, detail-stabilise (the output)
//          -> specular: detail-specular-temporal (the reflection's history where the hit
//             distance is given, else the surface's, capped by parallax and roughness)
//             .. detail-specular-atrous{last} -> add-specular
#include <cctype>
#include <string>
#include <vector>

#include "methods/method.h"

namespace rtd {

namespace {

// The output's stabilisation (DetailStabiliseKernel): the previous frame's share where nothing
// moved, the clamp's half width in standard deviations of the 3x3 neighbourhood, and the share's
// fall with motion (a reflection on a moving surface is not held back; docs/quality.md).
constexpr float kStabiliseBlend = 0.65f, kStabiliseClampSigma = 1.5f, kStabiliseFalloff = 4.0f;

// Where the firefly removal saw each pixel far above its limit (DetailAccumulate's lights):
// allocated zeroed (fillByte 0), and so all 0 where no pass writes it (the removal off).
ResourceId declareAboveLimit(Pipeline& p, const std::string& signal) {
    return p.declare(floatImage(signal.empty() ? "aboveLimit" : signal + "AboveLimit", 1));
}

// What both signals' passes use in turn (frame lifetime).
struct SharedImages {
    ResourceId derivatives, variance, filterA, filterB, validity, lagScale, currentSums;
    ResourceId lobe;  // the split signal's: roughness, hit distance (DetailSplitKernel)
};

// One signal's histories and passes, from its despeckled image `in` to its filtered image (the
// output, stabilised and times the albedo, when toOutput; else returned). specular: the split
// signal's specular part, with its own reprojection (DetailSpecularReproject).
ResourceId declareSignal(Pipeline& p, const DenoiserSettings& settings, const FrameImages& f,
                         const SharedImages& shared, ResourceId in, ResourceId above, bool specular,
                         bool toOutput, const LearnedNetwork* mix) {
    const DetailSettings& d = settings.detail;
    const std::string prefix = specular ? "specular" : "";
    auto named = [&](const std::string& name) {
        return specular ? prefix + char(std::toupper(name[0])) + name.substr(1) : name;
    };
    const std::string passPrefix = specular ? "detail-specular-" : "detail-";
    ResourceId slow = p.declare(floatImage(named("slowHistory"), 3, Lifetime::History));
    ResourceId fast = p.declare(floatImage(named("fastHistory"), 3, Lifetime::History));
    ResourceId moments = p.declare(floatImage(named("moments"), 3, Lifetime::History));
    ResourceId length = p.declare({.name = named("historyLength"),
                                   .lifetime = Lifetime::History,
                                   .hasDebugView = !specular,
                                   .debugView = DebugView::HistoryLength,
                                   .debugDivisor = float(d.maxHistory)});
    const ResourceId derivatives = shared.derivatives, variance = shared.variance;
    const ResourceId validity = shared.validity;
    const SvgfTerms terms{d.sigmaDepth, d.sigmaNormal, d.sigmaLuminance};

    // The output's stabilisation (toOutput: the signal that writes the output, stabilised): its
    // history, and that history reprojected by the temporal pass.
    ResourceId stable, heldStable;
    if (toOutput) {
        stable = p.declare(floatImage("stableIllumination", 3, Lifetime::History));
        heldStable = p.declare(floatImage("heldStable", 3));
    }

    const HistoryTest test = historyTest(settings.history);
    std::vector<ResourceId> temporalReads =
        with(reprojectionReads(p, f), {derivatives, previous(slow), previous(fast),
                                       previous(moments), previous(length), in, f.noisy, above});
    if (specular) temporalReads.push_back(shared.lobe);
    std::vector<ResourceId> temporalWrites{slow, fast, moments, length, validity, in};
    if (toOutput) {
        temporalReads.push_back(previous(stable));
        temporalWrites.push_back(heldStable);
    }
    p.addPass(passPrefix + "temporal", StepKind::DetailTemporalStage, temporalReads, temporalWrites,
              2, [=](const PassContext& c) {
                  GBufferView g = gbuffer(c, f);
                  const FrameBinding& frame = c.frame();
                  const PreviousGeometry before = previousGeometry(c, f);
                  DetailReprojectKernel reproject{g,
                                                  before,
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
                  reproject.previousStable = c.planes(previous(toOutput ? stable : slow));
                  accumulate.raw = c.planes(f.noisy);
                  accumulate.above = c.floats(above);
                  if (toOutput) accumulate.heldStable = c.planes(heldStable);
                  DetailTemporalStageStep step{reproject, accumulate};
                  if (specular) {
                      step.onlyKeyed = g.filterKey;
                      step.hasSpecular = 1;
                      step.specularFollowsFirst = frame.hitDistance.data ? 1 : 0;
                      step.specular = {g,
                                       before,
                                       c.objects(),
                                       frame.objectCount,
                                       c.planes(previous(slow)),
                                       c.planes(previous(fast)),
                                       c.planeSet(previous(moments)),
                                       c.floats(previous(length)),
                                       {},
                                       c.bytes(validity),
                                       c.planeSet(shared.lobe),
                                       frame.cameraPosition,
                                       float(d.maxHistory)};
                  }
                  c.device().run(step);
              });

    // The anti-lag runs with a caller's confidence too: the renderer's gradients (A-SVGF) take
    // most of a switched light's change, not all. The fast history's window sums in windowSums
    // (free after the firefly removal).
    constexpr int kWindow = DetailClampKernel::kRadius;
    const ResourceId lagScale = shared.lagScale, currentSums = shared.currentSums;
    p.addPass(
        passPrefix + "clamp", StepKind::DetailClamp,
        with(gbufferReads(f), {in, fast, slow, moments, length}),
        {fast, slow, moments, length, variance, lagScale, f.windowSums, currentSums}, kNarrowWindow,
        [=](const PassContext& c) {
            const GBufferView g = gbuffer(c, f);
            const bool antiLag = d.antiLag;
            DetailClampStep step{
                {g, c.planes(fast), c.planeSet(f.windowSums), kWindow},
                {g, c.planes(in), c.planeSet(currentSums), kWindow},
                {g, c.planes(in), c.planeSet(f.windowSums), c.planeSet(currentSums), c.planes(slow),
                 c.planeSet(moments), c.floats(length), c.planeSet(variance), c.floats(lagScale),
                 d.clampSigma, float(d.fastHistory), d.momentsAlpha, antiLag ? 1 : 0},
                {c.layout(), c.planes(fast), c.floats(lagScale)}};
            if (specular) step.onlyKeyed = g.filterKey;
            c.device().run(step);
        });

    // Short histories only (block-sparse): SVGF's 7x7 estimate of the variance and colour, with
    // its wide luminance tolerance (there is no variance yet), all of it at 1 frame, half at 2,
    // none from 3 (switched off at once, it shows as a step of noise in the output). It is
    // written back into the slow history (ReLAX's history fix): the next frames accumulate onto
    // a denoised start rather than onto one or two raw samples.
    SvgfTerms wide = terms;
    wide.sigmaLuminance = 10.0f;
    constexpr float kShortHistory = 1.0f, kSpatialUntil = 3.0f;  // frames: share 1 -> 0
    p.addPass(
        passPrefix + "variance", StepKind::SvgfVariance,
        with(gbufferReads(f), {slow, moments, length, derivatives, variance}), {variance, slow},
        kSvgfWindowRadius, [=](const PassContext& c) {
            const GBufferView g = gbuffer(c, f);
            c.device().run(SvgfVarianceStep{
                {g, c.planeSet(derivatives), c.planes(slow), c.planeSet(moments), c.floats(length),
                 c.planeSet(variance), wide, kShortHistory, kSpatialUntil},
                {c.layout(), c.planeSet(variance), c.planes(slow), c.floats(length), kSpatialUntil},
                specular ? g.filterKey : nullptr});
        });

    const ResourceId filtered =
        mix ? declareLearnedMix(
                  p, f, {derivatives, variance, length, shared.filterA, shared.filterB, terms},
                  *mix)
            : declareGuidedIterations(p, f, passPrefix + "atrous", derivatives, variance,
                                      shared.filterA, shared.filterB,
                                      specular ? d.specularIterations : d.iterations, terms, -1, {},
                                      false, specular);
    if (!toOutput) return filtered;

    // The stabilisation, last: the residual noise a narrowed filter leaves would otherwise
    // flicker from frame to frame (docs/quality.md). Before the specular passes, which reuse
    // the validity and the anti-lag's ratios.
    p.addPass(
        "detail-stabilise", StepKind::DetailStabilise,
        with(reprojectionReads(p, f), {filtered, heldStable, validity, lagScale, length, f.albedo}),
        {stable, p.output()}, 1, [=](const PassContext& c) {
            c.device().run(DetailStabiliseStep{
                {gbuffer(c, f), c.planeSet(filtered), c.planes(heldStable), c.bytes(validity),
                 c.floats(lagScale), c.floats(length), c.planes(stable), c.planes(f.albedo),
                 c.output(), kStabiliseBlend, kStabiliseClampSigma, previousGeometry(c, f),
                 c.objects(), c.frame().objectCount, kStabiliseFalloff}});
        });
    return filtered;
}

}  // namespace

FrameImages declareDetail(Pipeline& p, const DenoiserSettings& settings, const MethodInputs& inputs,
                          const LearnedNetwork* mix) {
    FrameImages f = declareIngest(p, settings);
    ResourceId specularNoisy, lobe;
    // The specular passes' G-buffer: the frame's, with their own object IDs and filter keys, -1
    // where the lobe is not kept apart (DetailSplitKernel): they skip those pixels and never
    // take them in.
    FrameImages specularFrame = f;
    if (inputs.specular) {
        specularNoisy = p.declare(floatImage("specularNoisy", 3));
        lobe = p.declare(floatImage("specularLobe", 2));
        specularFrame.objectId = p.declare({.name = "specularObjectId",
                                            .element = Element::Int32,
                                            .lifetime = Lifetime::History,
                                            .fillByte = 0xff});
        specularFrame.filterKeys =
            p.declare({.name = "specularFilterKeys", .element = Element::Int32, .fillByte = 0xff});
        const FrameImages s = specularFrame;
        p.addPass("detail-split", StepKind::DetailSplit,
                  {p.frame(), f.noisy, f.albedo, f.objectId, f.filterKeys},
                  {f.noisy, specularNoisy, lobe, s.objectId, s.filterKeys}, 0,
                  [f, s, specularNoisy, lobe](const PassContext& c) {
                      const FrameBinding& frame = c.frame();
                      DetailSplitStep step{{c.layout(), c.planes(f.noisy), c.planes(f.albedo),
                                            frame.specular, frame.roughness, frame.hitDistance,
                                            c.ints(f.objectId), c.ints(f.filterKeys),
                                            c.planes(specularNoisy), c.planeSet(lobe),
                                            c.ints(s.objectId), c.ints(s.filterKeys)}};
                      c.device().run(step);
                  });
    }
    const ResourceId above = declareAboveLimit(p, "");
    ResourceId in = declareDespeckle(p, settings, f, false, "", above);

    SharedImages shared;
    shared.derivatives = p.declare(floatImage("derivatives", 3));  // dz/dx, dz/dy, fwidth(n)
    // rgb + variance, the A-Trous input.
    shared.variance = p.declare({.name = "illumination+variance",
                                 .planes = 4,
                                 .hasDebugView = true,
                                 .debugView = DebugView::Variance,
                                 .debugPlane = 3,
                                 .debugShow = DebugShow::StandardDeviation});
    shared.filterA = p.declare(floatImage("filterA", 4));
    shared.filterB = p.declare(floatImage("filterB", 4));
    shared.validity = declareValidity(p);
    shared.lagScale = p.declare(floatImage("lagScale", 1));
    shared.currentSums = p.declare(floatImage("currentSums", 3));
    shared.lobe = lobe;

    const ResourceId derivatives = shared.derivatives;
    p.addPass("geometry", StepKind::Geometry, gbufferReads(f), {derivatives}, 2,
              [f, derivatives](const PassContext& c) {
                  c.device().run(GeometryStep{{gbuffer(c, f), c.planeSet(derivatives)}});
              });
    declareSignal(p, settings, f, shared, in, above, false, true, mix);
    if (!inputs.specular) return f;

    specularFrame.noisy = specularNoisy;
    const ResourceId specularAbove = declareAboveLimit(p, "specular");
    ResourceId specularIn =
        declareDespeckle(p, settings, specularFrame, false, "specular", specularAbove);
    ResourceId filtered = declareSignal(p, settings, specularFrame, shared, specularIn,
                                        specularAbove, true, false, nullptr);
    const ResourceId keys = specularFrame.filterKeys;
    p.addPass("add-specular", StepKind::AddToOutput, {filtered, keys, p.output()}, {p.output()}, 0,
              [filtered, keys](const PassContext& c) {
                  c.device().run(
                      AddToOutputStep{{c.layout(), c.planes(filtered), c.ints(keys), c.output()}});
              });
    return f;
}

}  // namespace rtd
