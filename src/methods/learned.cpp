// learned: svgf's reprojection, accumulation, variance and five A-Trous iterations, every level
// kept; then a small network per pixel weighs the six candidates (kernels/learned.h), its
// weights trained on the generated corpus (training/, docs/learned.md).
//
//   ingest -> [outlier] -> geometry -> svgf-temporal -> svgf-variance
//          -> learned-atrous0 .. learned-atrous4 (each into its own image) -> learned-mix
#include <fmt/format.h>

#include <algorithm>
#include <iterator>

#include "methods/learned_weights.h"
#include "methods/method.h"

namespace rtd {

FrameImages declareLearned(Pipeline& p, const DenoiserSettings& settings) {
    // Loaded before any pass is declared: a bad file is refused with nothing allocated.
    const LearnedNetwork network = learnedNetwork(settings.learned.weights);
    const SvgfSettings& sv = settings.svgf;
    const SvgfFront s = declareSvgfFront(p, settings);
    const FrameImages& f = s.images;

    // The iterations' outputs: the feedback one writes next frame's history, the others one
    // image each (svgf's two ping-pong images and two more).
    ResourceId pool[] = {s.filterA, s.filterB, p.declare(floatImage("learned-level-a", 4)),
                         p.declare(floatImage("learned-level-b", 4))};
    const int feedbackIteration = std::min(sv.feedbackIteration, kLearnedCandidates - 2);
    ResourceId candidates[kLearnedCandidates] = {s.illumination};
    int next = 0;
    for (int it = 0; it < kLearnedCandidates - 1; ++it) {
        const ResourceId src = candidates[it];
        const ResourceId dst = it == feedbackIteration ? s.feedback : pool[next++];
        const int stride = 1 << it;
        p.addPass(fmt::format("learned-atrous{}", it), StepKind::SvgfAtrousIteration,
                  with(gbufferReads(f), {src, s.derivatives}), {dst}, 2 * stride,
                  [=, terms = s.terms, derivatives = s.derivatives](const PassContext& c) {
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
    dumped.insert(dumped.end(), {s.length, f.albedo, f.filterKeys});
    p.addDebugImage(DebugView::LearnedInputs, dumped);

    std::vector<ResourceId> reads = with(gbufferReads(f), {s.length, f.albedo});
    reads.insert(reads.end(), std::begin(candidates), std::end(candidates));
    p.addPass("learned-mix", StepKind::LearnedMix, reads, {p.output()}, 0,
              [=, length = s.length](const PassContext& c) {
                  LearnedMixKernel mix{gbuffer(c, f),      {},         c.floats(length),
                                       c.planes(f.albedo), c.output(), network};
                  for (int k = 0; k < kLearnedCandidates; ++k)
                      mix.candidates[k] = c.planeSet(candidates[k]);
                  c.device().run(LearnedMixStep{mix});
              });
    return f;
}

}  // namespace rtd
