#!/usr/bin/env python3
"""Fits the polynomials of src/core/math.h that were fitted near 1 (near-minimax relative
error, Lawson's iteratively reweighted least squares on Chebyshev nodes; pure Python) and
prints their float coefficients, their relative error on the fitted interval (coefficients
rounded to float, evaluated in double) and the smallest value below it:

  acosSquaredFactorNearOne: acos(a)^2 = (1 - a) q(a), degree 3 on [0.6, 1]
  negLog2FactorNearOne:     -log2(a)  = (1 - a) L(a), degree 4 on [0.8, 1]

Usage: scripts/fit_polynomials.py
"""
import math
import struct


def to_float(v):
    return struct.unpack("f", struct.pack("f", v))[0]


def solve(a, b):
    n = len(a)
    m = [row[:] + [bb] for row, bb in zip(a, b)]
    for i in range(n):
        p = max(range(i, n), key=lambda r: abs(m[r][i]))
        m[i], m[p] = m[p], m[i]
        for r in range(n):
            if r != i:
                f = m[r][i] / m[i][i]
                for c in range(i, n + 1):
                    m[r][c] -= f * m[i][c]
    return [m[i][n] / m[i][i] for i in range(n)]


def lawson(xs, target, basis, weight, iterations=200):
    """Coefficients c minimising max |weight(x) (sum c_k basis_k(x) - target(x))| over xs."""
    w = [1.0 / len(xs)] * len(xs)
    k = len(basis(xs[0]))
    for _ in range(iterations):
        a = [[0.0] * k for _ in range(k)]
        b = [0.0] * k
        for x, wi in zip(xs, w):
            phi = [weight(x) * v for v in basis(x)]
            t = weight(x) * target(x)
            for i in range(k):
                b[i] += wi * phi[i] * t
                for j in range(k):
                    a[i][j] += wi * phi[i] * phi[j]
        c = solve(a, b)
        err = [abs(weight(x) * (sum(ci * v for ci, v in zip(c, basis(x))) - target(x)))
               for x in xs]
        total = sum(wi * e for wi, e in zip(w, err))
        w = [wi * e / total for wi, e in zip(w, err)]
    return c


def horner(coefficients, x):
    acc = coefficients[-1]
    for c in reversed(coefficients[:-1]):
        acc = acc * x + c
    return acc


def chebyshev_nodes(lo, hi, n=300):
    return [(lo + hi) / 2 + (hi - lo) / 2 * math.cos(math.pi * (i + 0.5) / n) for i in range(n)]


def fit_near_one(name, factor, lo, degree):
    xs = chebyshev_nodes(lo, 1.0)
    c = [to_float(v) for v in lawson(xs, factor, lambda a: [a**k for k in range(degree + 1)],
                                     lambda a: 1.0 / factor(a))]
    grid = [lo + (1.0 - lo) * i / 20000 for i in range(20001)]
    error = max(abs(horner(c, a) / factor(a) - 1.0) for a in grid)
    below = [(1.0 - a) * horner(c, a) for a in [-1.0 + (lo + 1.0) * i / 4000 for i in range(4001)]]
    growing = all(below[i] >= below[i + 1] for i in range(len(below) - 1))
    print(f"{name}: degree {degree} on [{lo}, 1], relative error {error:.2e}, "
          f"(1 - a) f(a) >= {min(below):.4f} below {lo} (growing as a falls: {growing})")
    print("    " + ", ".join(f"{v:.8e}f" for v in c))


def main():
    fit_near_one("acosSquaredFactorNearOne",
                 lambda a: math.acos(a) ** 2 / (1.0 - a) if a < 1.0 else 2.0, 0.6, 3)
    fit_near_one("negLog2FactorNearOne",
                 lambda a: -math.log2(a) / (1.0 - a) if a < 1.0 else 1.0 / math.log(2.0), 0.8, 4)


if __name__ == "__main__":
    main()
