// Shape interface: geometry that Embree intersects, plus the area sampling
// that area lights need.
#pragma once

#include "../core/math.h"
#include "../core/properties.h"
#include "interaction.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <vector>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

namespace mvpt {

class Bsdf;
class Light;
class Medium;

struct BoundingBox {
    Point3f min{Infinity, Infinity, Infinity}, max{-Infinity, -Infinity, -Infinity};
    void expand(Point3f p) { min = vmin(min, p); max = vmax(max, p); }
    void expand(const BoundingBox &b) { min = vmin(min, b.min); max = vmax(max, b.max); }
    bool valid() const { return min.x <= max.x; }
    Point3f center() const { return (min + max) * 0.5f; }
};

/// A point on a shape's surface chosen by area sampling.
struct ShapeSample {
    Point3f p;
    Normal3f n;
    Vec2f uv;
    /// Density w.r.t. surface area.
    float pdf_a = 0.f;
};

/// Maps scene time to Embree's motion-blur time in [0, 1]: one affine map per
/// scene, spanning the keyframes of all animated shapes (times outside clamp,
/// which holds the end poses).
struct MotionTime {
    float t0 = 0.f, t1 = 1.f;
    float to_embree(float t) const { return t1 > t0 ? std::clamp((t - t0) / (t1 - t0), 0.f, 1.f) : 0.f; }
};

class Shape : public Object {
public:
    /// Add the geometry to `scene`; returns its Embree geometry id.
    virtual unsigned attach(RTCDevice device, RTCScene scene, const MotionTime &motion) = 0;
    /// Complete a hit: `prim` and barycentrics `b` come from Embree. Must set t, p, n,
    /// sh_frame and uv (the caller sets time, shape, prim; `si` may hold an older hit).
    virtual void fill_interaction(const Ray &ray, float t, uint32_t prim, Vec2f b, SurfaceInteraction &si) const = 0;
    /// Complete a hit inside an Embree instance that this shape attached
    /// (instances, animated shapes): `inner_geom` is the geometry id in its
    /// sub-scene. Sets `si.shape` to the shape actually hit.
    virtual void fill_instance_interaction(const Ray &ray, float t, unsigned inner_geom, uint32_t prim, Vec2f b,
                                           SurfaceInteraction &si) const;
    /// The partial derivatives dp/du and dp/dv of the surface's parametrisation (Mitsuba's) at
    /// the point `p` of primitive `prim`, in the shape's space (the world, unless instanced);
    /// zero where the shape has none. What bump maps perturb (surface_uv_partials).
    virtual std::pair<Vec3f, Vec3f> uv_partials(uint32_t prim, Point3f p) const {
        (void)prim, (void)p;
        return {};
    }
    /// The names of the shape's mesh attributes ("vertex_color", ...); none but on meshes.
    virtual std::vector<std::string> attribute_names() const { return {}; }
    /// Attribute `name` at the hit `si` on this shape (1 channel: the same in all three);
    /// zero where the shape has no such attribute (the loader refuses such scenes).
    virtual Color3f eval_attribute(const std::string &name, const SurfaceInteraction &si) const {
        (void)name, (void)si;
        return Color3f(0.f);
    }
    /// Keyframe time range of an animated shape; false when it does not move.
    virtual bool time_range(float &begin, float &end) const { (void)begin; (void)end; return false; }
    /// True for a `shapegroup`, which is rendered only through instances.
    virtual bool is_shapegroup() const { return false; }
    virtual float area() const = 0;
    virtual BoundingBox bounds() const = 0;
    /// Uniform point on the surface (density 1/area).
    virtual ShapeSample sample_area(Vec2f u) const = 0;
    /// A point as seen from `ref`; returns it with its solid-angle density at `ref`
    /// (0 when degenerate). The default converts area sampling.
    virtual std::pair<ShapeSample, float> sample_solid_angle(Point3f ref, Vec2f u) const;
    /// Density of `sample_solid_angle` for the point `si` on this shape (the
    /// area-to-solid-angle factor uses the shading normal, as Mitsuba does).
    virtual float pdf_solid_angle(Point3f ref, const SurfaceInteraction &si) const;

    std::shared_ptr<Bsdf> bsdf;
    std::shared_ptr<Light> emitter;
    /// The media inside and outside the surface (null: vacuum), Mitsuba's `interior` and
    /// `exterior`; outside is where the oriented geometric normal points.
    std::shared_ptr<Medium> interior, exterior;
    bool is_medium_transition() const { return interior || exterior; }
    /// The medium a ray enters when it leaves the surface in direction `d` (geometric normal `n`).
    const Medium *target_medium(Vec3f d, Normal3f n) const { return dot(d, n) > 0.f ? exterior.get() : interior.get(); }
    /// Whether `sample_area` / `sample_solid_angle` must fill `ShapeSample::uv`; false for
    /// an emitter whose radiance is uniform (it spares a sphere two inverse trig calls).
    bool sample_uv = true;
    std::string id;
};

/// dp/du and dp/dv at the hit `si` in world space (Shape::uv_partials, moved by the instance
/// that was hit, if any).
std::pair<Vec3f, Vec3f> surface_uv_partials(const SurfaceInteraction &si);

/// Convert an area density at `p` (normal `n`) to solid angle seen from `ref`.
inline float area_to_solid_angle(float pdf_a, Point3f ref, Point3f p, Normal3f n) {
    Vec3f d = p - ref;
    float dist2 = squared_norm(d);
    float cos_t = absdot(n, d) / std::sqrt(dist2);
    return cos_t > 0.f ? pdf_a * dist2 / cos_t : 0.f;
}

inline std::pair<ShapeSample, float> Shape::sample_solid_angle(Point3f ref, Vec2f u) const {
    ShapeSample s = sample_area(u);
    return {s, area_to_solid_angle(s.pdf_a, ref, s.p, s.n)};
}

inline void Shape::fill_instance_interaction(const Ray &, float, unsigned, uint32_t, Vec2f, SurfaceInteraction &) const {
    throw std::logic_error("fill_instance_interaction called on a shape that attaches no instance");
}

inline float Shape::pdf_solid_angle(Point3f ref, const SurfaceInteraction &si) const {
    return area_to_solid_angle(1.f / area(), ref, si.p, si.sh_frame.n);
}

} // namespace mvpt
