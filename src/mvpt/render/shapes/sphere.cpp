// Analytic sphere (Mitsuba's `sphere`): center + radius and/or a similarity
// `to_world`; uv = (phi / 2pi, theta / pi) in object space. Light sampling
// picks uniformly inside the visible cone from outside [Akalin, "Sampling the
// visible sphere"], uniformly by area from inside.
#include "../../core/simd.h"
#include "../../core/warp.h"
#include "analytic.h"
#include "instance.h"
#include "mesh.h"
#include "sphere.h"
#include "sphere_cone.h"

#include <cstring>
#include <limits>

namespace mvpt {

namespace {

/// Cheap exact-enough rejection of the ray segment o + t d, t in [tmin, tmax], against the
/// sphere (center c, squared radius r2 with a margin) without square root or division: the
/// squared distance to the center is convex along the ray, so the segment misses the sphere
/// when its point closest to the center lies outside. Most shadow rays (which stop just short
/// of a sampled point on the sphere) and passing rays end here; the margin leaves every case
/// that rounding could decide either way to the roots. Branch-free (selects), so that a loop
/// over a packet's lanes vectorises.
[[gnu::always_inline]] inline bool segment_misses(double cx, double cy, double cz, double r2, double ox, double oy,
                                                  double oz, double dx, double dy, double dz, double tmin, double tmax) {
    const double lx = ox - cx, ly = oy - cy, lz = oz - cz;
    const double dd = (dx * dx + dy * dy) + dz * dz, ld = (lx * dx + ly * dy) + lz * dz,
                 ll = (lx * lx + ly * ly) + lz * lz;
    // The segment's point closest to the center: beyond tmax, before tmin, or inside (then the
    // squared line distance times dd decides).
    const bool beyond = -ld >= tmax * dd, before = !beyond & (-ld <= tmin * dd);
    const bool line_misses = ll * dd - ld * ld > r2 * dd;
    const double t = select(beyond, tmax, tmin);
    const double px = lx + t * dx, py = ly + t * dy, pz = lz + t * dz;
    const bool end_misses = (std::abs(t) <= 1.7976931348623157e308) & ((px * px + py * py) + pz * pz > r2);
    return ((beyond | before) & end_misses) | (!(beyond | before) & line_misses);
}

/// segment_misses for the n lanes of an Embree packet (RTCRayN: n-wide structure of arrays
/// org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, time, tfar): t[i] = 0 for the valid lanes
/// that may hit, NaN for the others.
MVPT_MULTI_ISA void sphere_candidates(const float *r, size_t n, const int *valid, double cx, double cy, double cz,
                                      double r2, double *t) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (size_t i = 0; i < n; ++i) {
        bool misses = segment_misses(cx, cy, cz, r2, r[i], r[n + i], r[2 * n + i], r[4 * n + i], r[5 * n + i],
                                     r[6 * n + i], r[3 * n + i], r[8 * n + i]);
        t[i] = select((valid[i] == -1) & !misses, 0.0, nan);
    }
}

} // namespace

class Sphere final : public AnalyticShape {
public:
    Sphere(const Properties &props, const Transform &to_world) {
        Vec3f center = props.get_vector("center", Vec3f(0.f));
        float radius = props.get_float("radius", 1.f);
        m_flip_normals = props.get_bool("flip_normals", false);
        m_to_world = to_world * Transform::translate(center) * Transform::scale(Vec3f(radius));
        // Like Mitsuba: the radius is the length of the transformed x axis (a
        // non-uniform scale is not an ellipsoid), a mirroring flips the normals.
        const Matrix4 &m = m_to_world.matrix();
        m_center = {float(m.m[0][3]), float(m.m[1][3]), float(m.m[2][3])};
        m_radius = std::sqrt(m.m[0][0] * m.m[0][0] + m.m[1][0] * m.m[1][0] + m.m[2][0] * m.m[2][0]);
        if (!(m_radius > 0.0) || !std::isfinite(m_radius) || !m.is_finite())
            props.fail("radius", "the sphere's radius (after to_world) must be positive and finite");
        if (m.determinant3x3() < 0) m_flip_normals = !m_flip_normals;
        m_to_object = m_to_world.inverse();
        m_inv_area = float(1.0 / (4.0 * 3.14159265358979323846 * m_radius * m_radius));
        attach_shape_children(*this, props);
    }

