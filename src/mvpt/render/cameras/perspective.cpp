// Perspective (pinhole) and thin-lens cameras, Mitsuba's `perspective` and
// `thinlens` sensors: camera space has +z forward, +x left, +y up. `to_world` may be
// keyframed (<animation>): the pose is then evaluated at each ray's time.
#include "../../core/simd.h"
#include "../../core/plugin.h"
#include "../camera.h"
#include "../camera_projection.h"
#include "camera_pose.h"
#include "field_of_view.h"
#include "sensor_common.h"

#include <cmath>

namespace mvpt {

namespace {

/// PerspectiveCamera::ray_in_pose for a static pinhole camera over n film positions, as a
/// vector loop (the same operations in the same order: bit-identical rays).
MVPT_MULTI_ISA void pinhole_kernel(const CameraProjection &proj, float width, float height,
                                   const float *__restrict fx, const float *__restrict fy, size_t n,
                                   float *__restrict dx, float *__restrict dy, float *__restrict dz,
                                   float *__restrict tmin, float *__restrict tmax) {
    const CameraPose &pose = proj.pose;
    for (size_t i = 0; i < n; ++i) {
        float u = fx[i] / width + proj.ppo_x, v = fy[i] / height + proj.ppo_y;
        float px = -(2.f * u - 1.f) * proj.tan_x, py = -(2.f * v - 1.f) * proj.tan_y, pz = 1.f;
        float inv_n = 1.f / std::sqrt(px * px + py * py + pz * pz);
        float cx = px * inv_n, cy = py * inv_n, cz = pz * inv_n;
        float inv_z = 1.f / cz;
        float wx = (pose.axis[0].x * cx + pose.axis[1].x * cy) + pose.axis[2].x * cz;
        float wy = (pose.axis[0].y * cx + pose.axis[1].y * cy) + pose.axis[2].y * cz;
        float wz = (pose.axis[0].z * cx + pose.axis[1].z * cy) + pose.axis[2].z * cz;
        float inv_w = 1.f / std::sqrt(wx * wx + wy * wy + wz * wz);
        dx[i] = wx * inv_w;
        dy[i] = wy * inv_w;
        dz[i] = wz * inv_w;
        tmin[i] = proj.near_clip * inv_z;
        tmax[i] = proj.far_clip * inv_z;
    }
}

} // namespace

class PerspectiveCamera final : public Camera {
public:
    PerspectiveCamera(const Properties &props, bool thin_lens) {
        read_sensor_common(*this, props);
        m_to_world = props.get_animated_transform("to_world");
        // Every pose must be a rigid motion: no scale or shear (Mitsuba's has_scale, tolerance 1e-3).
        // Keyframes that are rigid interpolate (slerp + lerp) to rigid poses.
        for (const TransformKey &k : m_to_world.keys())
            if (!is_rigid(k.original.matrix()))
                props.fail("to_world", m_to_world.is_animated()
                                           ? "the keyframe at time " + std::to_string(k.time) +
                                                 " of a sensor's 'to_world' must be a rigid motion: scale or shear is not allowed"
                                           : "'to_world' of a sensor must be a rigid motion: scale or shear is not allowed");
        m_animated = m_to_world.is_animated();
        m_proj.pose = CameraPose(m_to_world.eval(shutter_open));
        m_proj.near_clip = props.get_float("near_clip", 1e-2f);
        m_proj.far_clip = props.get_float("far_clip", 1e4f);
        if (!(m_proj.near_clip > 0.f) || !(m_proj.far_clip > m_proj.near_clip))
            props.fail("near_clip", "need 0 < near_clip < far_clip, got " + std::to_string(m_proj.near_clip) + " and " +
                                        std::to_string(m_proj.far_clip));
        m_focus_distance = props.get_float("focus_distance", m_proj.far_clip);
        if (thin_lens) {
            m_proj.aperture_radius = props.get_float("aperture_radius");
            if (!(m_proj.aperture_radius >= 0.f)) props.fail("aperture_radius", "'aperture_radius' must be >= 0");
            if (!(m_focus_distance > 0.f)) props.fail("focus_distance", "'focus_distance' must be > 0");
        }
        read_field_of_view(props, film.width, film.height, &m_proj.tan_x, &m_proj.tan_y);
        // Off-axis (sheared) frustum: Mitsuba's principal_point_offset_x/_y, in units of the
        // full film's width/height, are added to the film position before it is mapped to the
        // near plane (so +x moves the image content left). Mitsuba 3 has them on `perspective`
        // only; mvpt also accepts them on `thinlens` (camera rigs shear thin-lens views too).
        m_proj.ppo_x = props.get_float("principal_point_offset_x", 0.f);
        m_proj.ppo_y = props.get_float("principal_point_offset_y", 0.f);
        // Pixels are square for every fov_axis (tan_x / W == tan_y / H), so one film distance serves.
        m_proj.film_distance = 0.5f * float(film.width) / m_proj.tan_x;
        m_proj.inv_focus_distance = 1.f / m_focus_distance;
        m_proj.width = float(film.width);
        m_proj.height = float(film.height);
    }

