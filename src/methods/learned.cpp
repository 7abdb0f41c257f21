// learned: detail's passes (both histories, the anti-lag, the variance, the stabilisation), its
// five A-Trous iterations each kept in an image of its own; a small network per pixel weighs the
// six candidates (kernels/learned.h) before the stabilisation, its weights trained on the
// generated corpus (training/, docs/learned.md).
//
//   ingest -> [outlier] -> geometry -> detail-temporal -> detail-clamp -> detail-variance
//          -> learned-atrous0 .. learned-atrous4 (each into its own image) -> learned-mix
//          -> detail-stabilise (modulated)
#include "methods/learned_weights.h"
#include "methods/method.h"

namespace rtd {

FrameImages declareLearned(Pipeline& p, const DenoiserSettings& settings,
                           const MethodInputs& inputs) {
    // Loaded before any pass is declared: a bad file is refused with nothing allocated.
    const LearnedNetwork network = learnedNetwork(settings.learned.weights);
    return declareDetail(p, settings, inputs, &network);
}

ResourceId declareLearnedMix(Pipeline& p, const FrameImages& f, const LearnedLevels& in,
                             const LearnedNetwork& network) {
    // The levels, each kept: detail's two ping-pong images and three more; the mix, one more.
    const std::vector<ResourceId> levels = {
        in.filterA, in.filterB, p.declare(floatImage("learned-level-c", 4)),
        p.declare(floatImage("learned-level-d", 4)), p.declare(floatImage("learned-level-e", 4))};
    const ResourceId mixed = p.declare(floatImage("learned-mixed", 3));
    declareGuidedIterations(p, f, "learned-atrous", in.derivatives, in.illumination, in.filterA,
                            in.filterB, kLearnedCandidates - 1, in.terms, -1, {}, false, false,
                            levels);
    std::vector<ResourceId> candidates = {in.illumination};
    candidates.insert(candidates.end(), levels.begin(), levels.end());

    // The network's inputs for training (docs/learned_spec.md): the candidates, the history
    // length, the albedo and whether the pixel holds an object.
    std::vector<ResourceId> dumped = candidates;
    dumped.insert(dumped.end(), {in.length, f.albedo, f.filterKeys});
    p.addDebugImage(DebugView::LearnedInputs, dumped);

    std::vector<ResourceId> reads = with(gbufferReads(f), {in.length});
    reads.insert(reads.end(), candidates.begin(), candidates.end());
    p.addPass(
        "learned-mix", StepKind::LearnedMix, reads, {mixed}, 0,
        [=, length = in.length](const PassContext& c) {
            LearnedMixKernel mix{gbuffer(c, f), {}, c.floats(length), c.planes(mixed), network};
            for (int k = 0; k < kLearnedCandidates; ++k)
                mix.candidates[k] = c.planeSet(candidates[k]);
            c.device().run(LearnedMixStep{mix});
        });
    return mixed;
}

}  // namespace rtd
