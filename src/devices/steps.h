// The logical kernels a method's passes name ("the SVGF A-Trous iteration at stride s", "the
// temporal stage"). Each holds its kernel functors in their reference (planar, separate-pass)
// form; a device runs it in its own fastest form (cpu_device.cpp: planar, split, pair-sharing;
// cuda_device.cu: fused, interleaved, paired rows). The functors are the same on both back ends.
#pragma once

#include "kernels/accumulate.h"
#include "kernels/atrous.h"
#include "kernels/convert.h"
#include "kernels/detail.h"
#include "kernels/energy.h"
#include "kernels/ingest.h"
#include "kernels/jbf.h"
#include "kernels/learned.h"
#include "kernels/modulate.h"
#include "kernels/outlier.h"
#include "kernels/outlier_tile.h"
#include "kernels/reproject.h"
#include "kernels/svgf.h"
#include "kernels/window_sums.h"

namespace rtd {

enum class StepKind {
    Ingest,
    Despeckle,
    Jbf,
    AtrousLevel,
    TemporalStage,
    Geometry,
    SvgfTemporalStage,
    SvgfVariance,
    SvgfAtrousIteration,
    DetailTemporalStage,
    DetailClamp,
    DetailSplit,
    DetailStabilise,
    AddToOutput,
    Modulate,
    EnergyInput,
    Energy,
    LearnedMix,
};

// The frame's buffers into the device's images. Its guide (normal + depth, 4 planes) may be
// written interleaved: the device reads it back the same way in every step.
// hasMotion: also the motion vectors into the history test's previous positions.
struct IngestStep {
    IngestKernel ingest;
    MotionIngestKernel motion = {};
    bool hasMotion = false;
};

// A caller's buffer into packed floats or IDs, the result into the caller's layout, or a ray
// distance into view depth (convert.h): before and after a frame's passes, where its buffers are
// not packed float.
struct ConvertStep {
    enum class Kind { Input, ViewDepth, Output } kind = Kind::Input;
    ConvertInputKernel input = {};
    ViewDepthFromPositionKernel viewDepth = {};
    WriteOutputKernel output = {};
};

// Firefly removal of `in` into `out`. clampSums, where set: also the colour row sums of `out`
// over SVGF's history-clamp window (kSvgfWindowRadius), which the next steps read.
struct DespeckleStep {
    GBufferView g;
    Planes3 in, out;
    PlaneSet rowSums;  // 7 planes of working memory (the separate passes' window statistics)
    int radius;
    float k;
    PlaneSet clampSums = {};
    float* above = nullptr;  // optional out: aboveLimit's mark per pixel (Outlier)
};

struct JbfStep {
    JbfKernel jbf;
};

// One level of the course's A-Trous filter; modulated: writes the result times the albedo into
// the output instead of its `out` planes.
struct AtrousLevelStep {
    AtrousModulatedKernel level;
    bool modulated = false;
};

// The assignment's temporal stage after the spatial filter: the clamp window's row sums of
// `accumulate.current`, the history test's slopes, the back-projection and the accumulation.
// reproject.derivatives, reproject.reprojected and accumulate.reprojected are the device's to
// fill (the split form's working planes).
struct TemporalStageStep {
    ReprojectKernel reproject;
    AccumulateModulatedKernel accumulate;  // its radius picks the window's instantiation
};

// The depth slopes and normal change per pixel (the history test's, SVGF's edge terms).
struct GeometryStep {
    GeometryDerivativesKernel geometry;
};

// SVGF's reprojection (with the 3x3 search where the bilinear taps fail) and accumulation.
// reproject.history and accumulate.history are the device's to fill (the split form's working
// planes). clampRows: first the history clamp's row sums of accumulate.radiance.
struct SvgfTemporalStageStep {
    SvgfReprojectKernel reproject;
    SvgfAccumulateKernel accumulate;
    bool clampRows = false;
};

// historyFix (where its slow history is set): the estimate then written back into the history
// (detail).
struct SvgfVarianceStep {
    SvgfVarianceKernel variance;
    DetailHistoryFixKernel historyFix = {};
    const std::int32_t* onlyKeyed = nullptr;  // as in DetailTemporalStageStep
};

// Modulated: writes the result times the albedo into the output instead of `out`.
struct SvgfAtrousIterationStep {
    SvgfAtrousModulatedKernel iteration;
    bool modulated = false;
    const std::int32_t* onlyKeyed = nullptr;  // as in DetailTemporalStageStep
};

// The detail method's reprojection (with the 3x3 search) and accumulation of both histories.
// reproject.history and accumulate.history are the device's to fill (working planes).
// specular (hasSpecular): the specular signal's, whose history is then followed by the
// reflection or capped (DetailSpecularReproject) before the accumulation.
struct DetailTemporalStageStep {
    DetailReprojectKernel reproject;
    DetailAccumulateKernel accumulate;
    DetailSpecularReprojectKernel specular = {};
    int hasSpecular = 0;
    // The frame gives the specular hit distance: the reflection is followed first, and the
    // surface's history found only where that fails (DetailSpecularFollow, DetailSpecularSurface).
    int specularFollowsFirst = 0;
    // Set (the split signal's specular passes): the pixels whose key here is < 0 may be skipped,
    // their outputs left unspecified (the CPU skips runs of them: WhereKeyed).
    const std::int32_t* onlyKeyed = nullptr;
};

// The ingest's image into the diffuse and specular signals (frames with a specular input).
struct DetailSplitStep {
    DetailSplitKernel split;
};

// The detail method's output: its result stabilised, times the albedo.
struct DetailStabiliseStep {
    DetailStabiliseKernel stabilise;
};

// The filtered specular signal added to the output.
struct AddToOutputStep {
    AddToOutputKernel add;
};

// The window sums of the fast history and of the current luminance, the clamp and anti-lag,
// then the anti-lag's ratio applied to the fast history.
struct DetailClampStep {
    ColorRowSumsKernel fastRows;
    LuminanceRowSumsKernel currentRows;
    DetailClampKernel clamp;
    DetailScaleKernel scale;
    const std::int32_t* onlyKeyed = nullptr;  // as in DetailTemporalStageStep
};

struct ModulateStep {
    ModulateKernel modulate;
};

// The input's luminance for the energy restoration, after the ingest.
struct EnergyInputStep {
    EnergyInputKernel input;
};

// The energy restoration of the output (kernels/energy.h): four kernels over the tile grid
// (grid.across x grid.down items) and two over the frame (one item), then one over the pixels.
struct EnergyStep {
    EnergyOutputSumsKernel sums;
    EnergyAccumulateKernel accumulate;
    EnergyFrameCapKernel frameCap;
    EnergyTailKernel tail;
    EnergyGainKernel gain;
    EnergyFrameGainKernel frameGain;
    EnergyApplyKernel apply;
};

// The learned method's network over its candidates, times the albedo, into the output.
struct LearnedMixStep {
    LearnedMixKernel mix;
};

// The same fields in another form of a kernel family (forms differ in template flags only).
template <bool Interleaved>
Ingest<Interleaved> ingestForm(const IngestKernel& k) {
    return {k.layout,     k.beautyRgb,   k.normalRgb, k.positionRgb,    k.depthIn,
            k.idIn,       k.objectCount, k.albedoRgb, k.albedoEpsilon,  k.beauty,
            k.albedo,     k.normal,      k.position,  k.depth,          k.objectId,
            k.inputFlags, k.normalDepth, k.filterKey, k.separateObjects};
}
template <bool NarrowNormal, bool Modulated>
Atrous<NarrowNormal, Modulated> atrousForm(const AtrousModulatedKernel& k) {
    return {k.g, k.in, k.out, k.stride, k.edges, k.albedo, k.rgbOut};
}
template <int MaxRadius>
AccumulateModulated<MaxRadius> accumulateForm(const AccumulateModulatedKernel& k) {
    return {k.g,     k.rowSums, k.current, k.reprojected, k.validity, k.out,
            k.alpha, k.clampK,  k.radius,  k.albedo,      k.rgbOut};
}
// The detail method's temporal stage on both devices, split (the history handed on through
// `history`, kDetailHistoryPlanes working planes): the bilinear reprojection, the sparse 3x3
// search, the accumulation (its form with the confidence where the frame has one: that form's
// per-pixel type switch keeps the CPU's loop scalar).
template <class Launch>
void runDetailTemporalStep(const DetailTemporalStageStep& s, PlaneSet history, Launch&& launch) {
    DetailReprojectKernel reproject = s.reproject;
    reproject.history = history;
    const DetailReprojectKernel& r = reproject;
    // Without a history or objects, nothing to follow (and no object to read).
    const bool follow = s.hasSpecular && r.hasHistory && s.specular.objectCount > 0;
    if (follow && s.specularFollowsFirst) {
        const DetailSpecularReprojectKernel& k = s.specular;
        const DetailSpecularFollowKernel specular{k.g,
                                                  k.previous,
                                                  k.objects,
                                                  k.objectCount,
                                                  k.previousSlow,
                                                  k.previousFast,
                                                  k.previousMoments,
                                                  k.previousLength,
                                                  history,
                                                  k.validity,
                                                  k.lobe,
                                                  k.cameraPosition,
                                                  k.maxHistory};
        launch(specular);
        launch(DetailSpecularSurfaceKernel{reproject, specular});
    } else {
        launch(reproject);
        launch(DetailReprojectSearchKernel{r.g, r.previous, r.objects, r.objectCount, r.derivatives,
                                           r.test, r.previousSlow, r.previousFast,
                                           r.previousMoments, r.previousLength, r.history,
                                           r.validity, r.hasHistory, r.previousStable});
        if (follow) {
            DetailSpecularReprojectKernel specular = s.specular;
            specular.history = history;
            launch(specular);
        }
    }
    const DetailAccumulateKernel& a = s.accumulate;
    if (a.confidence.data)
        launch(DetailAccumulateConfidenceKernel{
            a.g, a.radiance, history, a.validity, a.confidence, a.slow, a.fast, a.moments, a.length,
            a.maxHistory, a.fastHistory, a.momentsAlpha, a.heldStable, a.raw, a.above});
    else
        launch(DetailAccumulateKernel{a.g, a.radiance, history, a.validity, a.confidence, a.slow,
                                      a.fast, a.moments, a.length, a.maxHistory, a.fastHistory,
                                      a.momentsAlpha, a.heldStable, a.raw, a.above});
}
// The detail method's clamp step, alike on both devices: the two window sums, the clamp and
// anti-lag, then the fast history's scaling (after every neighbour's read of it).
template <class Launch>
void runDetailClampStep(const DetailClampStep& s, Launch&& launch) {
    launch(s.fastRows);
    launch(s.currentRows);
    launch(s.clamp);
    launch(s.scale);
}
template <bool Search3x3>
SvgfReproject<Search3x3> svgfReprojectForm(const SvgfReprojectKernel& k) {
    return {k.g,
            k.previous,
            k.objects,
            k.objectCount,
            k.derivatives,
            k.test,
            k.previousIllumination,
            k.previousMoments,
            k.previousLength,
            k.history,
            k.validity,
            k.hasHistory};
}
template <int FixedSigmaNormal, bool Interleaved, bool SkipsInactive = Interleaved>
SvgfVariance<FixedSigmaNormal, Interleaved, SkipsInactive> svgfVarianceForm(
    const SvgfVarianceKernel& k) {
    return {k.g,   k.derivatives, k.illumination, k.moments,  k.length,
            k.out, k.terms,       k.shortHistory, k.fadeUntil};
}
template <int FixedSigmaNormal, bool Modulated, bool Interleaved>
SvgfAtrous<FixedSigmaNormal, Modulated, Interleaved> svgfAtrousForm(
    const SvgfAtrousModulatedKernel& k) {
    return {k.g, k.derivatives, k.in, k.out, k.stride, k.terms, k.albedo, k.rgbOut};
}

// The forms both devices pick alike, launched by `launch(kernel)` (the device's own launcher).
// The narrow-normal forms where sigma_normal makes opposite normals' weight vanish: no square
// root per tap. tiles: the firefly removal as one tile pass where its window fits the tile.
template <class Launch>
void runJbfStep(const JbfStep& s, Launch&& launch) {
    const JbfKernel& j = s.jbf;
    if (oppositeNormalsVanish(j.edges))
        launch(JbfNarrowNormalKernel{j.g, j.in, j.out, j.radius, j.coordScale, j.edges});
    else
        launch(j);
}
template <class Launch>
void runAtrousLevelStep(const AtrousLevelStep& s, Launch&& launch) {
    const bool narrow = oppositeNormalsVanish(s.level.edges);
    if (s.modulated)
        narrow ? launch(atrousForm<true, true>(s.level)) : launch(s.level);
    else
        narrow ? launch(atrousForm<true, false>(s.level))
               : launch(atrousForm<false, false>(s.level));
}
template <class Launch>
void runDespeckleStep(const DespeckleStep& s, bool tiles, Launch&& launch) {
    if (tiles && s.radius <= kNarrowWindow) {  // the window statistics kept in the tile
        if (s.clampSums.data)
            launch(OutlierClampTileKernel{s.g, s.in, s.out, s.clampSums, s.radius, s.k, s.above});
        else
            launch(OutlierTileKernel{s.g, s.in, s.out, {}, s.radius, s.k, s.above});
        return;
    }
    if (s.radius <= kNarrowWindow) {
        launch(LuminanceRowSumsKernel{s.g, s.in, s.rowSums, s.radius});
        launch(OutlierKernel{s.g, s.rowSums, s.in, s.out, s.radius, s.k, s.above});
    } else {
        launch(LuminanceRowSumsWideKernel{s.g, s.in, s.rowSums, s.radius});
        launch(OutlierWideKernel{s.g, s.rowSums, s.in, s.out, s.radius, s.k, s.above});
    }
    if (s.clampSums.data) launch(ColorRowSumsKernel{s.g, s.out, s.clampSums, kSvgfWindowRadius});
}

template <class Launch>
void runConvertStep(const ConvertStep& s, Launch&& launch) {
    switch (s.kind) {
        case ConvertStep::Kind::Input:
            launch(s.input);
            break;
        case ConvertStep::Kind::ViewDepth:
            launch(s.viewDepth);
            break;
        case ConvertStep::Kind::Output:
            launch(s.output);
            break;
    }
}

// Calls run.template operator()<MaxRadius>() with the window instantiation (window_sums.h) that
// covers `radius`: the 7x7 one where it suffices, else the widest.
template <class Run>
void forWindow(int radius, Run&& run) {
    if (radius <= kNarrowWindow)
        run.template operator()<kNarrowWindow>();
    else
        run.template operator()<kWideWindow>();
}

}  // namespace rtd
