#!/usr/bin/env python3
# Per-channel statistics of scanline OpenEXR files (NONE, ZIPS or ZIP compression; HALF, FLOAT
# or UINT channels), in plain Python 3 (no numpy, no OpenEXR module): the checks of the Cycles
# validation scenes (tests/test_validation_scenes.sh) run anywhere Blender does.
#
#   scripts/blender/exr_stats.py FILE.exr [FILE.exr ...]          # a table per file
#   scripts/blender/exr_stats.py --json FILE.exr [FILE.exr ...]   # {file: {channel: stats}}
#   scripts/blender/exr_stats.py --diff A.exr B.exr CHANNEL       # fraction of pixels that differ
#
# Stats per channel: type, min, max, mean (over finite values), finite (count of non-finite
# values is `nonfinite`), nonzero (the fraction of values != 0).
import json
import math
import struct
import sys
import zlib

TYPES = {0: ("UINT", "I", 4), 1: ("HALF", "e", 2), 2: ("FLOAT", "f", 4)}
LINES_PER_BLOCK = {0: 1, 2: 1, 3: 16}


def _cstring(data, pos):
    end = data.index(b"\0", pos)
    return data[pos:end].decode("latin-1"), end + 1


def read_header(data):
    magic, version = struct.unpack_from("<ii", data, 0)
    if magic != 20000630:
        raise ValueError("not an OpenEXR file")
    if version & 0x1a00:  # tiled (0x200), deep (0x800), multipart (0x1000)
        raise ValueError("only single-part scanline files are supported")
    pos, header = 8, {}
    while data[pos] != 0:
        name, pos = _cstring(data, pos)
        kind, pos = _cstring(data, pos)
        (size,) = struct.unpack_from("<i", data, pos)
        pos += 4
        value = data[pos:pos + size]
        pos += size
        if kind == "chlist":
            channels, p = [], 0
            while value[p] != 0:
                channel, p = _cstring(value, p)
                pixel_type, _, xs, ys = struct.unpack_from("<iB3xii", value, p)
                p += 16
                if (xs, ys) != (1, 1):
                    raise ValueError(f"channel {channel}: subsampled channels are not supported")
                channels.append((channel, pixel_type))
            header[name] = channels
        elif kind == "compression":
            header[name] = value[0]
        elif kind == "box2i":
            header[name] = struct.unpack("<iiii", value)
        else:
            header[name] = (kind, value)
    return header, pos + 1


def _unzip(raw, expected):
    if len(raw) == expected:  # stored uncompressed when compression would not shrink it
        return raw
    t = bytearray(zlib.decompress(raw))
    for i in range(1, len(t)):
        t[i] = (t[i - 1] + t[i] - 128) & 0xff
    half = (len(t) + 1) // 2
    out = bytearray(len(t))
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return bytes(out)


def read_exr(path):
    """{channel: (type name, list of values, row-major, top row first)}, width, height."""
    with open(path, "rb") as f:
        data = f.read()
    header, pos = read_header(data)
    compression = header["compression"]
    if compression not in LINES_PER_BLOCK:
        raise ValueError(f"{path}: compression {compression} is not supported (NONE, ZIPS, ZIP)")
    x0, y0, x1, y1 = header["dataWindow"]
    width, height = x1 - x0 + 1, y1 - y0 + 1
    channels = header["channels"]
    lines = LINES_PER_BLOCK[compression]
    blocks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{blocks}Q", data, pos)
    values = {name: [] for name, _ in channels}
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        rows = min(lines, y1 - y + 1)
        expected = rows * width * sum(TYPES[t][2] for _, t in channels)
        block = data[offset + 8:offset + 8 + size]
        block = _unzip(block, expected) if compression in (2, 3) else block
        p = 0
        for _ in range(rows):
            for name, pixel_type in channels:
                _, code, bytes_per = TYPES[pixel_type]
                values[name].extend(struct.unpack_from(f"<{width}{code}", block, p))
                p += width * bytes_per
    return {name: (TYPES[t][0], values[name]) for name, t in channels}, width, height


def stats(kind, values):
    finite = [v for v in values if math.isfinite(v)]
    return {"type": kind,
            "min": min(finite) if finite else None,
            "max": max(finite) if finite else None,
            "mean": sum(finite) / len(finite) if finite else None,
            "nonfinite": len(values) - len(finite),
            "nonzero": sum(1 for v in values if v != 0) / max(1, len(values))}


def main(argv):
    if argv[:1] == ["--diff"] and len(argv) == 4:
        a, _, _ = read_exr(argv[1])
        b, _, _ = read_exr(argv[2])
        va, vb = a[argv[3]][1], b[argv[3]][1]
        print(sum(1 for x, y in zip(va, vb) if x != y) / max(1, len(va)))
        return 0
    as_json = argv[:1] == ["--json"]
    files = argv[1:] if as_json else argv
    if not files:
        print(__doc__ if __doc__ else "usage: exr_stats.py [--json] FILE.exr ...",
              file=sys.stderr)
        return 2
    result = {}
    for path in files:
        channels, width, height = read_exr(path)
        result[path] = {"width": width, "height": height,
                        "channels": {name: stats(*channels[name]) for name in channels}}
    if as_json:
        json.dump(result, sys.stdout, indent=1)
        print()
        return 0
    for path, info in result.items():
        print(f"{path}: {info['width']}x{info['height']}")
        for name, s in info["channels"].items():
            fmt = lambda v: "none" if v is None else f"{v:.6g}"
            print(f"  {name:36s} {s['type']:5s} min {fmt(s['min'])} max {fmt(s['max'])} "
                  f"mean {fmt(s['mean'])} nonzero {s['nonzero']:.3f} nonfinite {s['nonfinite']}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
