// Single-precision exp, log, erf and atan2 as branch-free polynomials [Moshier, Cephes
// 1984-1992, expf/logf/erff/erfcf/atanf]: inline, so that GCC vectorises them inside the
// multi-ISA kernels and batch loops, and shared by the scalar code, so that a kernel and the
// scalar path it replaces give the same bits (the build has no FMA contraction). Accuracy
// (checked against double precision in tests/cpp/test_poly_math.cpp): exp and log within
// 1e-7 relative, erf within 2e-7 absolute, atan2 within 3e-7 absolute. Not libm
// replacements: the domains are those stated per function.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "math.h"

namespace mvpt {

/// e^x for finite x; 0 below -87.3 (no denormals).
[[gnu::always_inline]] inline float exp_poly(float x) {
    // std::min(std::max(x, lo), hi) as selects (branches would stop vectorisation).
    float lo = select(x < -87.33654f, -87.33654f, x);
    float xc = select(88.3762626f < lo, 88.3762626f, lo);
    // x = n ln2 + r with |r| <= ln2 / 2; ln2 split in two for an exact n ln2 (Cody-Waite).
    float t = xc * 1.44269504088896341f;
    int32_t n = int32_t(t + select(t < 0.f, -0.5f, 0.5f));
    float fn = float(n);
    float r = (xc - fn * 0.693359375f) - fn * -2.12194440e-4f;
    float p = ((((1.9875691500e-4f * r + 1.3981999507e-3f) * r + 8.3334519073e-3f) * r + 4.1665795894e-2f) * r +
               1.6666665459e-1f) * r + 5.0000001201e-1f;
    p = (p * (r * r) + r) + 1.f;
    float scale = std::bit_cast<float>((n + 127) << 23);
    return select(x < -87.33654f, 0.f, p * scale);
}

/// Natural logarithm of a positive, normal, finite x.
[[gnu::always_inline]] inline float log_poly(float x) {
    // x = 2^e m with m in [sqrt(1/2), sqrt(2)); log(x) = e ln2 + log(m), log(m) by a polynomial in m - 1.
    int32_t bits = std::bit_cast<int32_t>(x);
    int32_t e = ((bits >> 23) & 0xff) - 126;
    float m = std::bit_cast<float>((bits & 0x007fffff) | 0x3f000000); // [0.5, 1)
    bool low = m < 0.707106781186547524f;
    e -= int32_t(low);
    m = select(low, (m + m) - 1.f, m - 1.f);
    float z = m * m;
    float y = (((((((7.0376836292e-2f * m - 1.1514610310e-1f) * m + 1.1676998740e-1f) * m - 1.2420140846e-1f) * m +
                  1.4249322787e-1f) * m - 1.6668057665e-1f) * m + 2.0000714765e-1f) * m - 2.4999993993e-1f) * m +
              3.3333331174e-1f;
    y = y * m * z;
    float fe = float(e);
    y = y + -2.12194440e-4f * fe;
    y = y + -0.5f * z;
    return (m + y) + 0.693359375f * fe;
}

/// The error function erf(x) for finite x.
[[gnu::always_inline]] inline float erf_poly(float x) {
    float a = std::abs(x), z = a * a;
    // |x| < 1: x T(x^2); else 1 - erfc(x), erfc(x) = e^{-x^2} / x P(1/x^2) (P for x < 2, R beyond).
    float small = ((((((7.853861353153693e-5f * z - 8.010193625184903e-4f) * z + 5.188327685732524e-3f) * z -
                       2.685381193529856e-2f) * z + 1.128358514861418e-1f) * z - 3.761262582423300e-1f) * z +
                   1.128379165726710f) * a;
    float q = 1.f / select(a < 1.f, 1.f, a), y = q * q;
    float p = ((((((((2.326819970068386e-2f * y - 1.387039388740657e-1f) * y + 3.687424674597105e-1f) * y -
                     5.824733027278666e-1f) * y + 6.210004621745983e-1f) * y - 4.944515323274145e-1f) * y +
                  3.404879937665872e-1f) * y - 2.741127028184656e-1f) * y + 5.638259427386472e-1f);
    float rr = (((((((-1.047766399936249e1f * y + 1.297719955372516e1f) * y - 7.495518717768503f) * y +
                    2.921019019210786f) * y - 1.015265279202700f) * y + 4.218463358204948e-1f) * y -
                 2.820767439740514e-1f) * y + 5.641895067754075e-1f);
    float erfc = (exp_poly(-z) * q) * select(a < 2.f, p, rr);
    return std::copysign(select(a < 1.f, small, 1.f - erfc), x);
}

/// The inverse error function on (-1, 1) [Giles, "Approximating the erfinv function", GPU
/// Computing Gems, 2010]: both of its polynomials (Estrin's scheme), then a select.
[[gnu::always_inline]] inline float erfinv_poly(float x) {
    float v = (1.f - x) * (1.f + x);
    float w = -log_poly(select(v < 1e-30f, 1e-30f, v)); // std::max(v, 1e-30f)
    auto poly8 = [](float v, float c0, float c1, float c2, float c3, float c4, float c5, float c6, float c7, float c8) {
        float v2 = v * v, v4 = v2 * v2;
        float p01 = c0 + c1 * v, p23 = c2 + c3 * v, p45 = c4 + c5 * v, p67 = c6 + c7 * v;
        return (p01 + p23 * v2) + (p45 + p67 * v2) * v4 + c8 * (v4 * v4);
    };
    float central = poly8(w - 2.5f, 1.50140941f, 0.246640727f, -0.00417768164f, -0.00125372503f, 0.00021858087f,
                          -4.39150654e-06f, -3.5233877e-06f, 3.43273939e-07f, 2.81022636e-08f);
    float tail = poly8(std::sqrt(w) - 3.f, 2.83297682f, 1.00167406f, 0.00943887047f, -0.0076224613f, 0.00573950773f,
                       -0.00367342844f, 0.00134934322f, 0.000100950558f, -0.000200214257f);
    return select(w < 5.f, central, tail) * x;
}

/// atan2(y, x) in [-pi, pi], with std::atan2's signs at zeros (atan2(+-0, -0) = +-pi) and 0
/// for (0, 0); x and y finite. atan of min/max(|x|, |y|) in [0, 1] (above tan(pi/8) through
/// atan(t) = pi/4 + atan((t - 1) / (t + 1))), then the octant.
[[gnu::always_inline]] inline float atan2_poly(float y, float x) {
    float ax = std::abs(x), ay = std::abs(y);
    bool y_major = ay > ax;
    float hi = select(y_major, ay, ax), lo = select(y_major, ax, ay);
    float t = select(hi > 0.f, lo / hi, 0.f);
    bool upper = t > 0.414213562373095f;
    t = select(upper, (t - 1.f) / (t + 1.f), t);
    float z = t * t;
    float r = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * t + t;
    r = r + select(upper, Pi / 4.f, 0.f);
    r = select(y_major, Pi / 2.f - r, r);
    r = select(std::signbit(x), Pi - r, r);
    return std::copysign(r, y);
}

} // namespace mvpt
