#include "path.h"

#include "../render/bsdf.h"
#include "../render/light.h"
#include "../render/shape.h"
#include "../core/plugin.h"
#include "../scene/scene.h"

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

    Spectrum result(0.f), throughput = state.throughput;
    float eta = state.eta;
    Point3f prev_p = state.prev_p; // previous scattering vertex (reference point of NEE's density)
    float prev_bsdf_pdf = state.prev_bsdf_pdf;
    bool prev_bsdf_delta = state.prev_bsdf_delta;
    bool valid = state.valid;

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

        // ---------------- Emission (hit by BSDF sampling, MIS against NEE) ----------------
        const Light *emitter = hit ? si.shape->emitter.get() : scene.environment();
        if (emitter && !m_cfg.hide_emitters && hit) valid = true;
        if (emitter && !(depth == 0 && m_cfg.hide_emitters)) {
            float w;
            Spectrum le = emitted_radiance(scene, emitter, ray, hit, si, prev_p, prev_bsdf_pdf, prev_bsdf_delta, w);
            if (!le.is_black()) result += throughput * le * w;
        }
        if (!hit || depth + 1 >= max_depth) break;

        const Bsdf &bsdf = *si.shape->bsdf;
        si.wi = si.to_local(-ray.d);

        // ---------------- Next-event estimation ----------------
        float u_light_select = sampler.next_1d();
        Vec2f u_light = sampler.next_2d();
        if (bsdf.has_smooth() && !lights.empty()) {
            size_t idx = std::min(size_t(u_light_select * float(lights.size())), lights.size() - 1);
            const Light &light = *lights[idx];
            auto [ls, weight] = light.sample_li(si.p, u_light, si.time);
            if (!weight.is_black()) {
                weight *= float(lights.size());
                Vec3f wo = si.to_local(ls.d);
                Spectrum f = bsdf.eval(ctx, si, si.wi, wo);
                if (!f.is_black()) {
                    Ray shadow = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
                    ++counters.shadow_rays;
                    if (!scene.occluded(shadow)) {
                        float w = ls.delta ? 1.f : mis_power(ls.pdf / float(lights.size()), bsdf.pdf(ctx, si, si.wi, wo));
                        result += throughput * f * weight * w;
                    }
                }
            }
        }

        // ---------------- BSDF sampling ----------------
        float u_lobe = sampler.next_1d();
        Vec2f u_dir = sampler.next_2d();
        auto [bs, bsdf_weight] = bsdf.sample(ctx, si, si.wi, u_lobe, u_dir);
        if (!(bs.sampled_type & BsdfNull)) valid = true;
        if (bsdf_weight.is_black()) break;
        Vec3f wo_world = si.to_world(bs.wo);
        ray = si.spawn_ray(wo_world);
        throughput *= bsdf_weight;
        eta *= bs.eta;
        prev_p = si.p;
        prev_bsdf_pdf = bs.pdf;
        prev_bsdf_delta = (bs.sampled_type & BsdfDelta) != 0;

        // ---------------- Russian roulette ----------------
        float t_max = throughput.max_value();
        float u_rr = sampler.next_1d();
        if (!(t_max > 0.f)) break;
        if (depth + 1 >= uint32_t(m_cfg.rr_depth)) {
            float q = std::min(t_max * eta * eta, 0.95f);
            if (u_rr >= q) break;
            throughput *= 1.f / q;
        }
    }
    if (valid_out) *valid_out = valid;
    return valid ? result : Spectrum(0.f);
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
