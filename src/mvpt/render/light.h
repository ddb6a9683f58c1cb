// Emitter interface (Mitsuba's "emitter"): direct-illumination sampling from a
// reference point, its solid-angle density, and emitted radiance.
#pragma once

#include "../core/math.h"
#include "../core/properties.h"
#include "interaction.h"

#include <tuple>
#include <utility>

namespace mvpt {

class Shape;

/// A point on a light chosen from a reference point.
struct LightSample {
    Point3f p;
    Normal3f n;
    /// Unit direction from the reference point towards the light.
    Vec3f d;
    float dist = Infinity;
    /// Solid-angle density at the reference point (1 for delta lights).
    float pdf = 0.f;
    bool delta = false;
};

enum LightFlags : uint32_t {
    LightDeltaPosition = 1u << 0,
    LightDeltaDirection = 1u << 1,
    LightInfinite = 1u << 2,
    LightSurface = 1u << 3,
};

class Light : public Object {
public:
    /// Sample a direction towards the light; the weight is L_e / pdf, zero when
    /// the light cannot be reached (visibility is not tested here).
    virtual std::pair<LightSample, Spectrum> sample_li(Point3f ref, Vec2f u, float time) const = 0;
    /// Density of `sample_li` choosing the point `si` (area lights; `si` is the
    /// hit on the light) or direction `d` (environment lights).
    virtual float pdf_li(Point3f ref, const SurfaceInteraction &si, Vec3f d) const = 0;
    /// Radiance leaving surface point `si` in direction `w` (world, pointing away).
    virtual Spectrum eval(const SurfaceInteraction &, Vec3f) const { return {}; }
    /// Radiance arriving along a ray that escaped in direction `d` (environment lights).
    virtual Spectrum eval_environment(Vec3f) const { return {}; }
    /// `eval_environment(d)` and, when `pdf` is given, `pdf_li(ref, si, d)` into it: one
    /// call for an escaped ray that needs both (an environment map maps `d` once).
    virtual Spectrum eval_environment_pdf(Point3f ref, const SurfaceInteraction &si, Vec3f d, float *pdf) const {
        if (pdf) *pdf = pdf_li(ref, si, d);
        return eval_environment(d);
    }
    /// `sample_li` for `n` reference points at once (lane i: ref[i], u[i], time[i] into ls[i],
    /// weight[i]); a light overrides it to run the lanes in stages whose memory reads overlap.
    virtual void sample_li_batch(size_t n, const Point3f *ref, const Vec2f *u, const float *time, LightSample *ls,
                                 Spectrum *weight) const {
        for (size_t i = 0; i < n; ++i) std::tie(ls[i], weight[i]) = sample_li(ref[i], u[i], time[i]);
    }
    /// `eval_environment_pdf` for `n` escaped rays at once (from ref[i] in direction d[i], no
    /// surface hit), every lane's density into `pdf` unless it is null.
    virtual void eval_environment_batch(size_t n, const Point3f *ref, const Vec3f *d, Spectrum *le, float *pdf) const {
        const SurfaceInteraction si_none;
        for (size_t i = 0; i < n; ++i) le[i] = eval_environment_pdf(ref[i], si_none, d[i], pdf ? pdf + i : nullptr);
    }
    /// Whether the light moves during the scene's time (an animated transform).
    virtual bool moves() const { return false; }
    /// Scene extent, for lights placed at infinity.
    virtual void set_scene_bounds(Point3f center, float radius) { (void)center; (void)radius; }
    /// Attach an area light to its shape.
    virtual void set_shape(const Shape *) {}
    /// The shape an area light is attached to (nullptr for other lights).
    virtual const Shape *shape() const { return nullptr; }
    /// True when an area light's radiance is the same all over its shape (uv unused).
    virtual bool uniform_radiance() const { return false; }

    uint32_t flags() const { return m_flags; }
    bool is_delta() const { return (m_flags & (LightDeltaPosition | LightDeltaDirection)) != 0; }
    bool is_environment() const { return (m_flags & LightInfinite) != 0 && !(m_flags & LightDeltaDirection); }
    bool is_area() const { return (m_flags & LightSurface) != 0; }

protected:
    uint32_t m_flags = 0;
};

} // namespace mvpt
