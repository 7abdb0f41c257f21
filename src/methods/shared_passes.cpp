// The passes several methods share: the ingest, the firefly removal, the spatial filters (JBF,
// A-Trous levels) and the modulation.
#include <fmt/format.h>

#include <algorithm>

#include "methods/method.h"
#include "rtdenoise/error.h"

namespace rtd {
namespace {

EdgeStoppingTerms edgeTerms(const EdgeStoppingSettings& s) {
    return {1.0f / (2.0f * s.sigmaColor * s.sigmaColor),
            1.0f / (2.0f * s.sigmaNormal * s.sigmaNormal),
            1.0f / (2.0f * s.sigmaPlane * s.sigmaPlane)};
}

// How far a window kernel of this radius reads (its compile-time width, window_sums.h).
int windowReach(int radius) {
    return radius <= kNarrowWindow ? kNarrowWindow : kWideWindow;
}

}  // namespace

namespace {

FrameImages declareMethodPasses(Pipeline& pipeline, const DenoiserSettings& settings,
                                const MethodInputs& inputs) {
    switch (settings.method) {
        case Method::Jbf:
            return declareJbf(pipeline, settings);
        case Method::Atrous:
            return declareAtrous(pipeline, settings);
        case Method::Temporal:
            return declareTemporal(pipeline, settings);
        case Method::Svgf:
            return declareSvgf(pipeline, settings);
        case Method::Detail:
            return declareDetail(pipeline, settings, inputs);
        case Method::Learned:
            return declareLearned(pipeline, settings, inputs);
    }
    throw Error(ErrorCode::InvalidArgument, "settings: unknown method");
}

// The energy restoration of the output, last (kernels/energy.h): its arrays hold one value per
// 16x16 tile.
void declareEnergy(Pipeline& p, const DenoiserSettings& settings, const FrameImages& f) {
    if (!settings.energy.keep) return;
    // The tiles' average spans up to 4 frames: longer ones lag behind a method whose loss falls
    // as its history grows (chosen on the train set, docs/energy.md).
    constexpr float kEnergyFrames = 4.0f;
    // The frame's average spans up to 16 frames: the cut light is rare bright samples (the train
    // sequences are 16 frames long).
    constexpr float kEnergyFrameFrames = 16.0f;
    // One value per plane for the whole frame: a tile larger than any image.
    constexpr int kWholeFrame = 1 << 30;
    ResourceId tiles =
        p.declare({.name = "energyTiles", .planes = 7, .padded = false, .tile = kEnergyTile});
    ResourceId history = p.declare({.name = "energyHistory",
                                    .planes = 3,
                                    .lifetime = Lifetime::History,
                                    .padded = false,
                                    .tile = kEnergyTile});
    ResourceId whole =
        p.declare({.name = "energyFrame", .planes = 2, .padded = false, .tile = kWholeFrame});
    ResourceId wholeHistory = p.declare({.name = "energyFrameHistory",
                                         .planes = 3,
                                         .lifetime = Lifetime::History,
                                         .padded = false,
                                         .tile = kWholeFrame});
    const int temporal = usesHistory(settings.method) ? 1 : 0;
    const float cap = settings.energy.cap, frameShare = settings.energy.frameShare;
    p.addPass(
        "energy", StepKind::Energy,
        {p.frame(), f.energyInput, f.filterKeys, p.output(), previous(history),
         previous(wholeHistory)},
        {tiles, history, whole, wholeHistory, p.output()}, 0, [=](const PassContext& c) {
            const Layout& L = c.layout();
            EnergyGrid grid{energyTilesAcross(L.width), energyTilesAcross(L.height),
                            c.floats(tiles),        c.floats(history),
                            c.floats(previous(history)), c.floats(whole),
                            c.floats(wholeHistory), c.floats(previous(wholeHistory))};
            const std::int32_t* keys = c.ints(f.filterKeys);
            float* out = c.output();
            const float* input = c.floats(f.energyInput);
            const int hasHistory = c.frame().hasHistory;
            c.device().run(EnergyStep{
                {L, keys, out, input, grid},
                {L, keys, out, input, c.frame().confidence, grid, temporal, hasHistory,
                 kEnergyFrames, cap},
                {grid, temporal, hasHistory, kEnergyFrameFrames, frameShare},
                {L, keys, out, input, grid},
                {grid},
                {grid},
                {L, keys, out, grid}});
        });
}

}  // namespace

FrameImages declareMethod(Pipeline& pipeline, const DenoiserSettings& settings,
                          const MethodInputs& inputs) {
    FrameImages f = declareMethodPasses(pipeline, settings, inputs);
    declareEnergy(pipeline, settings, f);
    return f;
}

ResourceDecl floatImage(std::string name, int planes, Lifetime lifetime) {
    return {.name = std::move(name), .planes = planes, .lifetime = lifetime};
}

std::vector<ResourceId> gbufferReads(const FrameImages& f) {
    return {f.guide, f.position, f.objectId, f.filterKeys};
}

std::vector<ResourceId> with(std::vector<ResourceId> ids, std::initializer_list<ResourceId> more) {
    ids.insert(ids.end(), more);
    return ids;
}

GBufferView gbuffer(const PassContext& c, const FrameImages& f) {
    float* guide = c.floats(f.guide);
    int planeSize = c.layout().planeSize;
    // Normal planes then depth, or both interleaved (NormalDepth4): the device's steps read it
    // in the form its ingest wrote.
    return {c.layout(),           {guide, planeSize},
            c.planes(f.position), guide + 3 * std::size_t(planeSize),
            c.ints(f.objectId),   {guide},
            c.ints(f.filterKeys)};
}

PreviousGeometry previousGeometry(const PassContext& c, const FrameImages& f) {
    float* guide = c.floats(previous(f.guide));
    int planeSize = c.layout().planeSize;
    const bool fromMotion = c.frame().motion.data != nullptr;
    return {c.ints(previous(f.objectId)),
            guide + 3 * std::size_t(planeSize),
            {guide, planeSize},
            {guide},
            fromMotion ? c.planes(f.motion) : Planes3{},
            fromMotion ? 1 : 0};
}

std::vector<ResourceId> reprojectionReads(const Pipeline& p, const FrameImages& f) {
    return with(gbufferReads(f),
                {previous(f.guide), previous(f.objectId), f.motion, p.matrices(), p.frame()});
}

ResourceId declareValidity(Pipeline& p) {
    return p.declare({.name = "validity",
                      .element = Element::Byte,
                      .fillByte = kReprojectionNoHistory,
                      .hasDebugView = true,
                      .debugView = DebugView::Reprojection,
                      .debugShow = DebugShow::ReprojectionCodes});
}

HistoryTest historyTest(const HistorySettings& s) {
    return {s.geometryTests ? 1 : 0, s.depthTolerance, s.normalTolerance};
}

FrameImages declareIngest(Pipeline& p, const DenoiserSettings& settings) {
    FrameImages f;
    f.noisy = p.declare(floatImage("noisy", 3));
    f.albedo = p.declare(floatImage("albedo", 3));
    f.guide = p.declare(floatImage("guide", 4, Lifetime::History));
    f.position = p.declare(floatImage("position", 3));
    // -1 everywhere: the border reads as background.
    f.objectId = p.declare({.name = "objectId",
                            .element = Element::Int32,
                            .lifetime = Lifetime::History,
                            .fillByte = 0xff});
    f.filterKeys = p.declare({.name = "filterKeys", .element = Element::Int32, .fillByte = 0xff});
    f.inputFlags = p.declare({.name = "inputFlags", .element = Element::Byte, .padded = false});
    bool temporal = usesHistory(settings.method);
    if (temporal || settings.outlier.enabled) f.windowSums = p.declare(floatImage("windowSums", 7));
    std::vector<ResourceId> writes = {f.noisy,    f.albedo,     f.guide,     f.position,
                                      f.objectId, f.filterKeys, f.inputFlags};
    if (temporal) {
        f.motion = p.declare(floatImage("motion", 3));
        writes.push_back(f.motion);
    }
    const float epsilon = settings.albedo.epsilon;
    const int separateObjects = settings.edges.separateObjects ? 1 : 0;
    const float motionSign = settings.motion.currentMinusPrevious ? -1.0f : 1.0f;
    const float motionScale[3] = {motionSign * settings.motion.scaleX,
                                  motionSign * settings.motion.scaleY, motionSign};
    p.addPass("ingest", StepKind::Ingest, {p.frame()}, writes, 0,
              [f, epsilon, separateObjects, motionScale](const PassContext& c) {
                  const FrameBinding& in = c.frame();
                  float* guide = c.floats(f.guide);  // normal planes + depth, or interleaved
                  const int planeSize = c.layout().planeSize;
                  const bool hasMotion = in.motion.data != nullptr;
                  MotionIngestKernel motion;
                  if (hasMotion)
                      motion = {c.layout(),     in.motion,      in.depth,          motionScale[0],
                                motionScale[1], motionScale[2], c.planes(f.motion)};
                  c.device().run(IngestStep{{c.layout(),
                                             in.beauty,
                                             in.normal,
                                             in.position,
                                             in.depth,
                                             in.objectId,
                                             in.objectCount,
                                             in.albedo,
                                             epsilon,
                                             c.planes(f.noisy),
                                             c.planes(f.albedo),
                                             {guide, planeSize},
                                             c.planes(f.position),
                                             guide + 3 * std::size_t(planeSize),
                                             c.ints(f.objectId),
                                             c.bytes(f.inputFlags),
                                             {guide},
                                             c.ints(f.filterKeys),
                                             separateObjects},
                                            motion,
                                            hasMotion});
              });
    if (settings.energy.keep) {
        f.energyInput = p.declare(floatImage("energyInput", 1));
        p.addPass(
            "energy-input", StepKind::EnergyInput, {f.noisy, f.albedo}, {f.energyInput}, 0,
            [f](const PassContext& c) {
                c.device().run(EnergyInputStep{
                    {c.layout(), c.planes(f.noisy), c.planes(f.albedo), c.floats(f.energyInput)}});
            });
    }
    return f;
}

ResourceId declareDespeckle(Pipeline& p, const DenoiserSettings& settings, const FrameImages& f,
                            bool clampSums, const std::string& signal, ResourceId above) {
    if (!settings.outlier.enabled) return f.noisy;
    const std::string suffix = signal.empty() ? "" : "-" + signal;
    ResourceId despeckled = p.declare(floatImage("despeckled" + suffix, 3));
    const int radius = settings.outlier.radius;
    const float k = settings.outlier.k;
    std::vector<ResourceId> writes{despeckled, f.windowSums};
    if (above.index >= 0) writes.push_back(above);
    p.addPass(
        "outlier" + suffix, StepKind::Despeckle, with(gbufferReads(f), {f.noisy}), writes,
        clampSums ? std::max(windowReach(radius), kSvgfWindowRadius) : windowReach(radius),
        [f, despeckled, radius, k, clampSums, above](const PassContext& c) {
            c.device().run(DespeckleStep{gbuffer(c, f), c.planes(f.noisy), c.planes(despeckled),
                                         c.planeSet(f.windowSums), radius, k,
                                         clampSums ? c.planeSet(f.windowSums) : PlaneSet{},
                                         above.index >= 0 ? c.floats(above) : nullptr});
        });
    return despeckled;
}

void declareSpatialFilter(Pipeline& p, const DenoiserSettings& settings, const FrameImages& f,
                          SpatialFilter filter, ResourceId in, ResourceId out, ResourceId scratch,
                          bool modulateLast) {
    const EdgeStoppingTerms edges = edgeTerms(settings.edges);
    if (filter == SpatialFilter::Jbf) {
        const int radius = settings.jbf.radius;
        const float coordScale = 1.0f / (2.0f * settings.jbf.sigmaCoord * settings.jbf.sigmaCoord);
        p.addPass("jbf", StepKind::Jbf, with(gbufferReads(f), {in}), {out}, radius,
                  [f, in, out, radius, coordScale, edges](const PassContext& c) {
                      c.device().run(JbfStep{
                          {gbuffer(c, f), c.planes(in), c.planes(out), radius, coordScale, edges}});
                  });
        return;
    }
    // The levels ping-pong between `out` and `scratch`, ending in `out`.
    const int levels = settings.atrous.passes;
    ResourceId src = in;
    for (int level = 0; level < levels; ++level) {
        const bool modulated = modulateLast && level == levels - 1;
        const ResourceId dst = ((levels - 1 - level) % 2) == 0 ? out : scratch;
        const int stride = 1 << level;
        std::vector<ResourceId> reads = with(gbufferReads(f), {src});
        if (modulated) reads.push_back(f.albedo);
        p.addPass(fmt::format("atrous{}", level), StepKind::AtrousLevel, reads,
                  {modulated ? p.output() : dst}, 2 * stride,
                  [f, src, dst, stride, edges, modulated](const PassContext& c) {
                      AtrousModulatedKernel level{gbuffer(c, f), c.planes(src), {}, stride, edges};
                      if (modulated) {
                          level.albedo = c.planes(f.albedo);
                          level.rgbOut = c.output();
                      } else {
                          level.out = c.planes(dst);
                      }
                      c.device().run(AtrousLevelStep{level, modulated});
                  });
        src = dst;
    }
}

ResourceId declareGuidedIterations(Pipeline& p, const FrameImages& f, const std::string& prefix,
                                   ResourceId derivatives, ResourceId in, ResourceId filterA,
                                   ResourceId filterB, int iterations, SvgfTerms terms,
                                   int feedbackIteration, ResourceId feedback, bool toOutput,
                                   bool onlyKeyed, const std::vector<ResourceId>& levels) {
    ResourceId src = in;
    for (int it = 0; it < iterations; ++it) {
        const bool isFeedback = it == feedbackIteration;
        const bool last = it == iterations - 1;
        const bool modulated = last && !isFeedback && toOutput;
        const ResourceId dst = !levels.empty()              ? levels[std::size_t(it)]
                               : isFeedback                 ? feedback
                               : src.index == filterA.index ? filterB
                                                            : filterA;
        const int stride = 1 << it;
        std::vector<ResourceId> reads = with(gbufferReads(f), {src, derivatives});
        if (modulated) reads.push_back(f.albedo);
        p.addPass(fmt::format("{}{}", prefix, it), StepKind::SvgfAtrousIteration, reads,
                  {modulated ? p.output() : dst}, 2 * stride, [=](const PassContext& c) {
                      SvgfAtrousModulatedKernel iteration{gbuffer(c, f),   c.planeSet(derivatives),
                                                          c.planeSet(src), {},
                                                          stride,          terms};
                      if (modulated) {
                          iteration.albedo = c.planes(f.albedo);
                          iteration.rgbOut = c.output();
                      } else {
                          iteration.out = c.planeSet(dst);
                      }
                      c.device().run(SvgfAtrousIterationStep{
                          iteration, modulated, onlyKeyed ? iteration.g.filterKey : nullptr});
                  });
        if (last && !modulated && toOutput) declareModulate(p, f, dst);
        src = dst;
    }
    return src;
}

void declareModulate(Pipeline& p, const FrameImages& f, ResourceId source) {
    p.addPass("modulate", StepKind::Modulate, {source, f.albedo}, {p.output()}, 0,
              [f, source](const PassContext& c) {
                  c.device().run(
                      ModulateStep{{c.layout(), c.planes(source), c.planes(f.albedo), c.output()}});
              });
}

}  // namespace rtd
