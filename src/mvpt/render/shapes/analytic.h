// Base of the analytic shapes (sphere, disk, cylinder): one Embree user
// geometry primitive whose intersect/occluded callbacks pass Embree's ray
// packets to `intersect_t_n` (by default `intersect_t` lane by lane).
#pragma once

#include "../../core/plugin.h"
#include "../shape.h"

#include <cmath>

namespace mvpt {

class AnalyticShape : public Shape {
public:
    unsigned attach(RTCDevice device, RTCScene scene, const MotionTime &motion) override;

    /// Nearest hit parameter in [tmin, tmax] along `o + t d` (d need not be unit), or NaN.
    virtual double intersect_t(const double o[3], const double d[3], double tmin, double tmax) const = 0;

    /// intersect_t of the lanes of an Embree ray packet (n lanes, structure of arrays) that
    /// `valid` marks with -1; NaN for the others. The default calls intersect_t lane by lane.
    virtual void intersect_t_n(const RTCRayN *rays, unsigned n, const int *valid, double *t) const;
};

/// Roots of a x^2 + b x + c = 0 (near <= far), numerically stable (the
/// "citardauq" form [Press et al., Numerical Recipes §5.6]); false if none.
inline bool solve_quadratic(double a, double b, double c, double &near_t, double &far_t) {
    if (a == 0.0) {
        if (b == 0.0) return false;
        near_t = far_t = -c / b;
        return true;
    }
    double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return false;
    double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
    near_t = std::min(t0, t1);
    far_t = std::max(t0, t1);
    return true;
}

/// Shading frame from dp/du (Mitsuba's `initialize_sh_frame`), falling back to any frame around `n`.
inline Frame frame_from_dpdu(Normal3f n, Vec3f dp_du) {
    Vec3f s = dp_du - n * dot(n, dp_du);
    float l = norm(s);
    if (!(l > 1e-12f) || !std::isfinite(l)) return Frame(n);
    s = s / l;
    return Frame(s, cross(n, s), n);
}

/// Double-precision point/vector transforms for the intersection routines.
inline void xform_point(const Matrix4 &m, const double p[3], double out[3]) {
    for (int i = 0; i < 3; ++i) out[i] = m.m[i][0] * p[0] + m.m[i][1] * p[1] + m.m[i][2] * p[2] + m.m[i][3];
}
inline void xform_vector(const Matrix4 &m, const double v[3], double out[3]) {
    for (int i = 0; i < 3; ++i) out[i] = m.m[i][0] * v[0] + m.m[i][1] * v[1] + m.m[i][2] * v[2];
}

} // namespace mvpt
