// A perspective or thin-lens camera in one pose as plain data, and the shift geometry of
// docs/multiview-path-tracing.md §3–§4 computed from it. It is the one implementation
// behind PerspectiveCamera::shift_geometry, and lets multi-view path tracing shift a
// sample to every static view in one loop over contiguous data, without a virtual call
// or a pose evaluation per view (integrators/multiview/mv_candidates.*).
#pragma once

#include "camera.h"
#include "cameras/camera_pose.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace mvpt {

/// Pose and intrinsics of a perspective (pinhole) or thin-lens camera at one instant.
struct CameraProjection {
    CameraPose pose;
    float near_clip = 1e-2f, far_clip = 1e4f;
    float aperture_radius = 0.f;   ///< 0 for a pinhole
    float inv_focus_distance = 0.f;
    float tan_x = 1.f, tan_y = 1.f; ///< half-extent of the plane z = 1 seen by the full film
    float ppo_x = 0.f, ppo_y = 0.f; ///< principal point offset (fractions of the film size)
    float width = 1.f, height = 1.f; ///< full film size in pixels
    float film_distance = 1.f;     ///< f = (W/2) / tan(fov_x/2), in pixels

    /// Film position (pixels) of the point (qx, qy) of the plane z = 1 (Mitsuba's sample_to_camera
    /// inverted: film x grows to the camera's right = -x, film y downwards = -y).
    Vec2f film_from_plane(float qx, float qy) const {
        return {(0.5f * (1.f - qx / tan_x) - ppo_x) * width, (0.5f * (1.f - qy / tan_y) - ppo_y) * height};
    }
};

/// Number of scalars in a CameraProjection.
inline constexpr size_t ProjectionFields = 32;

/// The scalars of `c` in a fixed order (the inverse of `make_projection`).
inline void flatten(const CameraProjection &c, float out[ProjectionFields]) {
    const CameraPose &p = c.pose;
    const float v[ProjectionFields] = {p.origin.x,  p.origin.y,  p.origin.z,  p.axis[0].x, p.axis[0].y, p.axis[0].z,
                                       p.axis[1].x, p.axis[1].y, p.axis[1].z, p.axis[2].x, p.axis[2].y, p.axis[2].z,
                                       p.inv_row[0].x, p.inv_row[0].y, p.inv_row[0].z, p.inv_row[1].x, p.inv_row[1].y,
                                       p.inv_row[1].z, p.inv_row[2].x, p.inv_row[2].y, p.inv_row[2].z, c.near_clip,
                                       c.far_clip, c.aperture_radius, c.inv_focus_distance, c.tan_x, c.tan_y, c.ppo_x,
                                       c.ppo_y, c.width, c.height, c.film_distance};
    std::copy(v, v + ProjectionFields, out);
}

/// The CameraProjection whose scalars (in the order of `flatten`) are d[0], d[stride],
/// d[2 stride], ... (a column of a ProjectionTable).
[[gnu::always_inline]] inline CameraProjection make_projection(const float *d, size_t stride) {
    CameraProjection c;
    CameraPose &p = c.pose;
    p.origin = {d[0], d[stride], d[2 * stride]};
    p.axis[0] = {d[3 * stride], d[4 * stride], d[5 * stride]};
    p.axis[1] = {d[6 * stride], d[7 * stride], d[8 * stride]};
    p.axis[2] = {d[9 * stride], d[10 * stride], d[11 * stride]};
    p.inv_row[0] = {d[12 * stride], d[13 * stride], d[14 * stride]};
    p.inv_row[1] = {d[15 * stride], d[16 * stride], d[17 * stride]};
    p.inv_row[2] = {d[18 * stride], d[19 * stride], d[20 * stride]};
    c.near_clip = d[21 * stride], c.far_clip = d[22 * stride];
    c.aperture_radius = d[23 * stride], c.inv_focus_distance = d[24 * stride];
    c.tan_x = d[25 * stride], c.tan_y = d[26 * stride], c.ppo_x = d[27 * stride], c.ppo_y = d[28 * stride];
    c.width = d[29 * stride], c.height = d[30 * stride], c.film_distance = d[31 * stride];
    return c;
}

