#include "mv_sample.h"

#include "mv_candidates.h"
#include "mv_densities.h"
#include "mv_media.h"
#include "mv_mixture.h"
#include "mv_split_choice.h"
#include "../path/path_steps.h"
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
constexpr uint64_t SplitKey = 0x73706c6974; // "split": split b > 0 of a shared vertex re-keys its stream by SplitKey + b
constexpr uint64_t DeltaSplitKey = 0x64656c7461; // "delta": path k > 0 of a specular first vertex re-keys by DeltaSplitKey + k
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

namespace {

/// A native sample of view l in progress: its pixel, camera sample, first hit and stream.
struct NativeSample {
    int slot;        ///< l
    uint32_t pixel;  ///< in l's sample window
    Vec2f film;      ///< the film position
    float n;         ///< l's native samples in the pixel this pass: the plain weight is 1/n
    SampleKey key;
    Vec2f xi;        ///< the lens sample
    float t;         ///< the time
    const Ray &ray;  ///< the camera ray
    SurfaceInteraction &si;
    Sampler sampler;
    MvViewStats &st;
    uint64_t rays_before; ///< the thread's rays before this sample's camera ray
    MvMediaVertex media;  ///< through media (§10): the first surface and the camera segment
};

/// Radiance only the native strategy produces goes to l's own pixel with the plain weight
/// 1/n_l; it still counts W = 1/n_l so that the weighted estimator's sum of W covers the whole
/// pixel.
void splat_native_only(NativeSample &s, MvSplatSink &sink, MvSplitProbe *probe, const RayCounters &counters,
                       const Spectrum &L) {
    if (probe) mv_probe_native(*probe, s.key, L * (1.f / s.n));
    else if (!sink.native(s.slot, s.pixel, s.film, s.sampler.sample_hash(), Spectrum(0.f), 1.f / s.n, L * (1.f / s.n)))
        sink.lost(s.key);
    ++s.st.sharing;
    s.st.rays += counters.rays + counters.shadow_rays - s.rays_before;
}

/// A native sample that no other view can share (no hit, a first vertex with no smooth lobe,
/// no bounce, or one view): the (volumetric) path tracer's path, to l alone. False when the
/// views may share its first vertex.
bool trace_unshared(const MvContext &ctx, NativeSample &s, bool hit, MvScratch &sc, MvPendingSamples &pending,
                    MvSplatSink &sink, RayCounters &counters) {
    const Scene &scene = *ctx.scene;
    const PathConfig &pc = ctx.path->config();
    const uint32_t max_depth = pc.max_depth < 0 ? UINT_MAX : uint32_t(pc.max_depth);
    const Camera &cam = *ctx.views[s.slot].camera;
    const Light *env = scene.environment();
    const bool unshared = !hit || !s.si.shape->bsdf->has_smooth() || max_depth <= 1 || ctx.views.size() < 2;
    if (ctx.volpath && unshared) {
        if (!ctx.medium_vertices) {
            splat_native_only(s, sink, pending.probe, counters,
                              ctx.volpath->li_in(scene, s.ray, cam.medium.get(), s.sampler, counters));
            return true;
        }
        // The in-scattering along the segment is the medium vertex's; the rest is l's alone.
        splat_native_only(
            s, sink, pending.probe, counters,
            ctx.volpath->li_in(scene, s.ray, cam.medium.get(), s.sampler, counters, VolPathPart::ReachesSurface));
        mv_medium_vertex(ctx, s.slot, s.media.near, s.xi, s.pixel, s.film, s.key, s.sampler, sc, pending, counters, s.st);
        return true;
    }
    if (!hit) {
        const Spectrum le = env && !pc.hide_emitters ? env->eval_environment(s.ray.d) : Spectrum(0.f);
        splat_native_only(s, sink, pending.probe, counters, le);
        return true;
    }
    if (!unshared) return false;
    // Purely specular (or null) first vertex, or no bounce at all: test 4 of §3 fails for
    // every view, the path is the ordinary path tracer's. Where the views could share others'
    // first vertices it is split K ways (MvConfig::delta_splits), path k > 0 from the stream
    // re-keyed by k; the pilot records its PilotSplits paths apart.
    PathState state;
    state.valid = !pc.hide_emitters && env != nullptr;
    if (ctx.views.size() >= 2 && max_depth > 1) s.st.rejected[int(ShiftTest::Bsdf)] += ctx.views.size() - 1;
    const bool split = ctx.views.size() >= 2 && max_depth > 1; // (so the first vertex has no smooth lobe)
    const int k_paths = !split ? 1 : pending.probe ? PilotSplits : std::max(ctx.cfg.delta_splits, 1);
    const Sampler stream = s.sampler;
    Spectrum paths[PilotSplits], L(0.f);
    for (int k = 0; k < k_paths; ++k) {
        Sampler rekeyed = k > 0 ? stream.rekeyed(DeltaSplitKey + uint64_t(k)) : Sampler();
        const Spectrum lk = ctx.path->trace(scene, s.ray, state, k > 0 ? rekeyed : s.sampler, counters, &s.si);
        if (k < PilotSplits) paths[k] = lk;
        L += lk;
    }
    if (pending.probe && split) {
        mv_probe_delta(*pending.probe, s.key, paths, 1.f / s.n);
        s.st.rays += counters.rays + counters.shadow_rays - s.rays_before;
        return true;
    }
    splat_native_only(s, sink, pending.probe, counters, k_paths > 1 ? L * (1.f / float(k_paths)) : L);
    return true;
}

/// The views that share the sample: the shifts (§3 tests 1-3), the selection (§6) and the
/// visibility (test 5) of the candidates, the sharing ones into sc.sharing[0, ns), and the
/// sums D (§5). Returns ns.
size_t sharing_views(const MvContext &ctx, NativeSample &s, const Bsdf &bsdf, MvScratch &sc, RayCounters &counters) {
    const SurfaceInteraction &si = s.si;
    MvVertex y{si.p, si.n, s.t, s.xi, dot(si.n, s.ray.o - si.p)};
    gather_shifts(ctx, s.slot, s.pixel, s.film, y, bsdf, si, sc, &s.st);
    const size_t m = sc.cand.size;
    mv_select(ctx, sc, s.sampler, &bsdf, &si);
    // The balance estimator needs the visibility of every candidate (it enters D); the
    // published variant only that of the selected ones.
    if (ctx.volpath)
        mv_media_visibility(ctx, sc, si.p, si.time, s.media.walk.tr, ctx.cfg.mis_selected_only, &s.sampler, counters,
                            &s.st);
    else
        trace_visibility(ctx, sc, si, s.t, ctx.cfg.mis_selected_only, counters, &s.st);
    // S: the views that shade the sample; V: the strategies in the sums D (§5).
    auto &sharing = sc.sharing;
    grow_scratch(sharing, m);
    size_t ns = 0;
    for (size_t i = 0; i < m; ++i) { // branch-free compaction
        sharing[ns] = int(i);
        ns += sc.visible[i] & sc.selected[i];
    }
    mv_balance_sums(ctx, sc, &bsdf, &si, sharing.data(), ns);
    return ns;
}

/// The sharing views' directions at y (those of all candidates when all share: no gather).
const Vec3f *sharing_directions(MvScratch &sc, size_t ns) {
    if (ns == sc.cand.size) return sc.cand.wi.data();
    grow_scratch(sc.sharing_wi, ns);
    for (size_t i = 0; i < ns; ++i) sc.sharing_wi[i] = sc.cand.wi[sc.sharing[i]];
    return sc.sharing_wi.data();
}

/// Shared next-event estimation (§7): one emitter sample for every sharing view, their BSDF
/// values into f_nee, and the light weight times its MIS weight (zero when no view reflects the
/// light). Its shadow ray joins `pending` (its index into *shadow), or, through media, its
/// transmittance is taken now.
Spectrum shared_nee(const MvContext &ctx, NativeSample &s, const Bsdf &bsdf, const Vec3f *wi_s, size_t ns,
                    const LobeClasses &classes, float u_select, Vec2f u_light, Spectrum *f_nee, MvScratch &sc,
                    MvPendingSamples &pending, RayCounters &counters, int32_t *shadow) {
    const Scene &scene = *ctx.scene;
    const auto &lights = scene.lights();
    const SurfaceInteraction &si = s.si;
    if (lights.empty()) return Spectrum(0.f);
    const Light &light = *lights[uniform_emitter_index(u_select, lights.size())];
    auto [ls, weight] = light.sample_li(si.p, u_light, si.time);
    if (weight.is_black()) return Spectrum(0.f);
    weight *= float(lights.size());
    Vec3f wo = si.to_local(ls.d);
    auto &pdf = sc.view_pdf;
    grow_scratch(pdf, ns);
    bsdf.eval_pdf_views(Ctx, si, wi_s, ns, wo, f_nee, pdf.data());
    const float p_mix = smooth_mixture_pdf(classes, pdf.data(), ns); // the bounce's density of wo
    if (!(max_over_views(f_nee, ns) > 0.f)) return Spectrum(0.f); // no view reflects light this way
    const Ray ray = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
    if (ctx.volpath) { // the transmittance to the light, now
        s.sampler.set_dimension(DimSharedShadow);
        RandomStream rs = s.sampler.next_stream();
        weight *= shadow_transmittance(scene, ray, mv_medium_towards(si, ls.d, s.media.walk.medium), rs, counters);
    } else { // a shadow ray, traced with the tile's others
        *shadow = int32_t(pending.shadow_rays.size());
        pending.shadow_rays.push_back(ray);
        ++counters.shadow_rays;
    }
    return weight * emitter_sample_mis(ls, float(lights.size()), p_mix);
}

/// A number of a shared vertex's splits drawn in strata (§7, "Splitting"): split b's is
/// (b + u) / count, u the one split 0 draws, so that B splits take each of n choices about B / n
/// times (the emitter; the bounce's kind and view).
struct SplitStrata {
    float u = 0.f;
    int count = 1; ///< 1: each split chooses by its own number
    /// Split b's number, given the one it drew itself.
    float at(int b, float own) const {
        return count > 1 ? std::min((float(b) + u) / float(count), OneMinusEpsilon) : own;
    }
};

/// The shared bounce from the lobe mixture, one suffix for every sharing view (§7), with
/// Russian roulette at y as the path tracer's at depth 0: the views' BSDF values into fs, the
/// suffix into `pending`, and into `rec` its index, validity and the factor of b_i = f_i(wo) /
/// p_mix(wo) (or, for a delta lobe, the sampled view and its weight).
void shared_bounce(const MvContext &ctx, NativeSample &s, const Bsdf &bsdf, const Vec3f *wi_s, size_t ns,
                   const LobeClasses &classes, float u_lobe, Vec2f u_dir, float u_rr, SplitStrata event, int b,
                   bool valid, Spectrum *fs, MvScratch &sc, MvPendingSamples &pending, MvPendingSamples::Sample &rec) {
    const PathConfig &pc = ctx.path->config();
    const SurfaceInteraction &si = s.si;
    s.sampler.set_dimension(DimBounceView);
    grow_scratch(sc.view_pdf, ns);
    MixtureSample mix =
        sample_lobe_mixture(bsdf, si, wi_s, ns, classes, event.at(b, s.sampler.next_1d()), u_lobe, u_dir, fs,
                            sc.view_pdf.data());
    const BsdfSample &bs = mix.bs;
    // (Validity is the path tracer's rule: the volumetric one keeps every path, as Mitsuba's.)
    rec.valid = valid || !(bs.sampled_type & BsdfNull) || ctx.volpath;
    float b_scale = 0.f; // b_i = fs[i] * b_scale (smooth), or mix.weight |S| b_scale for the delta view only
    if (!mix.weight.is_black() && mix.pdf > 0.f) {
        // A delta lobe's direction serves only the view that sampled it.
        const float t_max = mix.delta ? mix.weight.max_value() * float(ns) : max_over_views(fs, ns) / mix.pdf;
        b_scale = mix.delta ? 1.f : 1.f / mix.pdf;
        bool alive = t_max > 0.f;
        if (alive && 1 >= pc.rr_depth) { // Russian roulette at y, as the path tracer does at depth 0
            float q = rr_survival(t_max, bs.eta);
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
            state.valid = rec.valid;
            rec.suffix = int32_t(pending.rays.size());
            const Vec3f wo = si.to_world(bs.wo);
            pending.rays.push_back(si.spawn_ray(wo));
            if (ctx.volpath) {
                pending.media.push_back(mv_medium_towards(si, wo, s.media.walk.medium));
                pending.dims.push_back(DimCameraEnd);
            }
            pending.states.push_back(state);
            pending.samplers.push_back(s.sampler);
        }
    }
    if (mix.delta) b_scale *= float(ns);
    rec.delta_view = mix.delta ? int32_t(mix.view) : -1;
    if (mix.delta && (bs.sampled_type & BsdfNull)) // its view's own odds of a null event over these
        rec.null_scale = float(ns) * (classes.split ? classes.p_delta[mix.view] / classes.q : 1.f);
    rec.b_scale = b_scale;
    if (mix.delta) rec.delta_bounce = mix.weight * b_scale;
}

/// Through media (§10): each sharing view's camera segment, its transmittance on the view's
/// values, and l's in-scattering along its own (unless the medium vertices share it).
void camera_segments(const MvContext &ctx, NativeSample &s, const MvScratch &sc, size_t ns, const Spectrum &le_y,
                     Spectrum *f_nee, Spectrum *fs, MvPendingSamples::Sample &rec, RayCounters &counters) {
    for (size_t i = 0; i < ns; ++i) {
        const Spectrum &tr = sc.tr[sc.sharing[i]];
        f_nee[i] *= tr, fs[i] *= tr;
    }
    if (rec.delta_view >= 0) rec.delta_bounce *= sc.tr[sc.sharing[rec.delta_view]];
    if (rec.splits == 0) return; // E, with l's in-scattering, is the first split's alone
    const Spectrum in_scattered =
        ctx.medium_vertices ? Spectrum(0.f) : mv_in_scattering(ctx, s.slot, s.ray, s.media, s.sampler, counters);
    rec.e = (le_y * s.media.walk.tr + in_scattered) * (1.f / s.n);
}

/// Each sharing view's share L_i / D_i, splatted once the suffix is known: the views' slots,
/// pixels, film positions and 1/D_i into `pending` from entry `first` (the native view is
/// sharing[0], candidate 0, always visible and selected).
void queue_shares(const MvScratch &sc, size_t ns, size_t first, MvPendingSamples &pending) {
    const MvCandidates &cand = sc.cand;
    int *const slot_out = pending.slot.data() + first;
    uint32_t *const pixel_out = pending.pixel.data() + first;
    Vec2f *const film_out = pending.film.data() + first;
    float *const w_out = pending.w.data() + first;
    if (ns == cand.size) { // every candidate shares: contiguous copies
        std::copy_n(cand.slot.data(), ns, slot_out);
        std::copy_n(cand.pixel.data(), ns, pixel_out);
        std::copy_n(cand.film.data(), ns, film_out);
        for (size_t i = 0; i < ns; ++i) w_out[i] = 1.f / sc.d[i];
        return;
    }
    for (size_t i = 0; i < ns; ++i) {
        const int k = sc.sharing[i];
        slot_out[i] = cand.slot[k];
        pixel_out[i] = cand.pixel[k];
        film_out[i] = cand.film[k];
        w_out[i] = 1.f / sc.d[k];
    }
}

/// Split b of a shared first vertex (§7, "Splitting"), from its own stream but for the numbers
/// that choose its emitter and its bounce's kind and view (`emitter`, `event`): one emitter
/// sample and one bounce for every sharing view, queued in `pending` until its suffix and
/// shadow ray are traced. Per sharing view i the radiance is
///   L_i = f_i(wo_nee) * nee_weight + b_i * suffix,   b_i = f_i(wo) / p_mix(wo) (RR included);
/// the first split's record also holds the views' entries and E.
void share_split(const MvContext &ctx, NativeSample &s, const Bsdf &bsdf, const Vec3f *wi_s, size_t ns,
                 const LobeClasses &classes, int splits, int b, SplitStrata emitter, SplitStrata event, bool valid,
                 const Spectrum &le_y, MvScratch &sc, MvPendingSamples &pending, RayCounters &counters) {
    s.sampler.set_dimension(DimCameraEnd); // the path tracer's block of vertex 0
    const float u_emitter = emitter.at(b, s.sampler.next_1d());
    const Vec2f u_light = s.sampler.next_2d();
    const float u_lobe = s.sampler.next_1d();
    const Vec2f u_dir = s.sampler.next_2d();
    const float u_rr = s.sampler.next_1d();
    // The sharing views' BSDF values go straight into the queue (splatted once the suffix is
    // known); f_nee holds stale values when there is no NEE, fs when the lobe is a delta: never read.
    const size_t first = pending.add_entries(ns);
    Spectrum *const f_nee = pending.f_nee.data() + first, *const fs = pending.f_bounce.data() + first;
    MvPendingSamples::Sample rec;
    rec.key = s.key;
    rec.first = uint32_t(first);
    rec.count = uint32_t(ns);
    rec.splits = b == 0 ? uint32_t(splits) : 0u;
    rec.shadow = -1;
    rec.nee_weight =
        shared_nee(ctx, s, bsdf, wi_s, ns, classes, u_emitter, u_light, f_nee, sc, pending, counters, &rec.shadow);
    rec.nee = !rec.nee_weight.is_black();
    shared_bounce(ctx, s, bsdf, wi_s, ns, classes, u_lobe, u_dir, u_rr, event, b, valid, fs, sc, pending, rec);
    if (b == 0) rec.e = le_y * (1.f / s.n);
    if (ctx.volpath) camera_segments(ctx, s, sc, ns, le_y, f_nee, fs, rec, counters);
    rec.hash = s.sampler.sample_hash(); // (the splats' taps take the first split's: the sample's)
    if (b == 0) queue_shares(sc, ns, first, pending);
    pending.samples.push_back(rec);
}

/// A native sample whose first vertex y the views share (§7): emission at y to l only, the
/// sharing views, and `splits` light samples and bounces for all of them, each weighted
/// 1/splits (split 0 on the sample's stream, split b on the stream re-keyed by b); the
/// contribution of view i is the mean of its splits' L_i, over D_i.
void share_first_vertex(const MvContext &ctx, NativeSample &s, MvScratch &sc, MvPendingSamples &pending,
                        RayCounters &counters) {
    const PathConfig &pc = ctx.path->config();
    SurfaceInteraction &si = s.si;
    const Bsdf &bsdf = *si.shape->bsdf;
    bool valid = !pc.hide_emitters && ctx.scene->environment() != nullptr;
    Spectrum le_y(0.f);
    if (const Light *emitter = si.shape->emitter.get(); emitter && !pc.hide_emitters) {
        valid = true;
        le_y = emitter->eval(si, -s.ray.d);
    }
    si.wi = si.to_local(-s.ray.d);
    const size_t ns = sharing_views(ctx, s, bsdf, sc, counters);
    const Vec3f *wi_s = sharing_directions(sc, ns);
    grow_scratch(sc.p_delta, ns), grow_scratch(sc.smooth_scale, ns);
    const LobeClasses classes = lobe_classes(bsdf, si, wi_s, ns, sc.p_delta.data(), sc.smooth_scale.data());
    const Sampler stream = s.sampler;
    const int splits = ctx.cfg.splits;
    // The splits' emitter choices and their bounces' kinds and views are stratified; the
    // pilot's stay independent, since the spread of its splits estimates r only then.
    SplitStrata emitter, event;
    if (!pending.probe) {
        Sampler first = stream;
        first.set_dimension(DimCameraEnd);
        emitter = {first.next_1d(), splits};
        first.set_dimension(DimBounceView);
        event = {first.next_1d(), splits};
    }
    for (int b = 0; b < splits; ++b) {
        if (b > 0) s.sampler = stream.rekeyed(SplitKey + uint64_t(b));
        share_split(ctx, s, bsdf, wi_s, ns, classes, splits, b, emitter, event, valid, le_y, sc, pending, counters);
    }
    s.sampler = stream;
    s.st.sharing += ns;
    s.st.rays += counters.rays + counters.shadow_rays - s.rays_before;
    if (ctx.medium_vertices)
        mv_medium_vertex(ctx, s.slot, s.media.near, s.xi, s.pixel, s.film, s.key, s.sampler, sc, pending, counters, s.st);
}

} // namespace

