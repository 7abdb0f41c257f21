"""Stage 6: the weights file of docs/learned_spec.md, written and read back.

    write_weights(path, arrays, trained)    arrays: w1 (16x14) b1 w2 (16x16) b2 w3 (6x16) b3,
                                            normalisation already folded (model.folded())
    load_weights(path) -> dict              the arrays (float32) and "trained"; raises
                                            WeightsError naming the problem (header, shape,
                                            counts, checksum)
    python3 training/export.py WEIGHTS      checks a file and prints its summary

The file: 'rtdenoise-weights 2', 'network learned-mix 14 16 16 6', 'range l0-margin 2' (the
model's L0_NOISE_MARGIN: the range the network was trained for), 'trained <text>', the blocks
w1 b1 w2 b2 w3 b3 ('%.9g' floats, whitespace separated; a block may span lines: here one matrix
row per line), then 'fnv1a32 <8 lowercase hex>': FNV-1a 32-bit of every byte before that line.
"""

import os
import re
import sys

import numpy as np

from model import L0_NOISE_MARGIN

MAGIC = "rtdenoise-weights 2"
NETWORK = "network learned-mix 14 16 16 6"
RANGE = f"range l0-margin {L0_NOISE_MARGIN:g}"
SHAPES = {"w1": (16, 14), "b1": (16,), "w2": (16, 16), "b2": (16,), "w3": (6, 16), "b3": (6,)}
BLOCKS = list(SHAPES)


class WeightsError(ValueError):
    pass


def fnv1a32(data: bytes) -> int:
    h = 0x811C9DC5
    for byte in data:
        h ^= byte
        h = (h * 0x01000193) & 0xFFFFFFFF
    return h


def _format(value) -> str:
    return "%.9g" % float(np.float32(value))


def weights_text(arrays, trained: str) -> str:
    trained = " ".join(str(trained).split())  # one line
    lines = [MAGIC, NETWORK, RANGE, f"trained {trained or '(not described)'}"]
    for name, shape in SHAPES.items():
        a = np.asarray(arrays[name], dtype=np.float32)
        if a.shape != shape:
            raise WeightsError(f"{name}: shape {a.shape}, expected {shape}")
        if not np.all(np.isfinite(a)):
            raise WeightsError(f"{name}: non-finite values")
        rows = a.reshape(shape[0], -1) if len(shape) == 2 else a.reshape(1, -1)
        for i, row in enumerate(rows):
            values = " ".join(_format(v) for v in row)
            lines.append(f"{name} {values}" if i == 0 else values)
    body = "\n".join(lines) + "\n"
    return body + "fnv1a32 %08x\n" % fnv1a32(body.encode("utf-8"))


def write_weights(path, arrays, trained: str):
    text = weights_text(arrays, trained)
    tmp = f"{path}.partial"
    with open(tmp, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
    os.replace(tmp, path)
    load_weights(path)  # what was written reads back
    return path


def load_weights(path):
    """Reads and verifies a weights file; returns {"w1": ..., ..., "trained": str}."""
    with open(path, "rb") as f:
        data = f.read()
    where = os.fspath(path)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise WeightsError(f"{where}: not UTF-8 ({e})") from None
    marker = text.rfind("\nfnv1a32 ")
    if marker < 0:
        raise WeightsError(f"{where}: no 'fnv1a32' checksum line (truncated?)")
    body, last = text[: marker + 1], text[marker + 1:]
    m = re.fullmatch(r"fnv1a32 ([0-9a-f]{8})\n?", last)
    if not m:
        raise WeightsError(f"{where}: the checksum line is not 'fnv1a32 <8 lowercase hex "
                           f"digits>' at the end of the file: {last[:40]!r}")
    expected, actual = int(m.group(1), 16), fnv1a32(body.encode("utf-8"))
    lines = body.split("\n")[:-1]
    if lines and lines[0] == "rtdenoise-weights 1":
        raise WeightsError(f"{where}: format 1, which does not record the range its network was "
                           f"trained for; expected {MAGIC!r} (retrain it: training/README.md)")
    if len(lines) < 4 or lines[0] != MAGIC:
        first = lines[0][:40] if lines else ""
        raise WeightsError(f"{where}: header {first!r}, expected {MAGIC!r}")
    if lines[1] != NETWORK:
        raise WeightsError(f"{where}: network {lines[1][:60]!r}, expected {NETWORK!r}")
    if lines[2] != RANGE:
        raise WeightsError(f"{where}: range {lines[2][:60]!r}, expected {RANGE!r} (a network "
                           f"trained for another range: retrain it)")
    if not lines[3].startswith("trained "):
        raise WeightsError(f"{where}: line 4 is not the 'trained' line: {lines[3][:40]!r}")
    values, order, current = {}, [], None
    for number, line in enumerate(lines[4:], start=5):
        words = line.split()
        if words and words[0] in SHAPES:
            current = words[0]
            if current in values:
                raise WeightsError(f"{where}:{number}: block {current} twice")
            order.append(current)
            values[current] = []
            words = words[1:]
        elif current is None:
            raise WeightsError(f"{where}:{number}: {line[:40]!r} before the first block")
        for word in words:
            try:
                values[current].append(float(word))
            except ValueError:
                raise WeightsError(f"{where}:{number}: {word[:20]!r} in {current} is not a "
                                   f"number") from None
    if order != BLOCKS:
        raise WeightsError(f"{where}: blocks {' '.join(order)}, expected {' '.join(BLOCKS)}")
    out = {"trained": lines[3][len("trained "):]}
    for name, shape in SHAPES.items():
        count = int(np.prod(shape))
        if len(values[name]) != count:
            raise WeightsError(f"{where}: {name} holds {len(values[name])} values, expected "
                               f"{count}")
        a = np.array(values[name], dtype=np.float64)
        if not np.all(np.isfinite(a)) or np.any(np.abs(a) > np.finfo(np.float32).max):
            raise WeightsError(f"{where}: {name} holds non-finite values")
        out[name] = a.astype(np.float32).reshape(shape)
    if expected != actual:
        raise WeightsError(f"{where}: checksum fnv1a32 {expected:08x} in the file, {actual:08x} "
                           f"of its contents (the file was changed or damaged)")
    return out


def checksum_of(path) -> str:
    """The file's recorded fnv1a32 (after verifying it)."""
    load_weights(path)
    with open(path, encoding="utf-8") as f:
        return f.read().rstrip("\n").rsplit("\n", 1)[1].split()[1]


def export_model(model, path, trained: str):
    return write_weights(path, model.folded(), trained)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: export.py WEIGHTS (verifies the file)")
    try:
        w = load_weights(sys.argv[1])
    except WeightsError as e:
        sys.exit(f"export.py: {e}")
    print(f"{sys.argv[1]}: valid (fnv1a32 {checksum_of(sys.argv[1])}); trained: {w['trained']}")
    for name in BLOCKS:
        print(f"  {name} {w[name].shape} |max| {np.abs(w[name]).max():.4g}")
