// Camera interface (Mitsuba's "sensor"): one view of the scene with its film,
// sampler settings and shutter interval, plus the projection API on which
// multi-view path tracing is built (docs/multiview-path-tracing.md §2–§4).
//
// Conventions shared by every method (design doc §2):
// - film positions are in pixel units, full-film coordinates (the crop window is
//   not subtracted), x to the right and y down; pixel (i, j) covers [i, i+1) x [j, j+1);
// - `lens` is a point xi on the *unit* disk; the world lens point is
//   u = o(t) + r (xi.x e1(t) + xi.y e2(t)) with lens radius r (0 for a pinhole) and
//   e1, e2 the camera's x and y axes at time t (camera space: +z forward, +x left, +y up);
// - `time` is absolute scene time; a camera with an animated `to_world` is posed at it.
#pragma once

#include "../core/math.h"
#include "../core/sampler.h"
#include "../core/animation.h"
#include "../core/properties.h"
#include "filter.h"

#include <memory>
#include <string>

namespace mvpt {

struct CameraProjection;
class Medium;

/// The `hdrfilm` of a sensor: full film size, the crop window that is rendered, the filter.
struct FilmDesc {
    int width = 768, height = 576;
    int crop_x = 0, crop_y = 0, crop_width = 768, crop_height = 576;
    std::shared_ptr<ReconstructionFilter> filter;

    /// True when film position `pos` (pixels, full-film coordinates) lies inside the crop window
    /// (design doc §3, test 3 "image"); half-open: [crop_x, crop_x + crop_width).
    bool contains(Vec2f pos) const {
        return pos.x >= float(crop_x) && pos.x < float(crop_x + crop_width) && pos.y >= float(crop_y) &&
               pos.y < float(crop_y + crop_height);
    }
};

/// Everything the shift T_{l->k} needs from the target camera at once (design doc §3–§4).
struct ShiftGeometry {
    Vec2f film;         ///< film position (pixels, full film) where u -> y lands
    Point3f lens_point; ///< u = o(t) + r (xi.x e1 + xi.y e2)
    float density = 0.f; ///< G(y) of `film_density`
    /// Length of the segment y -> u that the camera sees, i.e. up to its near clip plane
    /// (occluders closer to the lens than near_clip are invisible to camera rays too).
    float visible_length = 0.f;
};

class Camera : public Object {
public:
    /// Ray through film position `film`, lens point `lens` on the unit disk, at scene time `time`
    /// (design doc §2): from the lens point towards the point of the focus plane that `film`
    /// maps to. Rays carry unit weight; [tmin, tmax] spans camera-space depths [near, far].
    virtual Ray generate_ray(Vec2f film, Vec2f lens, float time) const = 0;
    /// `generate_ray` for n rays (a render tile's), bit-identical to it; cameras may override
    /// it with a vector kernel.
    virtual void generate_rays(const Vec2f *film, const Vec2f *lens, const float *time, size_t n, Ray *out) const {
        for (size_t i = 0; i < n; ++i) out[i] = generate_ray(film[i], lens[i], time[i]);
    }

    /// Inverse of `generate_ray` for a fixed lens point and time (design doc §3, the shift
    /// T_{l->k}): the film position where the ray from the lens point `u(time, lens)` towards
    /// `y` lands (the ray is intersected with the focus plane and that point projected through
    /// the lens centre; a pinhole gives the ordinary projection of `y`). Returns false, leaving
    /// `film_pos` unspecified, when `y` is behind the camera or its camera-space depth lies
    /// outside [near_clip, far_clip]. It does not test the film bounds: see `FilmDesc::contains`.
    virtual bool project(Point3f y, float time, Vec2f lens, Vec2f *film_pos) const = 0;

    /// World-space lens point u = o(t) + r (xi.x e1(t) + xi.y e2(t)) (design doc §2).
    virtual Point3f lens_point(float time, Vec2f lens) const = 0;

    /// Film area per unit surface area at `y` (normal `n_y`, any length and side), for the
    /// lens point `u(time, lens)` (design doc §4):
    ///     G(y) = f^2 cos(phi) / (cos^3(theta) d^2),   f = (W/2) / tan(fov_x/2) in pixels,
    /// theta between u->y and the optical axis, phi between n_y and y->u, d = |y - u|. A zero
    /// `n_y` makes y a point in a medium: then G is per unit volume and unit length along the
    /// camera ray, f^2 / (cos^3(theta) d^2) (design doc §10).
    /// The Jacobian of the shift l->k is |T'_{l->k}| = G_k(y) / G_l(y). Returns 0 when `y`
    /// is not in front of the lens plane.
    virtual float film_density(Point3f y, Normal3f n_y, float time, Vec2f lens) const = 0;

    /// `project`, `lens_point` and `film_density` in one pose evaluation (the hot path of
    /// multi-view path tracing). False when `project` is.
    virtual bool shift_geometry(Point3f y, Normal3f n_y, float time, Vec2f lens, ShiftGeometry *out) const = 0;

    /// The camera as plain projection data when `shift_geometry` does not depend on time
    /// (a static perspective or thin-lens camera), else null (camera_projection.h).
    virtual const CameraProjection *static_projection() const { return nullptr; }

    /// Lens radius (0 for a pinhole).
    virtual float lens_radius() const { return 0.f; }
    /// True when `to_world` is keyframed, i.e. the pose depends on time.
    virtual bool is_animated() const { return false; }

    std::string id;
    FilmDesc film;
    SamplerKind sampler_kind = SamplerKind::Independent;
    int sample_count = 4;
    uint32_t seed = 0;
    float shutter_open = 0.f, shutter_close = 0.f;
    /// The medium around the camera (its rays start in it; null: vacuum).
    std::shared_ptr<Medium> medium;

    /// Scene time for a uniform sample in the shutter interval.
    float sample_time(float u) const { return shutter_open + u * (shutter_close - shutter_open); }
};

} // namespace mvpt
