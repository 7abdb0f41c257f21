// learned: detail's passes (both histories, the anti-lag, the variance, the stabilisation), its
// five A-Trous iterations each kept in an image of its own; a small network per pixel weighs the
// six candidates (kernels/learned.h) before the stabilisation, its weights trained on the
// generated corpus (training/, docs/learned.md).
//
//   ingest -> [outlier] -> geometry -> detail-temporal -> detail-clamp -> detail-variance
//          -> learned-atrous0 .. learned-atrous4 (each into its own image) -> learned-mix
//          -> detail-stabilise (modulated)
#include <fmt/format.h>

#include <iterator>

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
    // The levels: detail's two ping-pong images and three more; the mix, one more.
    ResourceId pool[] = {in.filterA, in.filterB, p.declare(floatImage("learned-level-c", 4)),
                         p.declare(floatImage("learned-level-d", 4)),
                         p.declare(floatImage("learned-level-e", 4))};
    const ResourceId mixed = p.declare(floatImage("learned-mixed", 3));
    ResourceId candidates[kLearnedCandidates] = {in.illumination};
    for (int it = 0; it < kLearnedCandidates - 1; ++it) {
        const ResourceId src = candidates[it], dst = pool[it];
        const int stride = 1 << it;
        p.addPass(fmt::format("learned-atrous{}", it), StepKind::SvgfAtrousIteration,
                  with(gbufferReads(f), {src, in.derivatives}), {dst}, 2 * stride,
                  [=, terms = in.terms, derivatives = in.derivatives](const PassContext& c) {
                      SvgfAtrousModulatedKernel iteration{gbuffer(c, f),   c.planeSet(derivatives),
                                                          c.planeSet(src), c.planeSet(dst),
                                                          stride,          terms};
                      c.device().run(SvgfAtrousIterationStep{iteration, false, nullptr});
                  });
        candidates[it + 1] = dst;
    }

    // The network's inputs for training (docs/learned_spec.md): the candidates, the history
    // length, the albedo and whether the pixel holds an object.
    std::vector<ResourceId> dumped(std::begin(candidates), std::end(candidates));
    dumped.insert(dumped.end(), {in.length, f.albedo, f.filterKeys});
    p.addDebugImage(DebugView::LearnedInputs, dumped);

    std::vector<ResourceId> reads = with(gbufferReads(f), {in.length});
    reads.insert(reads.end(), std::begin(candidates), std::end(candidates));
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
