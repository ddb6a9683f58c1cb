#include "mv_sample.h"

#include "mv_candidates.h"
#include "mv_densities.h"
#include "mv_media.h"
#include "mv_mixture.h"
#include "../path/transmittance.h"
#include "../path/volpath.h"

#include "../../render/bsdf.h"
#include "../../render/light.h"
#include "../../render/shape.h"
#include "../../accel/scene.h"

#include <algorithm>
#include <climits>

namespace mvpt {

namespace {
const BsdfContext Ctx;
} // namespace

void mv_shift_views(const MvContext &ctx, int slot_l, const MvVertex &y, MvScratch &sc) {
    if (ctx.static_shift) { // one vector loop over contiguous camera data, no virtual call per view
        shift_static_views(ctx.projections, ctx.films, y, sc.shifts);
        return;
    }
    const size_t nv = ctx.views.size();
    ViewShifts &vs = sc.shifts;
    vs.resize(nv);
    ShiftBatch &b = vs.geo;
    const MvView &l = ctx.views[slot_l];
    for (size_t k = 0; k < nv; ++k) {
        const MvView &vk = ctx.views[k];
        float t_k = y.time;
        if (int(k) != slot_l && !shift_time(l, vk, y.time, ctx.scene_moves, &t_k)) {
            vs.status[k] = ShiftTimeOff;
            continue;
        }
        ShiftGeometry g;
        bool ok = vk.camera->shift_geometry(y.p, y.n, t_k, y.lens, &g);
        vs.status[k] = shift_status(y, ok, g, ctx.windows[k], &vs.pixel[k]);
        b.film_x[k] = g.film.x, b.film_y[k] = g.film.y;
        b.lens_x[k] = g.lens_point.x, b.lens_y[k] = g.lens_point.y, b.lens_z[k] = g.lens_point.z;
        b.density[k] = g.density;
        b.visible_length[k] = g.visible_length;
    }
}

namespace {

/// The candidates of §3 for the native sample of view `slot_l` (pixel `pixel_l`) with first hit
/// `y`: the native view first, then every view that passes the cheap tests, with its native
/// count and viewing direction (and lobe, for the material similarity).
void gather_shifts(const MvContext &ctx, int slot_l, uint32_t pixel_l, Vec2f film_l, const MvVertex &y,
                   const Bsdf &bsdf, const SurfaceInteraction &si, MvScratch &sc, MvViewStats *st_l) {
    const int nv = int(ctx.views.size());
    mv_shift_views(ctx, slot_l, y, sc);
    const ViewShifts &vs = sc.shifts;
    MvCandidates &c = sc.cand;
    c.reserve(size_t(nv));
    c.size = 0;
    c.push(vs, slot_l, float(ctx.native_map[slot_l][pixel_l]));
    c.pixel[0] = pixel_l;
    c.film[0] = film_l;
    if (!(vs.status[slot_l] & ShiftDepth)) {
        if (st_l) st_l->tried += uint64_t(nv - 1);
        for (int k = 0; k < nv; ++k) {
            if (k == slot_l) continue;
            if (uint32_t status = vs.status[k]) {
                if (st_l) ++st_l->rejected[int(first_failed_test(status))];
                continue;
            }
            c.push(vs, k, float(ctx.native_map[k][vs.pixel[k]]));
        }
    } else {
        c.g[0] = 1.f; // no density to compare (G_l <= 0, a grazing hit): the sample is l's alone, D_l = n_l
    }
    const size_t m = c.size;
    viewing_directions(c, si.p, si.sh_frame);
    c.wi[0] = si.wi; // the native view's direction is the camera ray's
    sc.s_sel.assign(m, 1.f);
    sc.visible.assign(m, 1);
    sc.selected.assign(m, 1);
    sc.alpha = bsdf.roughness(si);
    sc.material = ctx.cfg.select_material && (bsdf.flags() & BsdfGlossy);
    if (sc.material) {
        sc.sm.assign(m * m, -1.f);
        sc.lobe.resize(m);
        for (size_t i = 0; i < m; ++i) sc.lobe[i] = view_lobe(bsdf, si, c.wi[i]);
    }
}

/// Visibility of y from every candidate's lens point (or only the selected ones), traced as
/// packets from one origin; fills sc.visible.
void trace_visibility(const MvContext &ctx, MvScratch &sc, const SurfaceInteraction &si, float t, bool selected_only,
                      RayCounters &counters, MvViewStats *st_l) {
    const MvCandidates &c = sc.cand;
    const size_t m = c.size;
    if (m < 2) return;
    // Every candidate's lens point is on the native lens point's side of the surface (§3
    // orientation test), so all visibility rays leave from one offset origin.
    const Point3f o = si.offset_p(c.lens_point(0) - si.p);
    if (!selected_only && ctx.rig && ctx.rig->unblocked(o, si.shape, si.prim)) {
        // y's cell sees the whole rig: every candidate is visible (sc.visible is all 1), no
        // segment is built; those with room to block count as visibility rays, as when traced.
        uint64_t rays = 0, unselected = 0;
        for (size_t i = 1; i < m; ++i) rays += c.vis[i] > 0.f, unselected += sc.selected[i] == 0;
        counters.shadow_rays += rays;
        if (st_l) st_l->rejected[int(ShiftTest::Selection)] += unselected;
        return;
    }
    auto &seg = sc.segments;
    const size_t padded = whole_lanes(m - 1); // whole vectors, and whole packets for occluded_segments
    grow_scratch(seg, 4 * padded);
    float *dx = seg.data(), *dy = dx + padded, *dz = dy + padded, *t_max = dz + padded;
    visibility_segments(c, o, si.p, dx, dy, dz, t_max);
    if (selected_only)
        for (size_t i = 1; i < m; ++i)
            if (!sc.selected[i]) {
                t_max[i - 1] = -1.f;
                sc.visible[i] = 0;
                if (st_l) ++st_l->rejected[int(ShiftTest::Selection)];
            }
    auto &blocked = sc.blocked;
    grow_scratch(blocked, m);
    ctx.scene->occluded_segments(o, dx, dy, dz, t_max, m - 1, t, blocked.data(), ctx.across);
    for (size_t i = 1; i < m; ++i) {
        if (selected_only && !sc.selected[i]) continue;
        counters.shadow_rays += t_max[i - 1] > 0.f;
        sc.visible[i] = !blocked[i - 1];
        if (!st_l) continue;
        if (!sc.visible[i]) ++st_l->rejected[int(ShiftTest::Visibility)];
        else if (!selected_only && !sc.selected[i]) ++st_l->rejected[int(ShiftTest::Selection)];
    }
}

} // namespace

std::vector<std::pair<int, float>> mv_balance_densities(const MvContext &ctx, int slot, const SurfaceInteraction &hit,
                                                        Point3f lens_point, float time, Vec2f lens, MvScratch &sc) {
    const SampleWindow &window = ctx.windows[slot];
    SurfaceInteraction si = hit;
    si.wi = si.to_local(normalize(lens_point - si.p));
    ShiftGeometry geo;
    std::vector<std::pair<int, float>> out;
    if (!ctx.views[slot].camera->shift_geometry(si.p, si.n, time, lens, &geo) || !window.contains(geo.film)) return out;
    uint32_t pixel = window.index(int(std::floor(geo.film.x)), int(std::floor(geo.film.y)));
    MvVertex y{si.p, si.n, time, lens, dot(si.n, lens_point - si.p)};
    const Bsdf &bsdf = *si.shape->bsdf;
    gather_shifts(ctx, slot, pixel, geo.film, y, bsdf, si, sc, nullptr);
    RayCounters counters;
    if (ctx.volpath) mv_media_visibility(ctx, sc, si.p, si.time, Spectrum(1.f), false, nullptr, counters, nullptr);
    else trace_visibility(ctx, sc, si, time, false, counters, nullptr);
    std::vector<int> targets;
    for (size_t i = 0; i < sc.cand.size; ++i)
        if (sc.visible[i]) targets.push_back(int(i));
    mv_balance_sums(ctx, sc, &bsdf, &si, targets.data(), targets.size());
    for (int i : targets) out.emplace_back(sc.cand.slot[i], sc.d[i]);
    return out;
}

void mv_trace_primaries(const MvContext &ctx, int slot, MvPrimaries &prim) {
    const MvView &l = ctx.views[slot];
    const Camera &cam = *l.camera;
    const size_t n = prim.size();
    prim.rays.resize(n), prim.si.resize(n), prim.hit.resize(n);
    // Native sample z_l = (t, x_l, xi) (§2). Box filter: x_l uniform in the pixel. xi is drawn
    // for pinholes too: other views may have a lens.
    CameraSamples &cs = prim.camera;
    cs.draw(cam, ctx.seeds[slot], l.scene_index, prim.px.data(), prim.py.data(), prim.sample_index.data(), n,
            FilmSampling::Box, true);
    cam.generate_rays(cs.film.data(), cs.lens.data(), cs.time.data(), n, prim.rays.data());
    ctx.scene->intersect(prim.rays.data(), n, prim.si.data(), prim.hit.data(), true);
}

void mv_native_sample(const MvContext &ctx, int slot_l, MvPrimaries &prim, size_t i_prim, MvScratch &sc,
                      MvPendingSamples &pending, MvSplatSink &sink, RayCounters &counters, MvViewStats *stats) {
    const Scene &scene = *ctx.scene;
    const PathConfig &pc = ctx.path->config();
    const uint32_t max_depth = pc.max_depth < 0 ? UINT_MAX : uint32_t(pc.max_depth);
    const MvView &l = ctx.views[slot_l];
    const Camera &cam = *l.camera;
    const int px = int(prim.px[i_prim]), py = int(prim.py[i_prim]);
    const uint32_t pixel_l = ctx.windows[slot_l].index(px, py);
    const Vec2f film_l = prim.camera.film[i_prim];
    const float n_l = float(ctx.native_map[slot_l][pixel_l]);
    MvViewStats &st_l = stats[slot_l];
    const uint64_t rays_before = counters.rays + counters.shadow_rays;
    ++st_l.native;

    // The native sample's stream (its camera dimensions were drawn by mv_trace_primaries).
    Sampler sampler(cam.sampler_kind, ctx.seeds[slot_l]);
    prim.camera.start(sampler, i_prim, l.scene_index, uint32_t(px), uint32_t(py), prim.sample_index[i_prim], 0);
    const Vec2f xi = prim.camera.lens[i_prim];
    const float t = prim.camera.time[i_prim];
    const Ray &ray = prim.rays[i_prim];
    ++counters.camera_rays;
    ++counters.rays;
    SurfaceInteraction &si = prim.si[i_prim];
    bool hit = prim.hit[i_prim] != 0;
    // Through media (§10) the shared vertex is the first surface that is not null.
    MvMediaVertex media_y;
    if (ctx.volpath) {
        media_y = mv_media_first_vertex(ctx, slot_l, ray, sampler, counters);
        hit = media_y.found();
        if (hit) si = media_y.walk.si;
    }
    // The next sample's rig cells start loading (trace_visibility consults them unless only
    // the selected views are traced).
    if (ctx.rig && !ctx.cfg.mis_selected_only && i_prim + 1 < prim.size() && prim.hit[i_prim + 1]) {
        const SurfaceInteraction &next = prim.si[i_prim + 1];
        ctx.rig->prefetch(next.p, next.shape, next.prim);
    }

    // Radiance only the native strategy produces goes to l's own pixel with the plain weight 1/n_l;
    // it still counts W = 1/n_l so that the weighted estimator's sum of W covers the whole pixel.
    const SampleKey key{int64_t(prim.sample_index[i_prim]), int64_t(l.scene_index), py, px};
    auto native_only = [&](const Spectrum &L) {
        if (!sink.native(slot_l, pixel_l, film_l, sampler.sample_hash(), Spectrum(0.f), 1.f / n_l, L * (1.f / n_l)))
            sink.lost(key);
        ++st_l.sharing;
        st_l.rays += counters.rays + counters.shadow_rays - rays_before;
    };
    const Light *env = scene.environment();
    // Where no view can share the sample through media, it is the volumetric path tracer's.
    const bool unshared = !hit || !si.shape->bsdf->has_smooth() || max_depth <= 1 || ctx.views.size() < 2;
    if (ctx.volpath && unshared) {
        if (!ctx.medium_vertices) {
            native_only(ctx.volpath->li_in(scene, ray, cam.medium.get(), sampler, counters));
            return;
        }
        // The in-scattering along the segment is the medium vertex's; the rest is l's alone.
        native_only(ctx.volpath->li_in(scene, ray, cam.medium.get(), sampler, counters, VolPathPart::ReachesSurface));
        mv_medium_vertex(ctx, slot_l, media_y.near, xi, pixel_l, film_l, key, sampler, sc, pending, counters, st_l);
        return;
    }
    if (!hit) {
        native_only(env && !pc.hide_emitters ? env->eval_environment(ray.d) : Spectrum(0.f));
        return;
    }
    const Bsdf &bsdf = *si.shape->bsdf;
    if (unshared) {
        // Purely specular (or null) first vertex, or no bounce at all: test 4 of §3 fails for
        // every view, the path is the ordinary path tracer's.
        PathState state;
        state.valid = !pc.hide_emitters && env != nullptr;
        Spectrum L = ctx.path->trace(scene, ray, state, sampler, counters, &si);
        if (ctx.views.size() >= 2 && max_depth > 1) st_l.rejected[int(ShiftTest::Bsdf)] += ctx.views.size() - 1;
        native_only(L);
        return;
    }

    // ---------------- Emission at y: to l only (§7) ----------------
    bool valid = !pc.hide_emitters && env != nullptr;
    Spectrum le_y(0.f);
    if (const Light *emitter = si.shape->emitter.get(); emitter && !pc.hide_emitters) {
        valid = true;
        le_y = emitter->eval(si, -ray.d);
    }
    si.wi = si.to_local(-ray.d);

    // ---------------- Shifts (§3 tests 1-3), selection (§6), visibility (test 5) ----------------
    MvVertex y{si.p, si.n, t, xi, dot(si.n, ray.o - si.p)};
    gather_shifts(ctx, slot_l, pixel_l, film_l, y, bsdf, si, sc, &st_l);
    const MvCandidates &cand = sc.cand;
    const size_t m = cand.size;
    mv_select(ctx, sc, sampler, &bsdf, &si);
    // The balance estimator needs the visibility of every candidate (it enters D); the
    // published variant only that of the selected ones.
    if (ctx.volpath)
        mv_media_visibility(ctx, sc, si.p, si.time, media_y.walk.tr, ctx.cfg.mis_selected_only, &sampler, counters, &st_l);
    else
        trace_visibility(ctx, sc, si, t, ctx.cfg.mis_selected_only, counters, &st_l);
    // S: the views that shade the sample; V: the strategies in the sums D (§5).
    auto &sharing = sc.sharing;
    grow_scratch(sharing, m);
    size_t ns = 0;
    for (size_t i = 0; i < m; ++i) { // branch-free compaction
        sharing[ns] = int(i);
        ns += sc.visible[i] & sc.selected[i];
    }
    mv_balance_sums(ctx, sc, &bsdf, &si, sharing.data(), ns);

    // ---------------- Shared next-event estimation (§7) ----------------
    sampler.set_dimension(DimCameraEnd); // the path tracer's block of vertex 0
    float u_light_select = sampler.next_1d();
    Vec2f u_light = sampler.next_2d();
    float u_lobe = sampler.next_1d();
    Vec2f u_dir = sampler.next_2d();
    float u_rr = sampler.next_1d();
    // Per sharing view i (candidate sharing[i]) the radiance is
    //   L_i = f_i(wo_nee) * nee_weight + b_i * suffix,   b_i = f_i(wo) / p_mix(wo) (RR included),
    // and the contribution L_i / D_i.
    auto &wis = sc.sharing_wi;
    const Vec3f *wi_s = cand.wi.data(); // the sharing views' directions (all candidates share: no gather)
    if (ns < m) {
        grow_scratch(wis, ns);
        for (size_t i = 0; i < ns; ++i) wis[i] = cand.wi[sharing[i]];
        wi_s = wis.data();
    }
    const auto &lights = scene.lights();
    // The sharing views' BSDF values go straight into the queue (splatted once the suffix is known).
    const size_t first = pending.add_entries(ns);
    Spectrum *const f_nee = pending.f_nee.data() + first;
    Spectrum nee_weight(0.f); // light weight times MIS weight, zero when no view reflects the light
    int32_t nee_shadow = -1;  // its shadow ray, traced in mv_finish_samples
    if (!lights.empty()) {
        const Light &light = *lights[uniform_emitter_index(u_light_select, lights.size())];
        auto [ls, weight] = light.sample_li(si.p, u_light, si.time);
        if (!weight.is_black()) {
            weight *= float(lights.size());
            Vec3f wo = si.to_local(ls.d);
            auto &pdf = sc.view_pdf;
            grow_scratch(pdf, ns);
            bsdf.eval_pdf_views(Ctx, si, wi_s, ns, wo, f_nee, pdf.data());
            const float p_mix = sum_over_views(pdf.data(), ns); // the lobe mixture's density times |S|
            if (max_over_views(f_nee, ns) > 0.f) { // some view reflects light this way
                const Ray shadow = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
                if (ctx.volpath) { // the transmittance to the light, now
                    sampler.set_dimension(DimSharedShadow);
                    RandomStream rs = sampler.next_stream();
                    weight *= shadow_transmittance(scene, shadow, mv_medium_towards(si, ls.d, media_y.walk.medium), rs,
                                                   counters);
                } else { // a shadow ray, traced with the tile's others
                    nee_shadow = int32_t(pending.shadow_rays.size());
                    pending.shadow_rays.push_back(shadow);
                    ++counters.shadow_rays;
                }
                nee_weight = weight * emitter_sample_mis(ls, float(lights.size()), p_mix / float(ns));
            }
        }
    }
    const bool nee = !nee_weight.is_black();

    // ---------------- Shared bounce from the lobe mixture, one suffix (§7) ----------------
    sampler.set_dimension(DimBounceView);
    Spectrum *const fs = pending.f_bounce.data() + first;
    grow_scratch(sc.view_pdf, ns);
    MixtureSample mix =
        sample_lobe_mixture(bsdf, si, wi_s, ns, sampler.next_1d(), u_lobe, u_dir, fs, sc.view_pdf.data());
    const BsdfSample &bs = mix.bs;
    // (Validity is the path tracer's rule: the volumetric one keeps every path, as Mitsuba's.)
    bool valid_after = valid || !(bs.sampled_type & BsdfNull) || ctx.volpath;
    MvPendingSamples::Sample rec;
    rec.key = key;
    rec.valid = valid_after;
    float b_scale = 0.f; // b_i = fs[i] * b_scale (smooth), or mix.weight |S| b_scale for the delta view only
    if (!mix.weight.is_black() && mix.pdf > 0.f) {
        // A delta lobe's direction serves only the view that sampled it.
        float t_max = 0.f;
        if (mix.delta) {
            t_max = mix.weight.max_value() * float(ns);
        } else {
            t_max = max_over_views(fs, ns) / mix.pdf;
        }
        b_scale = mix.delta ? 1.f : 1.f / mix.pdf;
        bool alive = t_max > 0.f;
        if (alive && 1 >= pc.rr_depth) { // Russian roulette at y, as the path tracer does at depth 0
            float q = std::min(t_max * bs.eta * bs.eta, 0.95f);
            if (u_rr >= q) alive = false;
            else b_scale /= q;
        }
        if (alive) { // the suffix: traced with the tile's other suffixes (mv_finish_samples)
            PathState state;
            state.depth = 1;
            state.eta = bs.eta;
            state.prev_p = si.p;
            state.prev_bsdf_pdf = mix.pdf;
            state.prev_bsdf_delta = mix.delta;
            state.valid = valid_after;
            rec.suffix = int32_t(pending.rays.size());
            const Vec3f wo = si.to_world(bs.wo);
            pending.rays.push_back(si.spawn_ray(wo));
            if (ctx.volpath) {
                pending.media.push_back(mv_medium_towards(si, wo, media_y.walk.medium));
                pending.dims.push_back(DimCameraEnd);
            }
            pending.states.push_back(state);
            pending.samplers.push_back(sampler);
        }
    }
    if (mix.delta) b_scale *= float(ns);

    // ---------------- Each sharing view's share, L_i / D_i, splatted once the suffix is known ----------------
    // The native view is sharing[0] (candidate 0, always visible and selected).
    rec.first = uint32_t(first);
    rec.count = uint32_t(ns);
    rec.delta_view = mix.delta ? int32_t(mix.view) : -1;
    rec.shadow = nee_shadow;
    rec.nee = nee;
    rec.nee_weight = nee_weight;
    rec.b_scale = b_scale;
    if (mix.delta) rec.delta_bounce = mix.weight * b_scale;
    rec.e = le_y * (1.f / n_l);
    if (ctx.volpath) { // each view's camera segment (§10): its transmittance, and l's in-scattering
        for (size_t i = 0; i < ns; ++i) {
            const Spectrum &tr = sc.tr[sharing[i]];
            f_nee[i] *= tr, fs[i] *= tr;
        }
        if (mix.delta) rec.delta_bounce *= sc.tr[sharing[mix.view]];
        // (The in-scattering is the medium vertex's where those are shared.)
        const Spectrum in_scattered =
            ctx.medium_vertices ? Spectrum(0.f) : mv_in_scattering(ctx, slot_l, ray, media_y, sampler, counters);
        rec.e = (le_y * media_y.walk.tr + in_scattered) * (1.f / n_l);
    }
    rec.hash = sampler.sample_hash();
    int *const slot_out = pending.slot.data() + first;
    uint32_t *const pixel_out = pending.pixel.data() + first;
    Vec2f *const film_out = pending.film.data() + first;
    float *const w_out = pending.w.data() + first;
    if (ns == m) { // every candidate shares: contiguous copies
        std::copy_n(cand.slot.data(), ns, slot_out);
        std::copy_n(cand.pixel.data(), ns, pixel_out);
        std::copy_n(cand.film.data(), ns, film_out);
        for (size_t i = 0; i < ns; ++i) w_out[i] = 1.f / sc.d[i];
    } else {
        for (size_t i = 0; i < ns; ++i) {
            const int k = sharing[i];
            slot_out[i] = cand.slot[k];
            pixel_out[i] = cand.pixel[k];
            film_out[i] = cand.film[k];
            w_out[i] = 1.f / sc.d[k];
        }
    }
    // (f_nee holds stale values when there is no NEE, fs when the lobe is a delta: never read.)
    pending.samples.push_back(rec);
    st_l.sharing += ns;
    st_l.rays += counters.rays + counters.shadow_rays - rays_before;
    if (ctx.medium_vertices)
        mv_medium_vertex(ctx, slot_l, media_y.near, xi, pixel_l, film_l, key, sampler, sc, pending, counters, st_l);
}

} // namespace mvpt
