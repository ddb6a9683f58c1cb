#include "path.h"
#include "path_steps.h"

#include "../../render/bsdf.h"
#include "../../render/light.h"
#include "../../render/shape.h"
#include "../../core/plugin.h"
#include "../../accel/scene.h"

#include <climits>

namespace mvpt {

float emitter_pdf(const Scene &scene, const Light *light, Point3f ref, const SurfaceInteraction &si_light, Vec3f d) {
    size_t n = scene.lights().size();
    if (n == 0 || light->is_delta()) return 0.f;
    return light->pdf_li(ref, si_light, d) / float(n);
}

float emitter_pdf_from(const Scene &scene, const Light *light, float pdf_li) {
    size_t n = scene.lights().size();
    if (n == 0 || light->is_delta()) return 0.f;
    return pdf_li / float(n);
}

Spectrum emitted_radiance(const Scene &scene, const Light *emitter, const Ray &ray, bool hit,
                          const SurfaceInteraction &si, Point3f prev_p, float prev_pdf, bool prev_delta,
                          float &mis_weight) {
    // An escaped ray's radiance and NEE density come from one lookup of its direction.
    float env_pdf = 0.f;
    Spectrum le = hit ? emitter->eval(si, -ray.d)
                      : emitter->eval_environment_pdf(prev_p, si, ray.d, prev_delta ? nullptr : &env_pdf);
    mis_weight = 1.f;
    if (!le.is_black() && !prev_delta)
        mis_weight = mis_power(prev_pdf, hit ? emitter_pdf(scene, emitter, prev_p, si, ray.d)
                                             : emitter_pdf_from(scene, emitter, env_pdf));
    return le;
}

Spectrum PathIntegrator::li(const Scene &scene, const Ray &camera_ray, Sampler &sampler, RayCounters &counters) const {
    PathState state;
    // Mitsuba 3 keeps a path's radiance only if it scattered at a non-null surface, hit
    // an emitter, or could see the environment (so a camera ray that passes through
    // masks into nothing contributes nothing).
    state.valid = !m_cfg.hide_emitters && scene.environment() != nullptr;
    return trace(scene, camera_ray, state, sampler, counters);
}

Spectrum PathIntegrator::trace(const Scene &scene, Ray ray, PathState state, Sampler &sampler, RayCounters &counters,
                               const SurfaceInteraction *first_hit, bool *valid_out) const {
    const auto &lights = scene.lights();
    const uint32_t max_depth = m_cfg.max_depth < 0 ? UINT_MAX : uint32_t(m_cfg.max_depth);
    const BsdfContext ctx;
    Spectrum result(0.f);
    for (uint32_t depth = state.depth;; ++depth) {
        sampler.set_dimension(DimCameraEnd + depth * DimsPerVertex);
        SurfaceInteraction si;
        bool hit;
        if (first_hit && depth == state.depth) {
            si = *first_hit;
            hit = si.is_valid();
        } else {
            ++counters.rays;
            hit = scene.intersect(ray, si);
        }

        // Emission (hit by BSDF sampling, MIS against next-event estimation).
        const Light *emitter = hit ? si.shape->emitter.get() : scene.environment();
        if (emitter && !m_cfg.hide_emitters && hit) state.valid = true;
        if (emitter && !(depth == 0 && m_cfg.hide_emitters)) {
            float w;
            Spectrum le = emitted_radiance(scene, emitter, ray, hit, si, state.prev_p, state.prev_bsdf_pdf,
                                           state.prev_bsdf_delta, w);
            if (!le.is_black()) result += state.throughput * le * w;
        }
        if (!hit || depth + 1 >= max_depth) break;

        const Bsdf &bsdf = *si.shape->bsdf;
        si.wi = si.to_local(-ray.d);
        // The vertex's numbers, in this order: the emitter's choice and point, the BSDF's lobe
        // and direction, Russian roulette.
        const float u_light_select = sampler.next_1d();
        const Vec2f u_light = sampler.next_2d();
        const float u_lobe = sampler.next_1d();
        const Vec2f u_dir = sampler.next_2d();
        const float u_rr = sampler.next_1d();

        // Next-event estimation.
        if (bsdf.has_smooth() && !lights.empty()) {
            const Light &light = *lights[uniform_emitter_index(u_light_select, lights.size())];
            const auto [ls, weight] = light.sample_li(si.p, u_light, si.time);
            Spectrum contribution;
            Ray shadow;
            if (nee_step(bsdf, ctx, si, state.throughput, ls, weight, float(lights.size()), contribution, shadow)) {
                ++counters.shadow_rays;
                if (!scene.occluded(shadow)) result += contribution;
            }
        }

        // BSDF sampling and Russian roulette.
        const auto [bs, bsdf_weight] = bsdf.sample(ctx, si, si.wi, u_lobe, u_dir);
        if (!follow_bsdf_sample(state, si, bs, bsdf_weight, u_rr, depth, m_cfg.rr_depth, ray)) break;
    }
    if (valid_out) *valid_out = state.valid;
    return state.valid ? result : Spectrum(0.f);
}

PathConfig read_path_config(const Properties &props) {
    PathConfig cfg;
    cfg.max_depth = int(props.get_int_in("max_depth", -1, -1, INT32_MAX)); // -1: unlimited
    cfg.rr_depth = int(props.get_int_in("rr_depth", 5, 1, INT32_MAX));
    cfg.hide_emitters = props.get_bool("hide_emitters", false);
    return cfg;
}

MVPT_REGISTER_PLUGIN("integrator", "path", [](const Properties &props, const LoadContext &) {
    return std::make_shared<PathIntegrator>(read_path_config(props));
});

} // namespace mvpt
