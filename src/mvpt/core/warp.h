// Warps from the unit square to common domains, with their densities.
#pragma once

#include "math.h"

namespace mvpt::warp {

/// (sin a, cos a) for |a| <= pi/4 by Cephes' minimax polynomials (sinf.c, cosf.c; about
/// 1 ulp): no range reduction, so no branch, unlike std::sin/std::cos.
inline Vec2f sincos_quarter_turn(float a) {
    float z = a * a;
    float s = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * a + a;
    float c = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z - 0.5f * z + 1.f;
    return {s, c};
}

/// (sin 2πu, cos 2πu) for u in [0, 1) without libm: the nearest quarter turn q/4 is taken
/// out exactly (u is a multiple of 2^-24), the rest (|angle| <= pi/4) goes to
/// sincos_quarter_turn, and the quadrant rotates the pair. Branch-free, so vector loops
/// (integrators/path/path_kernels.cpp) compute the same bits as scalar code.
inline Vec2f sincos_turn(float u) {
    int quadrant = int(4.f * u + 0.5f); // the nearest quarter turn (u >= 0)
    Vec2f sc = sincos_quarter_turn((2.f * Pi) * (u - 0.25f * float(quadrant)));
    quadrant &= 3;
    // Rotation by quadrant * pi/2: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
    bool odd = (quadrant & 1) != 0, neg_sin = quadrant >= 2, neg_cos = quadrant == 1 || quadrant == 2;
    float s = select(odd, sc.y, sc.x), c = select(odd, sc.x, sc.y);
    return {select(neg_sin, -s, s), select(neg_cos, -c, c)};
}

/// Concentric map to the unit disk [Shirley & Chiu 1997]; density 1/pi.
inline Vec2f square_to_uniform_disk_concentric(Vec2f u) {
    float x = 2.f * u.x - 1.f, y = 2.f * u.y - 1.f;
    const bool centre = (x == 0.f) & (y == 0.f); // selected, not branched on: vector loops use this
    // phi = pi/4 (y/x) when |x| > |y|, else pi/2 - pi/4 (x/y) = pi/2 + a with
    // a = -pi/4 (x/y), whose cosine is -sin a and sine cos a. Both quotients are computed
    // and one selected (the comparison is unpredictable); the discarded one may be infinite.
    bool x_major = std::abs(x) > std::abs(y);
    float r = select(x_major, x, y);
    Vec2f sc = sincos_quarter_turn((Pi / 4.f) * select(x_major, y / x, -(x / y)));
    return {select(centre, 0.f, r * select(x_major, sc.y, -sc.x)), select(centre, 0.f, r * select(x_major, sc.x, sc.y))};
}

/// Cosine-weighted hemisphere around +z; density cos(theta)/pi.
inline Vec3f square_to_cosine_hemisphere(Vec2f u) {
    Vec2f p = square_to_uniform_disk_concentric(u);
    float z = safe_sqrt(1.f - p.x * p.x - p.y * p.y);
    return {p.x, p.y, z};
}
/// The cosine-weighted hemisphere's density at a direction whose cosine is cos_theta.
[[gnu::always_inline]] inline float cosine_hemisphere_pdf(float cos_theta) {
    return select(cos_theta > 0.f, cos_theta * InvPi, 0.f);
}
inline float square_to_cosine_hemisphere_pdf(Vec3f v) { return cosine_hemisphere_pdf(v.z); }

inline Vec3f square_to_uniform_sphere(Vec2f u) {
    float z = 1.f - 2.f * u.y;
    float r = safe_sqrt(1.f - z * z), phi = 2.f * Pi * u.x;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline float square_to_uniform_sphere_pdf() { return InvFourPi; }

inline Vec3f square_to_uniform_hemisphere(Vec2f u) {
    float z = u.y;
    float r = safe_sqrt(1.f - z * z), phi = 2.f * Pi * u.x;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline float square_to_uniform_hemisphere_pdf(Vec3f v) { return v.z > 0.f ? InvTwoPi : 0.f; }

/// Uniform directions in the cone of half-angle acos(cos_max) around +z.
inline Vec3f square_to_uniform_cone(Vec2f u, float cos_max) {
    float cos_t = (1.f - u.y) + u.y * cos_max;
    float sin_t = safe_sqrt(1.f - cos_t * cos_t), phi = 2.f * Pi * u.x;
    return {sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
}
inline float square_to_uniform_cone_pdf(float cos_max) { return 1.f / (2.f * Pi * (1.f - cos_max)); }

/// Uniform barycentrics (b1, b2) on a triangle [Heitz 2019 low-distortion map].
inline Vec2f square_to_uniform_triangle(Vec2f u) {
    // Branch-free (the comparison of two random numbers is unpredictable): the halved
    // coordinate is the smaller one's, the other is reduced by it.
    bool x_smaller = u.x < u.y;
    float half = std::min(u.x, u.y) / 2.f;
    float rest = std::max(u.x, u.y) - half;
    return {select(x_smaller, half, rest), select(x_smaller, rest, half)};
}

/// Standard normal via Box-Muller, first coordinate only.
inline float square_to_std_normal(Vec2f u) {
    float r = std::sqrt(-2.f * std::log(std::max(1.f - u.x, 1e-12f)));
    return r * std::cos(2.f * Pi * u.y);
}

} // namespace mvpt::warp
