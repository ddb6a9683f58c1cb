// The steps of a path tracer's vertex after its emission term (emitted_radiance, path.h):
// next-event estimation with its MIS weight, and the BSDF sample that the path follows with
// Russian roulette. Written once, for the reference path tracer (PathIntegrator::trace) and
// the wavefront's vertices that no vector kernel takes (path_batch.cpp); the kernels are
// pinned to them bit for bit by tests/cpp/test_path_batch*.cpp. Russian roulette's survival
// probability (rr_survival, branch-free) also serves the kernels, the volumetric path tracer
// and multi-view path tracing's shared bounce.
#pragma once

#include "path.h"

#include "../../render/bsdf.h"
#include "../../render/light.h"

#include <algorithm>
#include <cmath>

namespace mvpt {

/// Russian roulette's survival probability for a path whose throughput's largest channel is
/// t_max and whose refractions so far scaled radiance by eta: min(t_max eta^2, 0.95).
[[gnu::always_inline]] inline float rr_survival(float t_max, float eta) { return min_of(t_max * eta * eta, 0.95f); }

/// Next-event estimation at `si` for the emitter sample (ls, weight = L/pdf) of a light chosen
/// uniformly among `n_lights`: the contribution throughput * f * weight * n_lights * w_MIS
/// (power heuristic against BSDF sampling) into `contribution`, which counts if `shadow` is
/// unblocked. False when there is nothing to trace (the weight or f is zero).
inline bool nee_step(const Bsdf &bsdf, const BsdfContext &ctx, const SurfaceInteraction &si, const Spectrum &throughput,
                     const LightSample &ls, Spectrum weight, float n_lights, Spectrum &contribution, Ray &shadow) {
    if (weight.is_black()) return false;
    weight *= n_lights;
    const Vec3f wo = si.to_local(ls.d);
    const Spectrum f = bsdf.eval(ctx, si, si.wi, wo);
    if (f.is_black()) return false;
    shadow = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
    const float w = emitter_sample_mis(ls, n_lights, bsdf.pdf(ctx, si, si.wi, wo));
    contribution = throughput * f * weight * w;
    return true;
}

/// The path at vertex `depth` follows the BSDF sample (bs, weight f |cos| / pdf) drawn at `si`:
/// `path` (PathState's fields: valid, throughput, eta, prev_p, prev_bsdf_pdf, prev_bsdf_delta)
/// takes it and `ray` becomes the next ray; then Russian roulette with `u_rr` from depth + 1 >=
/// rr_depth on (survival probability min(max throughput * eta^2, 0.95)). False: the path ends.
template <typename Path>
inline bool follow_bsdf_sample(Path &path, const SurfaceInteraction &si, const BsdfSample &bs, const Spectrum &bsdf_weight,
                               float u_rr, uint32_t depth, int rr_depth, Ray &ray) {
    if (!(bs.sampled_type & BsdfNull)) path.valid = true;
    if (bsdf_weight.is_black()) return false;
    ray = si.spawn_ray(si.to_world(bs.wo));
    path.throughput *= bsdf_weight;
    path.eta *= bs.eta;
    path.prev_p = si.p;
    path.prev_bsdf_pdf = bs.pdf;
    path.prev_bsdf_delta = (bs.sampled_type & BsdfDelta) != 0;
    const float t_max = path.throughput.max_value();
    if (!(t_max > 0.f)) return false;
    if (depth + 1 >= uint32_t(rr_depth)) {
        const float q = rr_survival(t_max, path.eta);
        if (u_rr >= q) return false;
        path.throughput *= 1.f / q;
    }
    return true;
}

} // namespace mvpt
