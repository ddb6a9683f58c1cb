// Unidirectional path tracer with next-event estimation and MIS (power
// heuristic), with Mitsuba 3's max_depth / rr_depth / hide_emitters semantics.
#pragma once

#include "../../render/integrator.h"
#include "../../render/light.h"

namespace mvpt {

class Light;
class Scene;
struct SurfaceInteraction;

struct PathConfig {
    /// Longest path in vertices after the camera; -1: unlimited (1: emitters seen directly).
    int max_depth = -1;
    /// Depth from which Russian roulette may end a path.
    int rr_depth = 5;
    /// Hide emitters seen directly by the camera.
    bool hide_emitters = false;
};

/// `max_depth`, `rr_depth` and `hide_emitters` of an integrator element (Mitsuba's names and defaults).
PathConfig read_path_config(const Properties &props);

/// Sample dimensions consumed per path vertex (light choice, light point, lobe, direction, roulette).
inline constexpr uint32_t DimsPerVertex = 5;

/// State of a path about to trace `ray` towards its vertex number `depth` (0: the camera
/// ray's first hit). Multi-view path tracing starts shared suffixes from such a state.
struct PathState {
    uint32_t depth = 0;
    Spectrum throughput{1.f};
    float eta = 1.f;
    /// Previous scattering vertex and the density with which it sampled `ray` (for MIS
    /// against next-event estimation when `ray` hits an emitter).
    Point3f prev_p;
    float prev_bsdf_pdf = 1.f;
    bool prev_bsdf_delta = true;
    /// Mitsuba's valid-path rule: radiance counts only once the path scattered at a
    /// non-null surface, hit an emitter, or could see the environment.
    bool valid = false;
};

class PathIntegrator final : public Integrator {
public:
    explicit PathIntegrator(const PathConfig &cfg) : m_cfg(cfg) {}
    Spectrum li(const Scene &scene, const Ray &ray, Sampler &sampler, RayCounters &counters) const override;
    /// Radiance carried back along `ray` by the path continuing from `state` (throughput
    /// included). `first_hit`, when given, is the already computed intersection of `ray`;
    /// `valid_out` receives the valid-path flag at the end (the result is zero when false).
    Spectrum trace(const Scene &scene, Ray ray, PathState state, Sampler &sampler, RayCounters &counters,
                   const SurfaceInteraction *first_hit = nullptr, bool *valid_out = nullptr) const;
    /// The paths of many camera rays traced bounce by bounce (a wavefront), with Embree's
    /// packet queries; each result is bit-identical to `li` given the same hits (path_batch.cpp).
    void li_batch(const Scene &scene, const Ray *rays, Sampler *samplers, Spectrum *out, size_t n,
                  RayCounters &counters, const Medium *medium = nullptr) const override;
    /// `trace` for many paths as one wavefront: path i continues from `states[i]` along
    /// `rays[i]` (states null: li's start, camera rays), its result into `out[i]` and, when
    /// `valid_out` is given, its valid-path flag into `valid_out[i]`.
    void trace_batch(const Scene &scene, const Ray *rays, const PathState *states, Sampler *samplers, Spectrum *out,
                     uint8_t *valid_out, size_t n, RayCounters &counters) const;
    std::string name() const override { return "path"; }
    const PathConfig &config() const { return m_cfg; }

private:
    PathConfig m_cfg;
};

/// Probability density (solid angle, selection included) that NEE picks the
/// emitter point `si_light` / direction `d` from `ref`.
float emitter_pdf(const Scene &scene, const Light *light, Point3f ref, const SurfaceInteraction &si_light, Vec3f d);
/// `emitter_pdf` from the light's own density `pdf_li` of that point or direction.
float emitter_pdf_from(const Scene &scene, const Light *light, float pdf_li);

/// Radiance that `ray` finds at the emitter `emitter` it hit (at `si`; the environment when
/// `hit` is false), and into `mis_weight` its MIS weight against next-event estimation from
/// `prev_p`, whose direction density was `prev_pdf` (1 after a delta lobe or the camera,
/// `prev_delta`). Callers add throughput * radiance * weight, in that order (the wavefront's).
Spectrum emitted_radiance(const Scene &scene, const Light *emitter, const Ray &ray, bool hit,
                          const SurfaceInteraction &si, Point3f prev_p, float prev_pdf, bool prev_delta,
                          float &mis_weight);

/// Power heuristic with exponent 2 [Veach 1997, §9.2.4], branch-free (one lane; the vector
/// kernels run it on many).
[[gnu::always_inline]] inline float mis_power(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return select((a2 + b2) > 0.f, a2 / (a2 + b2), 0.f);
}

/// The emitter next-event estimation samples: one of `n_lights` (at least one) chosen
/// uniformly by the number u (the choice's probability 1 / n_lights is divided out of the
/// emitter's weight and enters emitter_sample_mis).
inline size_t uniform_emitter_index(float u, size_t n_lights) {
    return std::min(size_t(u * float(n_lights)), n_lights - 1);
}

/// MIS weight of next-event estimation's sample `ls` of a light chosen uniformly among
/// `n_lights`, against sampling its direction with density `pdf_other` (a BSDF's, a phase
/// function's or a mixture of them): the power heuristic, 1 for a delta light.
inline float emitter_sample_mis(const LightSample &ls, float n_lights, float pdf_other) {
    return ls.delta ? 1.f : mis_power(ls.pdf / n_lights, pdf_other);
}

} // namespace mvpt