    double intersect_t(const double o[3], const double d[3], double tmin, double tmax) const override {
        if (segment_misses(m_center.x, m_center.y, m_center.z, r2_margin(), o[0], o[1], o[2], d[0], d[1], d[2], tmin,
                           tmax))
            return std::nan("");
        return nearest_root(o, d, tmin, tmax);
    }

    /// A packet's lanes: the rejection test as one vector loop over all lanes, the roots
    /// (rarely needed: hits and near misses) lane by lane. Same results as intersect_t.
    void intersect_t_n(const RTCRayN *rays, unsigned n, const int *valid, double *t) const override {
        const float *r = reinterpret_cast<const float *>(rays);
        sphere_candidates(r, n, valid, m_center.x, m_center.y, m_center.z, r2_margin(), t);
        for (unsigned i = 0; i < n; ++i) {
            if (std::isnan(t[i])) continue;
            const double o[3] = {r[i], r[n + i], r[2 * n + i]}, d[3] = {r[4 * n + i], r[5 * n + i], r[6 * n + i]};
            t[i] = nearest_root(o, d, r[3 * n + i], r[8 * n + i]);
        }
    }

    void fill_interaction(const Ray &ray, float t, uint32_t, Vec2f, SurfaceInteraction &si) const override {
        // Re-solve in double and take the root Embree reported (its t is rounded to float).
        double o[3] = {ray.o.x, ray.o.y, ray.o.z}, d[3] = {ray.d.x, ray.d.y, ray.d.z}, tn, tf;
        double th = t;
        if (roots(o, d, tn, tf)) th = std::abs(tn - t) <= std::abs(tf - t) ? tn : tf;
        double p[3], len2 = 0;
        for (int i = 0; i < 3; ++i) {
            p[i] = o[i] + th * d[i] - m_center[i];
            len2 += p[i] * p[i];
        }
        double inv = len2 > 0 ? 1.0 / std::sqrt(len2) : 0.0;
        Normal3f n(float(p[0] * inv), float(p[1] * inv), float(p[2] * inv));
        si.t = t;
        si.p = m_center + n * float(m_radius); // re-projected onto the surface
        set_surface(si, n);
    }

    float area() const override { return 1.f / m_inv_area; }
    BoundingBox bounds() const override {
        BoundingBox b;
        b.expand(m_center - Vec3f(float(m_radius)));
        b.expand(m_center + Vec3f(float(m_radius)));
        return b;
    }
    SphereGeometry geometry() const { return {m_center, m_radius, m_flip_normals}; }

    ShapeSample sample_area(Vec2f u) const override {
        Normal3f n = warp::square_to_uniform_sphere(u);
        ShapeSample s;
        s.p = m_center + n * float(m_radius);
        s.n = m_flip_normals ? -n : n;
        if (sample_uv) s.uv = uv_of(s.p);
        s.pdf_a = m_inv_area;
        return s;
    }

    std::pair<ShapeSample, float> sample_solid_angle(Point3f ref, Vec2f u) const override {
        const float radius = float(m_radius);
        Vec3f dc = m_center - ref;
        float dc2 = squared_norm(dc);
        float radius_adj = cone_test_radius(radius, m_flip_normals);
        // Filled in place (one named result): returning a copied pair is slower.
        std::pair<ShapeSample, float> result;
        ShapeSample &s = result.first;
        float &pdf = result.second;
        if (dc2 > radius_adj * radius_adj) {
            // Outside: uniform direction in the cone subtended by the sphere.
            const SphereConeSample c = sample_sphere_cone(m_center, radius, ref, u);
            s.p = m_center + c.dir * radius;
            s.n = c.dir;
            pdf = c.pdf;
            if (squared_norm(s.p - ref) == 0.f) pdf = 0.f;
        } else {
            // Inside: uniform by area, converted to solid angle.
            Vec3f dir = warp::square_to_uniform_sphere(u);
            s.p = m_center + dir * radius;
            s.n = dir;
            Vec3f d = s.p - ref;
            float dist2 = squared_norm(d), cos_t = absdot(d, dir) / std::sqrt(dist2);
            pdf = cos_t > 0.f ? m_inv_area * dist2 / cos_t : 0.f;
        }
        if (m_flip_normals) s.n = -s.n;
        if (sample_uv) s.uv = uv_of(s.p);
        s.pdf_a = m_inv_area;
        return result;
    }