void mv_native_sample(const MvContext &ctx, int slot_l, MvPrimaries &prim, size_t i_prim, MvScratch &sc,
                      MvPendingSamples &pending, MvSplatSink &sink, RayCounters &counters, MvViewStats *stats) {
    const MvView &l = ctx.views[slot_l];
    const int px = int(prim.px[i_prim]), py = int(prim.py[i_prim]);
    const uint32_t pixel_l = ctx.windows[slot_l].index(px, py);
    MvViewStats &st_l = stats[slot_l];
    const uint64_t rays_before = counters.rays + counters.shadow_rays;
    ++st_l.native;
    // The native sample's stream (its camera dimensions were drawn by mv_trace_primaries).
    NativeSample s{slot_l,
                   pixel_l,
                   prim.camera.film[i_prim],
                   float(ctx.native_map[slot_l][pixel_l]),
                   SampleKey{int64_t(prim.sample_index[i_prim]), int64_t(l.scene_index), py, px},
                   prim.camera.lens[i_prim],
                   prim.camera.time[i_prim],
                   prim.rays[i_prim],
                   prim.si[i_prim],
                   Sampler(l.camera->sampler_kind, ctx.seeds[slot_l]),
                   st_l,
                   rays_before,
                   {}};
    prim.camera.start(s.sampler, i_prim, l.scene_index, uint32_t(px), uint32_t(py), prim.sample_index[i_prim], 0);
    ++counters.camera_rays;
    ++counters.rays;
    bool hit = prim.hit[i_prim] != 0;
    // Through media (§10) the shared vertex is the first surface that is not null.
    if (ctx.volpath) {
        s.media = mv_media_first_vertex(ctx, slot_l, s.ray, s.sampler, counters);
        hit = s.media.found();
        if (hit) s.si = s.media.walk.si;
    }
    // The next sample's rig cells start loading (trace_visibility consults them unless only
    // the selected views are traced).
    if (ctx.rig && !ctx.cfg.mis_selected_only && i_prim + 1 < prim.size() && prim.hit[i_prim + 1]) {
        const SurfaceInteraction &next = prim.si[i_prim + 1];
        ctx.rig->prefetch(next.p, next.shape, next.prim);
    }
    if (!trace_unshared(ctx, s, hit, sc, pending, sink, counters)) share_first_vertex(ctx, s, sc, pending, counters);
}

void mv_native_samples(const MvContext &ctx, int slot, MvPrimaries &prim, MvScratch &scratch, MvPendingSamples &pending,
                       MvSplatSink &sink, RayCounters &counters, MvViewStats *stats) {
    const size_t batch = size_t(std::max(ctx.cfg.batch_entries, 1));
    for (size_t i = 0; i < prim.size(); ++i) {
        mv_native_sample(ctx, slot, prim, i, scratch, pending, sink, counters, stats);
        if (pending.entries >= batch) mv_finish_samples(ctx, slot, pending, sink, counters, stats);
    }
    mv_finish_samples(ctx, slot, pending, sink, counters, stats);
}

} // namespace mvpt