    Ray generate_ray(Vec2f film_pos, Vec2f lens, float time) const override {
        // The static case uses the cached pose: no per-ray matrix evaluation.
        return m_animated ? ray_in_pose(CameraPose(m_to_world.eval(time)), film_pos, lens, time)
                          : ray_in_pose(m_proj.pose, film_pos, lens, time);
    }

    void generate_rays(const Vec2f *film_pos, const Vec2f *lens, const float *time, size_t n, Ray *out) const override {
        if (m_animated || m_proj.aperture_radius > 0.f) {
            Camera::generate_rays(film_pos, lens, time, n, out);
            return;
        }
        // Static pinhole: ray_in_pose's arithmetic in a vector loop over chunks of the rays.
        constexpr size_t Chunk = 64;
        alignas(64) float fx[Chunk], fy[Chunk], dx[Chunk], dy[Chunk], dz[Chunk], tmin[Chunk], tmax[Chunk];
        for (size_t b = 0; b < n; b += Chunk) {
            size_t m = std::min(Chunk, n - b);
            for (size_t i = 0; i < m; ++i) fx[i] = film_pos[b + i].x, fy[i] = film_pos[b + i].y;
            pinhole_kernel(m_proj, float(film.width), float(film.height), fx, fy, m, dx, dy, dz, tmin, tmax);
            for (size_t i = 0; i < m; ++i)
                out[b + i] = Ray{m_proj.pose.origin, {dx[i], dy[i], dz[i]}, tmin[i], tmax[i], time[b + i]};
        }
    }

    bool project(Point3f y, float time, Vec2f lens, Vec2f *film_pos) const override {
        Point3f p = pose_at(time).to_camera(y);
        if (!(p.z >= m_proj.near_clip && p.z <= m_proj.far_clip)) return false;
        // Point q on the plane z = 1 that the film position maps to (design doc §3). Thin lens:
        // the ray u -> p meets the focus plane z = f_d at P = u + (p - u) f_d / p.z, and
        // q = P / f_d = u (1/f_d - 1/p.z) + p / p.z; a pinhole (u = 0) gives q = p / p.z.
        float inv_z = 1.f / p.z;
        float qx = p.x * inv_z, qy = p.y * inv_z;
        if (m_proj.aperture_radius > 0.f) {
            float k = m_proj.aperture_radius * (m_proj.inv_focus_distance - inv_z);
            qx += lens.x * k;
            qy += lens.y * k;
        }
        *film_pos = film_from_plane(qx, qy);
        return true;
    }

    Point3f lens_point(float time, Vec2f lens) const override {
        return lens_point_in_pose(pose_at(time), lens);
    }

    float film_density(Point3f y, Normal3f n_y, float time, Vec2f lens) const override {
        CameraPose pose = pose_at(time);
        // G = f^2 cos(phi) / (cos^3(theta) d^2) (design doc §4): the direction -> focus-plane map
        // has area factor f_d^2 / cos^3(theta) from the lens point, scaled by (f / f_d)^2 onto the
        // film in pixels; dw/dA_y = cos(phi) / d^2.
        Vec3f w = y - lens_point_in_pose(pose, lens);
        float d2 = squared_norm(w), d = std::sqrt(d2);
        float cos_theta = dot(w, normalize(pose.axis[2])) / d;
        if (!(cos_theta > 0.f)) return 0.f;
        const float n_norm = norm(n_y);
        float cos_phi = n_norm > 0.f ? absdot(n_y, w) / (n_norm * d) : 1.f; // zero normal: a point in a medium
        return sqr(m_proj.film_distance) * cos_phi / (cos_theta * cos_theta * cos_theta * d2);
    }

