#!/usr/bin/env python3
"""Writes LAMBDA_POLY of crates/brdf/src/microfacet/beckmann.rs (needs mpmath).

H(x) = Λ(a) e^{a²} a³ with x = 1/a on [0, 0.8] (a ≥ 1.25), where
Λ(a) = (e^{−a²}/(a√π) − erfc a)/2 is Beckmann's Smith Λ. Chebyshev interpolation of
degree 28 at the Chebyshev points of the first kind, in 50-digit arithmetic, converted
to powers of τ = 2x/0.8 − 1. Prints the Rust array and the largest relative error of
its f64 Horner evaluation on 4001 points (1.2e-15 when written).

With `near`, LAMBDA_POLY_NEAR instead: degree 12 on [0, 0.3] (a ≥ 3.33), for the sums
1 + Λ of the conductor and the sampler, where Λ < 4·10⁻⁸ and an absolute error of
Λ below 10⁻¹⁸ is below a hundredth of an ulp of the sum; it also prints that largest
absolute error of Λ (2.2e-19 when written).

    python3 crates/brdf/scripts/beckmann_lambda_poly.py [near]
"""
import sys

import mpmath as mp

mp.mp.dps = 50
NEAR = sys.argv[1:] == ["near"]
LO, HI, DEG = (mp.mpf(0), mp.mpf("0.3"), 12) if NEAR else (mp.mpf(0), mp.mpf("0.8"), 28)


def scaled(x):
    if x == 0:
        return 1 / (4 * mp.sqrt(mp.pi))
    a = 1 / mp.mpf(x)
    return (1 / (a * mp.sqrt(mp.pi)) - mp.exp(a * a) * mp.erfc(a)) / 2 * a**3


def fit():
    n = DEG + 1
    nodes = [mp.cos(mp.pi * (k + mp.mpf(1) / 2) / n) for k in range(n)]
    values = [scaled((HI + LO) / 2 + (HI - LO) / 2 * t) for t in nodes]
    cheb = []
    for j in range(n):
        s = sum(values[k] * mp.cos(mp.pi * j * (k + mp.mpf(1) / 2) / n) for k in range(n))
        cheb.append(2 * s / n if j else s / n)
    # Chebyshev polynomials as power series, by T_j = 2τ T_{j−1} − T_{j−2}.
    t_pow = [[mp.mpf(1)], [mp.mpf(0), mp.mpf(1)]]
    for j in range(2, n):
        a = [mp.mpf(0)] + [2 * v for v in t_pow[j - 1]]
        b = t_pow[j - 2] + [mp.mpf(0)] * (len(a) - len(t_pow[j - 2]))
        t_pow.append([x - y for x, y in zip(a, b)])
    mono = [mp.mpf(0)] * n
    for j in range(n):
        for i, v in enumerate(t_pow[j]):
            mono[i] += cheb[j] * v
    return [float(v) for v in mono]


def main():
    coef = fit()
    worst = worst_abs = 0.0
    for i in range(4001):
        x = float(HI) * i / 4000
        tau = x * (2 / float(HI)) - 1
        p = 0.0
        for v in reversed(coef):
            p = p * tau + v
        ref = scaled(x)
        worst = max(worst, abs(float((p - ref) / ref)))
        if x > 0:
            lam = mp.exp(-1 / mp.mpf(x) ** 2) * mp.mpf(x) ** 3
            worst_abs = max(worst_abs, abs(float((p - ref) * lam)))
    name = "LAMBDA_POLY_NEAR" if NEAR else "LAMBDA_POLY"
    print(f"static {name}: [f64; {len(coef)}] = [")
    for v in coef:
        print(f"    {v!r},")
    print("];")
    print(f"// largest relative error of the f64 evaluation: {worst:.2e}")
    print(f"// largest absolute error of Λ = e^(-1/x²) x³ H(x): {worst_abs:.2e}")


if __name__ == "__main__":
    main()
