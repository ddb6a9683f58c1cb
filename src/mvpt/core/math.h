// Small fixed-size vector math: Vec2f, Vec3f, Color3f, Frame.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

namespace mvpt {

inline constexpr float Pi = 3.14159265358979323846f;
inline constexpr float InvPi = 0.31830988618379067154f;
inline constexpr float InvTwoPi = 0.15915494309189533577f;
inline constexpr float InvFourPi = 0.07957747154594766788f;
inline constexpr float Infinity = std::numeric_limits<float>::infinity();
/// Largest float strictly below one: the upper end of every [0, 1) sample.
inline constexpr float OneMinusEpsilon = 0x1.fffffep-1f;

inline float sqr(float x) { return x * x; }
/// `mask ? a : b` by bit masking, for floats and doubles: no branch to mispredict when
/// `mask` depends on a random number, and loops using it vectorise.
template <typename T> inline T select_bits(bool mask, T a, T b) {
    using Bits = std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>;
    static_assert(sizeof(T) == sizeof(Bits));
    Bits m = Bits(0) - Bits(mask), ia, ib;
    std::memcpy(&ia, &a, sizeof(T));
    std::memcpy(&ib, &b, sizeof(T));
    Bits r = (ia & m) | (ib & ~m);
    T out;
    std::memcpy(&out, &r, sizeof(T));
    return out;
}
inline float select(bool mask, float a, float b) { return select_bits(mask, a, b); }
inline double select(bool mask, double a, double b) { return select_bits(mask, a, b); }
/// std::max(a, b) and std::min(a, b) as selects (the same result for every input, NaN
/// included), for code that one lane runs and the vector kernels run on many.
[[gnu::always_inline]] inline float max_of(float a, float b) { return select(a < b, b, a); }
[[gnu::always_inline]] inline float min_of(float a, float b) { return select(b < a, b, a); }
/// sqrt(max(x, 0)) with the maximum as a bit select (std::max's result for every input, NaN
/// included), so that loops using it vectorise.
inline float safe_sqrt(float x) { return std::sqrt(select(x < 0.f, 0.f, x)); }
inline float safe_acos(float x) { return std::acos(std::clamp(x, -1.f, 1.f)); }
inline float lerp(float t, float a, float b) { return a + t * (b - a); }
inline float deg_to_rad(float d) { return d * (Pi / 180.f); }

struct Vec2f {
    float x = 0, y = 0;
    Vec2f() = default;
    constexpr Vec2f(float x, float y) : x(x), y(y) {}
    float operator[](int i) const { return i == 0 ? x : y; }
    float &operator[](int i) { return i == 0 ? x : y; }
};
inline Vec2f operator+(Vec2f a, Vec2f b) { return {a.x + b.x, a.y + b.y}; }
inline Vec2f operator-(Vec2f a, Vec2f b) { return {a.x - b.x, a.y - b.y}; }
inline Vec2f operator*(Vec2f a, float s) { return {a.x * s, a.y * s}; }
inline Vec2f operator*(float s, Vec2f a) { return {a.x * s, a.y * s}; }

struct Vec3f {
    float x = 0, y = 0, z = 0;
    Vec3f() = default;
    constexpr Vec3f(float x, float y, float z) : x(x), y(y), z(z) {}
    constexpr explicit Vec3f(float s) : x(s), y(s), z(s) {}
    float operator[](int i) const { return (&x)[i]; }
    float &operator[](int i) { return (&x)[i]; }
    Vec3f operator-() const { return {-x, -y, -z}; }
    Vec3f &operator+=(Vec3f b) { x += b.x; y += b.y; z += b.z; return *this; }
    Vec3f &operator-=(Vec3f b) { x -= b.x; y -= b.y; z -= b.z; return *this; }
    Vec3f &operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
};
using Point3f = Vec3f;
using Normal3f = Vec3f;

inline Vec3f operator+(Vec3f a, Vec3f b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3f operator-(Vec3f a, Vec3f b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3f operator*(Vec3f a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3f operator*(float s, Vec3f a) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3f operator/(Vec3f a, float s) { float r = 1.f / s; return a * r; }
inline bool operator==(Vec3f a, Vec3f b) { return a.x == b.x && a.y == b.y && a.z == b.z; }
inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float absdot(Vec3f a, Vec3f b) { return std::abs(dot(a, b)); }
inline Vec3f cross(Vec3f a, Vec3f b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float squared_norm(Vec3f a) { return dot(a, a); }
inline float norm(Vec3f a) { return std::sqrt(dot(a, a)); }
inline Vec3f normalize(Vec3f a) { return a / norm(a); }
inline Vec3f vmin(Vec3f a, Vec3f b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3f vmax(Vec3f a, Vec3f b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline Vec3f lerp(float t, Vec3f a, Vec3f b) { return a + t * (b - a); }
inline bool all_finite(Vec3f a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
/// Reflect `wi` about normal `n` (both pointing away from the surface).
inline Vec3f reflect(Vec3f wi, Vec3f n) { return 2.f * dot(wi, n) * n - wi; }

/// Linear RGB radiance, reflectance or throughput.
struct Color3f {
    float r = 0, g = 0, b = 0;
    Color3f() = default;
    constexpr Color3f(float r, float g, float b) : r(r), g(g), b(b) {}
    constexpr explicit Color3f(float s) : r(s), g(s), b(s) {}
    float operator[](int i) const { return (&r)[i]; }
    float &operator[](int i) { return (&r)[i]; }
    Color3f &operator+=(Color3f o) { r += o.r; g += o.g; b += o.b; return *this; }
    Color3f &operator*=(Color3f o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
    Color3f &operator*=(float s) { r *= s; g *= s; b *= s; return *this; }
    bool is_black() const { return r == 0.f && g == 0.f && b == 0.f; }
    float max_value() const { return std::max(r, std::max(g, b)); }
    float min_value() const { return std::min(r, std::min(g, b)); }
    float mean() const { return (r + g + b) * (1.f / 3.f); }
    /// Rec. 709 luminance.
    float luminance() const { return 0.212671f * r + 0.715160f * g + 0.072169f * b; }
    bool is_finite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
};
using Spectrum = Color3f;
inline Color3f operator+(Color3f a, Color3f b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
inline Color3f operator-(Color3f a, Color3f b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
inline Color3f operator*(Color3f a, Color3f b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
inline Color3f operator/(Color3f a, Color3f b) { return {a.r / b.r, a.g / b.g, a.b / b.b}; }
inline Color3f operator*(Color3f a, float s) { return {a.r * s, a.g * s, a.b * s}; }
inline Color3f operator*(float s, Color3f a) { return {a.r * s, a.g * s, a.b * s}; }
inline Color3f operator/(Color3f a, float s) { float r = 1.f / s; return a * r; }
inline Color3f lerp(float t, Color3f a, Color3f b) { return a + (b - a) * t; }
inline Color3f cexp(Color3f a) { return {std::exp(a.r), std::exp(a.g), std::exp(a.b)}; }
inline Color3f csqrt(Color3f a) { return {safe_sqrt(a.r), safe_sqrt(a.g), safe_sqrt(a.b)}; }

/// Orthonormal basis (s, t, n); local coordinates have n = +z.
struct Frame {
    Vec3f s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};
    Frame() = default;
    Frame(Vec3f s, Vec3f t, Vec3f n) : s(s), t(t), n(n) {}
    /// Basis around a unit normal [Duff et al. 2017, "Building an orthonormal basis, revisited"].
    explicit Frame(Vec3f n_) : n(n_) {
        float sign = std::copysign(1.f, n.z);
        float a = -1.f / (sign + n.z), b = n.x * n.y * a;
        s = {1.f + sign * n.x * n.x * a, sign * b, -sign * n.x};
        t = {b, sign + n.y * n.y * a, -n.y};
    }
    Vec3f to_local(Vec3f v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3f to_world(Vec3f v) const { return s * v.x + t * v.y + n * v.z; }

    static float cos_theta(Vec3f w) { return w.z; }
    static float cos2_theta(Vec3f w) { return w.z * w.z; }
    static float sin2_theta(Vec3f w) { return std::max(0.f, 1.f - w.z * w.z); }
    static float sin_theta(Vec3f w) { return std::sqrt(sin2_theta(w)); }
    static float tan_theta(Vec3f w) { return sin_theta(w) / w.z; }
    static float tan2_theta(Vec3f w) { return sin2_theta(w) / (w.z * w.z); }
    static float cos_phi(Vec3f w) { float s = sin_theta(w); return s == 0.f ? 1.f : std::clamp(w.x / s, -1.f, 1.f); }
    static float sin_phi(Vec3f w) { float s = sin_theta(w); return s == 0.f ? 0.f : std::clamp(w.y / s, -1.f, 1.f); }
};

/// Ray with origin, direction, valid parameter range and scene time.
struct Ray {
    Point3f o;
    Vec3f d;
    float tmin = 0.f, tmax = Infinity;
    float time = 0.f;
    Point3f at(float t) const { return o + d * t; }
};

/// Offset used to leave a surface without self-intersection (scaled by coordinates).
inline float ray_epsilon(Point3f p) {
    float m = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z), 1.f});
    return m * 1e-4f;
}

} // namespace mvpt