    bool shift_geometry(Point3f y, Normal3f n_y, float time, Vec2f lens, ShiftGeometry *out) const override {
        if (!m_animated) return mvpt::shift_geometry(m_proj, ShiftVertex(y, n_y), lens, out);
        CameraProjection posed = m_proj;
        posed.pose = pose_at(time);
        return mvpt::shift_geometry(posed, ShiftVertex(y, n_y), lens, out);
    }

    const CameraProjection *static_projection() const override { return m_animated ? nullptr : &m_proj; }

    float lens_radius() const override { return m_proj.aperture_radius; }
    bool is_animated() const override { return m_animated; }

private:
    /// The pose at `time` (keyframes interpolated only for an animated camera).
    CameraPose pose_at(float time) const { return m_animated ? CameraPose(m_to_world.eval(time)) : m_proj.pose; }

    static bool is_rigid(const Matrix4 &m) {
        for (int i = 0; i < 3; ++i)
            for (int j = i; j < 3; ++j) {
                double dot_ij = m.m[i][0] * m.m[j][0] + m.m[i][1] * m.m[j][1] + m.m[i][2] * m.m[j][2];
                if (std::abs(dot_ij - (i == j ? 1.0 : 0.0)) > 1e-3) return false;
            }
        return true;
    }

    /// Film position (pixels) -> camera-space point on the plane z = 1 (Mitsuba's sample_to_camera:
    /// film x grows to the camera's right = -x, film y grows downwards = -y).
    Vec3f plane_from_film(Vec2f film_pos) const {
        float u = film_pos.x / float(film.width) + m_proj.ppo_x, v = film_pos.y / float(film.height) + m_proj.ppo_y;
        return {-(2.f * u - 1.f) * m_proj.tan_x, -(2.f * v - 1.f) * m_proj.tan_y, 1.f};
    }
    /// Inverse of `plane_from_film`.
    Vec2f film_from_plane(float qx, float qy) const { return m_proj.film_from_plane(qx, qy); }

    Point3f lens_point_in_pose(const CameraPose &pose, Vec2f lens) const {
        if (m_proj.aperture_radius > 0.f)
            return pose.to_world(Point3f(lens.x * m_proj.aperture_radius, lens.y * m_proj.aperture_radius, 0.f));
        return pose.origin;
    }

    Ray ray_in_pose(const CameraPose &pose, Vec2f film_pos, Vec2f lens, float time) const {
        Vec3f near_p = plane_from_film(film_pos);
        Vec3f d_cam;
        Ray r;
        if (m_proj.aperture_radius > 0.f) {
            Vec3f o_cam(lens.x * m_proj.aperture_radius, lens.y * m_proj.aperture_radius, 0.f);
            d_cam = normalize(near_p * m_focus_distance - o_cam);
            r.o = pose.to_world(o_cam);
        } else {
            d_cam = normalize(near_p);
            r.o = pose.origin;
        }
        float inv_z = 1.f / d_cam.z;
        r.d = normalize(pose.vector_to_world(d_cam));
        r.tmin = m_proj.near_clip * inv_z;
        r.tmax = m_proj.far_clip * inv_z;
        r.time = time;
        return r;
    }

    AnimatedTransform m_to_world;
    bool m_animated = false;
    float m_focus_distance = 1e4f;
    /// The static pose (shutter open), clip range, lens, field of view (tangents), principal
    /// point offset and film distance f = (W/2) / tan(fov_x/2) in pixels.
    CameraProjection m_proj;
};

MVPT_REGISTER_PLUGIN("sensor", "perspective", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PerspectiveCamera>(p, false);
});
MVPT_REGISTER_PLUGIN("sensor", "thinlens", [](const Properties &p, const LoadContext &) {
    return std::make_shared<PerspectiveCamera>(p, true);
});

} // namespace mvpt
