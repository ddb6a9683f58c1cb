#include "volpath.h"

#include "../../render/bsdf.h"
#include "../../render/light.h"
#include "../../render/medium.h"
#include "../../render/shape.h"
#include "../../core/plugin.h"
#include "../../accel/scene.h"
#include "path_steps.h"
#include "transmittance.h"

#include <climits>

namespace mvpt {

Spectrum VolPathIntegrator::sample_emitter(const Scene &scene, Point3f p, const SurfaceInteraction *si,
                                           const Medium *medium, float time, Sampler &sampler, RayCounters &counters,
                                           LightSample &ls) const {
    const auto &lights = scene.lights();
    float u_select = sampler.next_1d();
    Vec2f u_light = sampler.next_2d();
    RandomStream rs = sampler.next_stream();
    if (lights.empty()) return Spectrum(0.f);
    Spectrum weight;
    std::tie(ls, weight) = lights[uniform_emitter_index(u_select, lights.size())]->sample_li(p, u_light, time);
    if (weight.is_black()) return weight;
    Ray shadow;
    if (si) {
        shadow = std::isinf(ls.dist) ? si->spawn_ray(ls.d) : si->spawn_ray_to(ls.p);
        // Leaving the surface towards the emitter may enter the medium on its other side.
        if (si->shape->is_medium_transition()) medium = si->shape->target_medium(ls.d, si->n);
    } else {
        shadow = Ray{p, ls.d, 0.f, std::isinf(ls.dist) ? Infinity : ls.dist * (1.f - ShadowEpsilon), time};
    }
    return weight * float(lights.size()) * shadow_transmittance(scene, shadow, medium, rs, counters);
}

Spectrum VolPathIntegrator::scatter_in_medium(const Scene &scene, const Medium &medium, const Spectrum &throughput,
                                              uint32_t block, Sampler &sampler, RayCounters &counters, Ray &ray,
                                              float &pdf, bool &delta) const {
    const Point3f p = ray.o;
    const Vec3f wi = -ray.d;
    const PhaseFunction &phase = medium.phase();
    Spectrum result(0.f);
    if (medium.sample_emitters()) {
        sampler.set_dimension(block + 3);
        LightSample ls;
        Spectrum le = sample_emitter(scene, p, nullptr, &medium, ray.time, sampler, counters, ls);
        if (!le.is_black()) {
            float f = phase.eval(wi, ls.d);
            result = throughput * le * f * emitter_sample_mis(ls, float(scene.lights().size()), f);
        }
    }
    sampler.set_dimension(block + 6);
    Vec3f wo = phase.sample(wi, sampler.next_2d());
    pdf = phase.eval(wi, wo), delta = !medium.sample_emitters();
    ray = Ray{p, wo, 0.f, Infinity, ray.time};
    return result;
}

Spectrum VolPathIntegrator::in_scattering(const Scene &scene, const Ray &ray, const Medium &medium, Sampler &sampler,
                                          RayCounters &counters, bool &drawn, uint32_t dims) const {
    drawn = false;
    if (m_cfg.max_depth >= 0 && m_cfg.max_depth <= 1) { // a scattering would end the path
        drawn = true;
        return Spectrum(0.f);
    }
    sampler.set_dimension(dims + 1); // the layout of a step's block (VolDimsPerStep)
    const float u = sampler.next_1d();
    MediumSample ms;
    if (!medium.sample_within(ray, ray.tmax, u, ms)) return Spectrum(0.f);
    drawn = true;
    if (!ms.scattered || ms.weight.is_black()) return Spectrum(0.f);
    PathState state;
    state.depth = 1;
    state.throughput = ms.weight;
    state.prev_p = ray.at(ms.t);
    Ray next{state.prev_p, ray.d, 0.f, Infinity, ray.time};
    Spectrum result = scatter_in_medium(scene, medium, state.throughput, dims, sampler, counters, next,
                                        state.prev_bsdf_pdf, state.prev_bsdf_delta);
    return result + trace(scene, next, &medium, state, sampler, counters, VolPathPart::ScatteredInMedium, dims);
}

Spectrum VolPathIntegrator::li(const Scene &scene, const Ray &ray, Sampler &sampler, RayCounters &counters) const {
    if (!scene.has_media()) return m_surfaces.li(scene, ray, sampler, counters);
    return li_in(scene, ray, nullptr, sampler, counters);
}

void VolPathIntegrator::li_batch(const Scene &scene, const Ray *rays, Sampler *samplers, Spectrum *out, size_t n,
                                 RayCounters &counters, const Medium *medium) const {
    if (!scene.has_media()) return m_surfaces.li_batch(scene, rays, samplers, out, n, counters);
    for (size_t i = 0; i < n; ++i) out[i] = li_in(scene, rays[i], medium, samplers[i], counters);
}

Spectrum VolPathIntegrator::li_in(const Scene &scene, Ray ray, const Medium *medium, Sampler &sampler,
                                  RayCounters &counters, VolPathPart part, uint32_t dims) const {
    // Start at the near plane: media fill the segment the camera sees.
    ray.o = ray.at(ray.tmin), ray.tmax -= ray.tmin, ray.tmin = 0.f;
    PathState start;
    start.prev_p = ray.o;
    return trace(scene, ray, medium, start, sampler, counters, part, dims);
}

Spectrum VolPathIntegrator::trace(const Scene &scene, Ray ray, const Medium *medium, const PathState &start,
                                  Sampler &sampler, RayCounters &counters, VolPathPart part, uint32_t dims) const {
    const uint32_t max_depth = m_cfg.max_depth < 0 ? UINT_MAX : uint32_t(m_cfg.max_depth);
    const bool scattered_only = part == VolPathPart::ScatteredInMedium;
    const bool unscattered_only = part == VolPathPart::ReachesSurface;
    // path.depth counts scattering events (crossing a null surface is none); path.prev_*: the
    // last of them and the density of the direction it sampled (MIS on emitters hit), a delta
    // (or the camera's) when the hit counts in full.
    PathState path = start;
    Spectrum result(0.f);
    for (uint32_t step = start.depth;; ++step) {
        const uint32_t block = dims + step * VolDimsPerStep;
        sampler.set_dimension(block);
        // ---------------- Russian roulette, as Mitsuba's volpath: before each step ----------------
        float u_rr = sampler.next_1d();
        if (path.throughput.is_black() || path.depth >= max_depth) break;
        if (path.depth > uint32_t(m_cfg.rr_depth)) {
            float q = rr_survival(path.throughput.max_value(), path.eta);
            if (u_rr >= q) break;
            path.throughput *= 1.f / q;
        }

        float u_flight = sampler.next_1d();
        RandomStream rs = sampler.next_stream();
        SurfaceInteraction si;
        ++counters.rays;
        // In a medium, surfaces beyond where the flight surely ends need not be found.
        const bool pass_through = unscattered_only && path.depth == 0; // the camera segment, without scattering
        Ray query = ray;
        if (medium && !pass_through) query.tmax = std::min(query.tmax, medium->free_flight_bound(u_flight));
        const bool hit = scene.intersect(query, si);

        // ---------------- Free flight through the medium ----------------
        if (medium && pass_through) {
            path.throughput *= medium->transmittance(ray, hit ? si.t : Infinity, rs);
        } else if (medium) {
            MediumSample ms = medium->sample(ray, hit ? si.t : Infinity, u_flight, rs);
            path.throughput *= ms.weight;
            if (ms.scattered) {
                if (++path.depth >= max_depth || path.throughput.is_black()) break;
                ray = Ray{ray.at(ms.t), ray.d, 0.f, Infinity, ray.time};
                path.prev_p = ray.o;
                result += scatter_in_medium(scene, *medium, path.throughput, block, sampler, counters, ray,
                                            path.prev_bsdf_pdf, path.prev_bsdf_delta);
                continue;
            }
        }

        // The part without scattering ends at the first surface that is not null.
        if (scattered_only && path.depth == 0 && (!hit || si.shape->bsdf->flags() != BsdfNull)) break;
        if (!surface_vertex(scene, hit, si, block, max_depth, path, ray, medium, result, sampler, counters)) break;
    }
    // (Mitsuba's volpath keeps the radiance of paths it calls invalid: validity is only alpha.)
    return result;
}

bool VolPathIntegrator::surface_vertex(const Scene &scene, bool hit, SurfaceInteraction &si, uint32_t block,
                                       uint32_t max_depth, PathState &path, Ray &ray, const Medium *&medium,
                                       Spectrum &result, Sampler &sampler, RayCounters &counters) const {
    const BsdfContext ctx;
    // ---------------- Emission (hit by BSDF or phase sampling, MIS against NEE) ----------------
    const Light *emitter = hit ? si.shape->emitter.get() : scene.environment();
    if (emitter && !(path.depth == 0 && m_cfg.hide_emitters)) {
        float w;
        Spectrum le = emitted_radiance(scene, emitter, ray, hit, si, path.prev_p, path.prev_bsdf_pdf,
                                       path.prev_bsdf_delta, w);
        if (!le.is_black()) result += path.throughput * le * w;
    }
    if (!hit) return false;

    // ---------------- Next-event estimation at the surface ----------------
    const Bsdf &bsdf = *si.shape->bsdf;
    si.wi = si.to_local(-ray.d);
    if (bsdf.has_smooth() && path.depth + 1 < max_depth) {
        LightSample ls;
        Spectrum le = sample_emitter(scene, si.p, &si, medium, si.time, sampler, counters, ls);
        if (!le.is_black()) {
            Vec3f wo = si.to_local(ls.d);
            auto [f, pdf] = bsdf.eval_pdf(ctx, si, si.wi, wo);
            result += path.throughput * le * f * emitter_sample_mis(ls, float(scene.lights().size()), pdf);
        }
    }

    // ---------------- BSDF sampling ----------------
    sampler.set_dimension(block + 6);
    float u_lobe = sampler.next_1d();
    auto [bs, bsdf_weight] = bsdf.sample(ctx, si, si.wi, u_lobe, sampler.next_2d());
    const bool scattered = !(bs.sampled_type & BsdfNull); // a failed sample counts too, as in Mitsuba
    if (bsdf_weight.is_black()) return false;
    const Vec3f wo = si.to_world(bs.wo);
    path.throughput *= bsdf_weight;
    path.eta *= bs.eta;
    if (scattered) {
        ++path.depth;
        path.prev_p = si.p, path.prev_bsdf_pdf = bs.pdf, path.prev_bsdf_delta = (bs.sampled_type & BsdfDelta) != 0;
    }
    if (si.shape->is_medium_transition()) medium = si.shape->target_medium(wo, si.n);
    ray = si.spawn_ray(wo);
    return true;
}

MVPT_REGISTER_PLUGIN("integrator", "volpath", [](const Properties &props, const LoadContext &) {
    return std::make_shared<VolPathIntegrator>(read_path_config(props));
});

} // namespace mvpt
