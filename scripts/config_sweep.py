#!/usr/bin/env python3
"""Configurations of the library side by side on sequences with references (issue 38's protocol:
run it on train sequences only), each sequence loaded once: energy ratio, relMSE, PSNR and temporal
error per sequence and configuration, then their means, the geometric mean of each configuration's
per-sequence relMSE ratio and its mean PSNR gain over the first configuration (the baseline).

  PYTHONPATH=build/release/python scripts/config_sweep.py SEQ... \\
      --config=NAME:METHOD[:key=value,...][@ENV=VALUE;ENV=VALUE]...

Settings are the Python module's keywords (energy_parts.py's --config). @ENV=VALUE sets
environment variables for that configuration alone (variables starting RTD_DEV_ are cleared
before each one): the switches of a prototype patch (docs/experiments/*.patch) read there, so that
one build serves every configuration. Environment: EXP_JSON=FILE writes every figure as JSON."""
import json
import os
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import rtdenoise as rtd  # noqa: E402
from energy_parts import evaluate, parse_config, sequence_paths  # noqa: E402


def main():
    configs, sequences = [], []
    for arg in sys.argv[1:]:
        if arg.startswith("--config="):
            spec, _, env = arg[len("--config="):].partition("@")
            envs = dict(e.split("=", 1) for e in env.split(";") if e)
            configs.append((*parse_config(spec), envs))
        elif arg.startswith("-"):
            sys.exit(__doc__)
        else:
            sequences.append(arg)
    if not configs or not sequences:
        sys.exit(__doc__)
    results = {}
    for folder in sequences:
        source, ref_paths = sequence_paths(folder)
        seq = rtd.open_sequence(source)
        frames = [seq[i] for i in range(len(seq))]
        refs = [rtd.read_exr(p)[..., :3] for p in ref_paths]
        for name, method, settings, envs in configs:
            for key in [k for k in os.environ if k.startswith("RTD_DEV_")]:
                del os.environ[key]
            os.environ.update(envs)
            r = evaluate(frames, refs, method, settings, 16)
            results.setdefault(folder, {})[name] = r
            print(f"{pathlib.Path(folder).name:<14} {name:<12} E {r['energy']:.3f} "
                  f"relMSE {r['rel_mse']:.4f} PSNR {r['psnr']:.2f} T {r['temporal']:.5f}",
                  flush=True)
    base = configs[0][0]
    print(f"means over {len(results)} sequences; ratios and gains against {base}")
    for name, *_ in configs:
        rows = [results[s][name] for s in results]
        ratio = np.exp(np.mean([np.log(results[s][name]["rel_mse"] / results[s][base]["rel_mse"])
                                for s in results]))
        gain = np.mean([results[s][name]["psnr"] - results[s][base]["psnr"] for s in results])
        temporal = np.mean([results[s][name]["temporal"] / results[s][base]["temporal"]
                            for s in results])
        print(f"{name:<12} E {np.mean([r['energy'] for r in rows]):.4f} "
              f"relMSE {np.mean([r['rel_mse'] for r in rows]):.4f} ratio {ratio:.3f} "
              f"PSNR {np.mean([r['psnr'] for r in rows]):.2f} gain {gain:+.3f} "
              f"T {np.mean([r['temporal'] for r in rows]):.5f} ratio {temporal:.3f}")
    if os.environ.get("EXP_JSON"):
        pathlib.Path(os.environ["EXP_JSON"]).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
