// Medium vertices of multi-view path tracing (docs/multiview-path-tracing.md §10): a scattering
// on a native camera segment, drawn by a free flight whose density every view can evaluate
// from its own segment, shared with every view that sees it as a surface vertex is (§3–§7).
#include "mv_densities.h"
#include "mv_media.h"

#include "../path/volpath.h"

#include "../../render/bsdf.h"
#include "../../render/light.h"
#include "../../render/medium.h"
#include "../../render/shape.h"
#include "../../accel/scene.h"

#include <algorithm>

namespace mvpt {

namespace {

/// Every medium a camera segment of the rendered views can pass has a constant extinction.
bool constant_media(const MvContext &ctx) {
    Spectrum sigma;
    auto constant = [&](const std::shared_ptr<Medium> &m) { return !m || m->constant_extinction(sigma); };
    for (const auto &shape : ctx.scene->shapes())
        if (!constant(shape->interior) || !constant(shape->exterior)) return false;
    for (const MvView &v : ctx.views)
        if (!constant(v.camera->medium)) return false;
    return true;
}

/// The candidates of a medium vertex `y` of view `slot` (its pixel and film position): the native
/// view first, then every view that passes the cheap tests; no frame, no material similarity.
void gather_medium_candidates(const MvContext &ctx, int slot, uint32_t pixel, Vec2f film, const MvVertex &y,
                              MvScratch &sc) {
    mv_shift_views(ctx, slot, y, sc);
    const ViewShifts &vs = sc.shifts;
    MvCandidates &c = sc.cand;
    c.reserve(ctx.views.size());
    c.size = 0;
    c.push(vs, slot, float(ctx.native_map[slot][pixel]));
    c.pixel[0] = pixel;
    c.film[0] = film;
    if (!(vs.status[slot] & ShiftDepth)) {
        for (int k = 0; k < int(ctx.views.size()); ++k)
            if (k != slot && vs.status[k] == 0) c.push(vs, k, float(ctx.native_map[k][vs.pixel[k]]));
    } else {
        c.g[0] = 1.f; // no density to compare: the vertex is l's alone
    }
    const size_t m = c.size;
    sc.s_sel.assign(m, 1.f);
    sc.visible.assign(m, 1);
    sc.selected.assign(m, 1);
    sc.material = false;
}

} // namespace

bool mv_can_share_medium_vertices(const MvContext &ctx) {
    if (!ctx.volpath || ctx.views.size() < 2 || !ctx.path) return false;
    const int max_depth = ctx.path->config().max_depth;
    if (max_depth >= 0 && max_depth <= 1) return false;
    for (const auto &shape : ctx.scene->shapes())
        if (shape->emitter && shape->bsdf->flags() == BsdfNull) return false; // emission seen through a null surface
    return constant_media(ctx);
}

namespace {

/// The views that share the medium vertex `p` of a flight of view `slot` (its pixel, film
/// position and lens sample): shift, densities g_k = G_k^V p_k(p) (§10), selection (§6) and
/// D_k (§5). Returns |S| (the candidates in sc.sharing); sc.tr[k] becomes what view k's own
/// estimate multiplies the radiance scattered at p by, T_k sigma_s / p_k.
size_t medium_sharing(const MvContext &ctx, int slot, uint32_t pixel, Vec2f film, Vec2f lens, const SegmentFlight &flight,
                      float time, Sampler &sampler, MvScratch &sc, RayCounters &counters) {
    const MvVertex y{flight.p, Normal3f(0.f), time, lens, 0.f, true};
    gather_medium_candidates(ctx, slot, pixel, film, y, sc);
    MvCandidates &cand = sc.cand;
    const size_t m = cand.size;
    // Every candidate's segment from its near plane to p: visibility and T_k(p); a strategy's
    // density there is G_k^V times its flight's 1/3 sum_c sigma_c T_k,c.
    mv_media_visibility(ctx, sc, flight.p, time, flight.tr, false, &sampler, counters, nullptr);
    Spectrum sigma_t;
    flight.medium->constant_extinction(sigma_t);
    const Spectrum sigma_s = flight.medium->scattering(flight.p);
    for (size_t i = 0; i < m; ++i) {
        const Spectrum &tr = sc.tr[i];
        const float pdf = (sigma_t[0] * tr[0] + sigma_t[1] * tr[1] + sigma_t[2] * tr[2]) * (1.f / 3.f);
        cand.g[i] *= pdf;
        sc.visible[i] &= uint8_t(pdf > 0.f);
        sc.tr[i] = pdf > 0.f ? tr * sigma_s * (1.f / pdf) : Spectrum(0.f);
    }
    mv_select(ctx, sc, sampler, nullptr, nullptr);
    if (ctx.cfg.mis_selected_only)
        for (size_t i = 1; i < m; ++i) sc.visible[i] &= uint8_t(sc.selected[i] != 0);
    auto &sharing = sc.sharing;
    sharing.resize(std::max(sharing.size(), m));
    size_t ns = 0;
    for (size_t i = 0; i < m; ++i) { // branch-free compaction
        sharing[ns] = int(i);
        ns += sc.visible[i] & sc.selected[i];
    }
    mv_balance_sums(ctx, sc, nullptr, nullptr, sharing.data(), ns);
    return ns;
}

/// Next-event estimation at p for the sharing views, whose directions towards their lens points
/// are wi[0, ns): the volumetric path tracer's emitter sample, each view's phase value into
/// f[i], and the light's weight times the power heuristic against the views' phase mixture
/// into rec (nee, nee_weight).
void medium_nee(const MvContext &ctx, const Medium &medium, Point3f p, float time, const Vec3f *wi, size_t ns,
                uint32_t dims, Sampler &sampler, Spectrum *f, MvPendingSamples::Sample &rec, RayCounters &counters) {
    if (!medium.sample_emitters()) return;
    sampler.set_dimension(dims + 3); // as a volumetric step draws its emitter sample
    LightSample ls;
    const Spectrum le = ctx.volpath->sample_emitter(*ctx.scene, p, nullptr, &medium, time, sampler, counters, ls);
    if (le.is_black()) return;
    float p_mix = 0.f;
    for (size_t i = 0; i < ns; ++i) {
        const float fi = medium.phase().eval(wi[i], ls.d);
        f[i] = Spectrum(fi);
        p_mix += fi;
    }
    p_mix /= float(ns);
    const float n_lights = float(ctx.scene->lights().size());
    rec.nee_weight = le * emitter_sample_mis(ls, n_lights, p_mix);
    rec.nee = !rec.nee_weight.is_black() && p_mix > 0.f;
}

/// The bounce at p: the phase function of a sharing view drawn uniformly, with the mixture's
/// density; each view's phase value into f[i], and the suffix queued in `pending` (rec.suffix).
void medium_bounce(const Medium &medium, Point3f p, float time, const Vec3f *wi, size_t ns, uint32_t dims,
                   Sampler &sampler, Spectrum *f, MvPendingSamples::Sample &rec, MvPendingSamples &pending) {
    sampler.set_dimension(dims);
    const size_t j = std::min(size_t(sampler.next_1d() * float(ns)), ns - 1);
    sampler.set_dimension(dims + 6); // as a volumetric step draws its phase sample
    const Vec3f wo = medium.phase().sample(wi[j], sampler.next_2d());
    float pdf_mix = 0.f;
    for (size_t i = 0; i < ns; ++i) {
        const float fi = medium.phase().eval(wi[i], wo);
        f[i] = Spectrum(fi);
        pdf_mix += fi;
    }
    pdf_mix /= float(ns);
    if (!(pdf_mix > 0.f)) return;
    PathState state;
    state.depth = 1;
    state.prev_p = p;
    state.prev_bsdf_pdf = pdf_mix;
    state.prev_bsdf_delta = !medium.sample_emitters(); // no NEE at p: emitters hit count in full
    rec.suffix = int32_t(pending.rays.size());
    rec.b_scale = 1.f / pdf_mix;
    pending.rays.push_back(Ray{p, wo, 0.f, Infinity, time});
    pending.media.push_back(&medium);
    pending.dims.push_back(dims);
    pending.states.push_back(state);
    pending.samplers.push_back(sampler);
}

/// One flight of mv_medium_vertex, its draws from dimension `dims` on; every strategy takes
/// MediumFlights of them, so each weight is 1 / (MediumFlights D_k).
void one_medium_vertex(const MvContext &ctx, int slot, const Ray &near, Vec2f lens, uint32_t pixel, Vec2f film,
                       const SampleKey &key, uint32_t dims, Sampler &sampler, MvScratch &sc, MvPendingSamples &pending,
                       RayCounters &counters) {
    sampler.set_dimension(dims + 1); // as a volumetric step draws its flight
    const SegmentFlight flight =
        flight_along_segment(*ctx.scene, near, ctx.views[slot].camera->medium.get(), sampler.next_1d(), counters);
    if (!flight.scattered || !(flight.pdf > 0.f)) return;
    const size_t ns = medium_sharing(ctx, slot, pixel, film, lens, flight, near.time, sampler, sc, counters);
    auto &wi = sc.sharing_wi; // from p towards each sharing view's lens point (world)
    wi.resize(std::max(wi.size(), ns));
    for (size_t i = 0; i < ns; ++i) wi[i] = normalize(sc.cand.lens_point(size_t(sc.sharing[i])) - flight.p);
    const size_t first = pending.add_entries(ns);
    Spectrum *const f_nee = pending.f_nee.data() + first, *const fs = pending.f_bounce.data() + first;
    MvPendingSamples::Sample rec;
    rec.key = key;
    rec.valid = true; // the volumetric path tracer keeps every path
    rec.medium = true;
    medium_nee(ctx, *flight.medium, flight.p, near.time, wi.data(), ns, dims, sampler, f_nee, rec, counters);
    medium_bounce(*flight.medium, flight.p, near.time, wi.data(), ns, dims, sampler, fs, rec, pending);
    for (size_t i = 0; i < ns; ++i) { // each sharing view's factor, pixel and W
        const size_t k = size_t(sc.sharing[i]);
        f_nee[i] = rec.nee ? f_nee[i] * sc.tr[k] : Spectrum(0.f); // (read by the splat loop: kept finite)
        fs[i] *= sc.tr[k];
        pending.slot[first + i] = sc.cand.slot[k];
        pending.pixel[first + i] = sc.cand.pixel[k];
        pending.film[first + i] = sc.cand.film[k];
        pending.w[first + i] = 1.f / (float(MediumFlights) * sc.d[k]);
    }
    rec.first = uint32_t(first);
    rec.count = uint32_t(ns);
    rec.hash = sampler.sample_hash();
    pending.samples.push_back(rec);
}

} // namespace

void mv_medium_vertex(const MvContext &ctx, int slot, const Ray &near, Vec2f lens, uint32_t pixel, Vec2f film,
                      const SampleKey &key, Sampler &sampler, MvScratch &sc, MvPendingSamples &pending,
                      RayCounters &counters, MvViewStats &st) {
    const uint64_t rays_before = counters.rays + counters.shadow_rays;
    for (int j = 0; j < MediumFlights; ++j)
        one_medium_vertex(ctx, slot, near, lens, pixel, film, key, DimMediumVertex + uint32_t(j) * DimMediumVertexStride,
                          sampler, sc, pending, counters);
    st.rays += counters.rays + counters.shadow_rays - rays_before;
}

} // namespace mvpt
