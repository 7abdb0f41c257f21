"""The install test's Python consumer: reads the rendered scene with the installed module's
reader, denoises it (the default method, CPU, no albedo: what the raw buffers hold) and checks
that its result equals the C consumer's and the C++ consumer's (max relative difference <=
1e-6)."""
import sys

import numpy as np
import rtdenoise

scene, packs = sys.argv[1], sys.argv[2]
sequence = rtdenoise.open_sequence(scene)
denoiser = rtdenoise.Denoiser(device="cpu")
worst = {"c": 0.0, "cpp": 0.0}
for i in range(len(sequence)):
    frame = sequence[i]
    result = denoiser.denoise(frame.color, frame.normal, position=frame.position,
                              depth=frame.depth, ids=frame.ids, matrices=frame.matrices)
    for name in worst:
        other = np.fromfile(f"{packs}/{name}_result_{i}.raw", dtype=np.float32)
        other = other.reshape(result.shape)
        difference = np.abs(result - other) / np.maximum(np.abs(other), 1e-3)
        worst[name] = max(worst[name], float(difference.max()))
print(f"python consumer ok, rtdenoise {rtdenoise.__version__}, {len(sequence)} frames: max "
      f"relative difference to C {worst['c']:.3g}, to C++ {worst['cpp']:.3g}")
sys.exit(0 if max(worst.values()) <= 1e-6 else 1)