    float pdf_solid_angle(Point3f ref, const SurfaceInteraction &si) const override {
        float sin_alpha = float(m_radius) / norm(m_center - ref);
        if (sin_alpha < OneMinusEpsilon) return warp::square_to_uniform_cone_pdf(safe_sqrt(1.f - sin_alpha * sin_alpha));
        return area_to_solid_angle(m_inv_area, ref, si.p, si.n);
    }

private:
    /// The squared radius with segment_misses's margin.
    double r2_margin() const { return m_radius * m_radius * (1.0 + 1e-6); }

    /// The nearest root of the ray's quadratic in [tmin, tmax], or NaN.
    double nearest_root(const double o[3], const double d[3], double tmin, double tmax) const {
        double near_t, far_t;
        if (!roots(o, d, near_t, far_t)) return std::nan("");
        if (near_t >= tmin && near_t <= tmax) return near_t;
        if (far_t >= tmin && far_t <= tmax) return far_t;
        return std::nan("");
    }

    bool roots(const double o[3], const double d[3], double &near_t, double &far_t) const {
        // Intersect from the point of the ray closest to the center: the
        // quadratic is then well conditioned for far-away or large spheres
        // (Mitsuba's robust variant, in double precision).
        double l[3], dd = 0, ld = 0;
        for (int i = 0; i < 3; ++i) {
            l[i] = o[i] - double(m_center[i]);
            dd += d[i] * d[i];
            ld += l[i] * d[i];
        }
        if (!(dd > 0)) return false;
        double plane_t = -ld / dd, op[3], b = 0, c = 0;
        for (int i = 0; i < 3; ++i) {
            op[i] = l[i] + plane_t * d[i];
            b += 2.0 * op[i] * d[i];
            c += op[i] * op[i];
        }
        c -= m_radius * m_radius;
        if (!solve_quadratic(dd, b, c, near_t, far_t)) return false;
        near_t += plane_t;
        far_t += plane_t;
        return true;
    }

    /// dp/du = 2 pi (-y, x, 0), dp/dv = pi (z cos phi, z sin phi, -r) at the local point (x, y, z),
    /// r = |(x, y)|; at the poles dp/dv = pi (1, 0, 0).
    std::pair<Vec3f, Vec3f> uv_partials(uint32_t, Point3f p) const override {
        const Point3f local = m_to_object.point(p);
        const float r = std::sqrt(local.x * local.x + local.y * local.y);
        const Vec3f dv = r > 0.f ? Vec3f(local.z * local.x / r, local.z * local.y / r, -r) : Vec3f(1.f, 0.f, 0.f);
        return {m_to_world.vector({-local.y, local.x, 0.f}) * (2.f * Pi), m_to_world.vector(dv) * Pi};
    }

    Vec2f uv_of(Point3f p) const {
        Point3f local = m_to_object.point(p);
        float theta = safe_acos(local.z), phi = std::atan2(local.y, local.x);
        if (phi < 0.f) phi += 2.f * Pi;
        return {phi * InvTwoPi, theta * InvPi};
    }

    void set_surface(SurfaceInteraction &si, Normal3f n) const {
        Point3f local = m_to_object.point(si.p);
        float theta = safe_acos(local.z), phi = std::atan2(local.y, local.x);
        if (phi < 0.f) phi += 2.f * Pi;
        si.uv = {phi * InvTwoPi, theta * InvPi};
        Vec3f dp_du = m_to_world.vector({-local.y, local.x, 0.f}) * (2.f * Pi);
        si.n = m_flip_normals ? -n : n;
        si.sh_frame = frame_from_dpdu(si.n, dp_du);
    }

    Transform m_to_world, m_to_object;
    Point3f m_center;
    double m_radius = 1.0;
    float m_inv_area = 1.f;
    bool m_flip_normals = false;
};

std::optional<SphereGeometry> sphere_geometry(const Shape &shape) {
    if (auto *s = dynamic_cast<const Sphere *>(&shape)) return s->geometry();
    return std::nullopt;
}

MVPT_REGISTER_PLUGIN("shape", "sphere", [](const Properties &props, const LoadContext &) {
    return make_maybe_animated(props, [&](const Transform &to_world) { return std::make_shared<Sphere>(props, to_world); });
});

} // namespace mvpt