/// The shared vertex y as every camera's shift reads it: its point, its normal n_y (zero for
/// a point in a medium) and 1/|n_y| (1 in a medium), the division made once per vertex and
/// not in a loop over cameras, where a division under a condition keeps the loop from
/// vectorising without AVX-512's masks.
struct ShiftVertex {
    Point3f p;
    Normal3f n;
    float inv_n;
    float in_medium; ///< 1 for a point in a medium, else 0
    ShiftVertex(Point3f y, Normal3f n_y) : p(y), n(n_y) {
        const float n_norm = norm(n_y);
        inv_n = n_norm > 0.f ? 1.f / n_norm : 1.f;
        in_medium = n_norm > 0.f ? 0.f : 1.f;
    }
};

/// Camera::shift_geometry for camera `c` (design doc §3 projection through the focus plane,
/// §4 film density G = f^2 cos(phi) / (cos^3(theta) d^2); a zero normal makes y a point in a
/// medium, with G per unit volume and length f^2 / (cos^3(theta) d^2), §10). False when y's camera-space depth
/// lies outside [near, far]; `out` then holds meaningless values. Branch-free (a pinhole is a
/// lens of radius 0), so that the loop over a ProjectionTable vectorises over cameras.
[[gnu::always_inline]] inline bool shift_geometry(const CameraProjection &c, const ShiftVertex &v, Vec2f lens, ShiftGeometry *out) {
    const Point3f y = v.p;
    Point3f p = c.pose.to_camera(y);
    // Thin lens: the ray u -> p meets the focus plane z = f_d at P = u + (p - u) f_d / p.z, and
    // q = P / f_d = u (1/f_d - 1/p.z) + p / p.z; a pinhole (u = 0) gives q = p / p.z.
    float inv_z = 1.f / p.z;
    float k = c.aperture_radius * (c.inv_focus_distance - inv_z);
    float qx = p.x * inv_z + lens.x * k, qy = p.y * inv_z + lens.y * k;
    float ux = lens.x * c.aperture_radius, uy = lens.y * c.aperture_radius;
    out->lens_point = c.pose.origin + c.pose.axis[0] * ux + c.pose.axis[1] * uy;
    out->film = c.film_from_plane(qx, qy);
    // With w = y - u (|w| = d, camera-space depth p.z as the lens is in the plane z = 0),
    // cos(theta) = p.z / d and cos(phi) = |n.w| / (|n| d), so G = f^2 |n.w| / (|n| p.z^3).
    Vec3f w = y - out->lens_point;
    float d = std::sqrt(sqr(p.x - ux) + sqr(p.y - uy) + sqr(p.z));
    // d cos(phi) = |n.w| / |n|, or d in a medium (a zero normal).
    const float n_w = absdot(v.n, w) + v.in_medium * d; // |n.w| on a surface (+ 0 d, exact for finite d), d in a medium
    out->density = sqr(c.film_distance) * n_w * v.inv_n * (inv_z * inv_z * inv_z);
    // Up to the near plane: d - near / cos(theta).
    out->visible_length = d * (1.f - c.near_clip * inv_z);
    return (p.z >= c.near_clip) & (p.z <= c.far_clip);
}

/// Many static cameras' projections as a structure of arrays (field-major), for
/// the vector loop of shift_static_views (integrators/multiview/mv_candidates.cpp).
class ProjectionTable {
public:
    ProjectionTable() = default;
    explicit ProjectionTable(const std::vector<CameraProjection> &cams) : m_size(cams.size()), m_data(ProjectionFields * m_size) {
        for (size_t k = 0; k < m_size; ++k) {
            float v[ProjectionFields];
            flatten(cams[k], v);
            for (size_t f = 0; f < ProjectionFields; ++f) m_data[f * m_size + k] = v[f];
        }
    }
    size_t size() const { return m_size; }
    const float *data() const { return m_data.data(); }
    /// Camera k of a table of `size` cameras whose arrays are `data`.
    [[gnu::always_inline]] static CameraProjection at(const float *data, size_t size, size_t k) {
        return make_projection(data + k, size);
    }

private:
    size_t m_size = 0;
    std::vector<float> m_data;
};

} // namespace mvpt
