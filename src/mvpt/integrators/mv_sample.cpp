#include "mv_sample.h"

#include "mv_mixture.h"

#include "../core/warp.h"
#include "../render/bsdf.h"
#include "../render/light.h"
#include "../render/shape.h"
#include "../scene/scene.h"

#include <algorithm>
#include <climits>

namespace mvpt {

MvViewStats &MvViewStats::operator+=(const MvViewStats &o) {
    native += o.native; received += o.received; tried += o.tried; sharing += o.sharing; rays += o.rays;
    for (int i = 0; i < int(ShiftTest::Count); ++i) rejected[i] += o.rejected[i];
    return *this;
}

void MvContext::prepare() {
    all_time_compatible = all_time_compatible_equal_dt = true;
    for (const MvView &a : views)
        for (const MvView &b : views) {
            all_time_compatible &= time_compatible(a, b, scene_moves);
            all_time_compatible_equal_dt &= a.dt == b.dt;
        }
    std::vector<CameraProjection> proj;
    static_shift = !scene_moves && all_time_compatible;
    for (const MvView &v : views) {
        const CameraProjection *p = v.camera->static_projection();
        static_shift &= p != nullptr;
        proj.push_back(p ? *p : CameraProjection{});
    }
    projections = ProjectionTable(proj);
}

namespace {
const BsdfContext Ctx;

/// Material similarity of candidates a and b, memoised in the |V| x |V| matrix `sm`.
float cached_similarity(const MvContext &ctx, MvScratch &sc, const Bsdf &bsdf, const SurfaceInteraction &si, size_t a,
                        size_t b) {
    if (a == b) return 1.f;
    size_t m = sc.cand.size();
    float &v = sc.sm[a * m + b];
    if (v < 0.f) v = sc.sm[b * m + a] = material_similarity(bsdf, si, sc.lobe[a], sc.lobe[b], ctx.cfg.tv, sc.alpha);
    return v;
}

/// Selection probability s_{j->k} of §6 between candidates j and k.
float selection(const MvContext &ctx, MvScratch &sc, const Bsdf &bsdf, const SurfaceInteraction &si, size_t j,
                size_t k) {
    if (j == k) return 1.f;
    float s = ctx.cfg.select_jacobian ? jacobian_similarity(sc.cand[j].geo.density, sc.cand[k].geo.density) : 1.f;
    if (s > 0.f && sc.material) s *= cached_similarity(ctx, sc, bsdf, si, j, k);
    return s;
}

/// The candidates of §3 for the native sample of view `slot_l` with first hit `y`: cand[0] is l
/// itself, then every view that passes the cheap tests, with its native count and lobe.
void gather_shifts(const MvContext &ctx, int slot_l, uint32_t pixel_l, const MvVertex &y, const Bsdf &bsdf,
                   const SurfaceInteraction &si, MvScratch &sc, MvViewStats *st_l) {
    const MvView &l = ctx.views[slot_l];
    auto &cand = sc.cand;
    cand.clear();
    ShiftCandidate self;
    self.slot = slot_l;
    self.pixel = pixel_l;
    self.time = y.time;
    const ShiftBatch &b = sc.batch;
    auto batch_geometry = [&](int k) {
        return ShiftGeometry{{b.film_x[k], b.film_y[k]}, {b.lens_x[k], b.lens_y[k], b.lens_z[k]}, b.density[k],
                             b.visible_length[k]};
    };
    bool self_ok;
    if (ctx.static_shift) { // every view's geometry at once (vectorised), no virtual call per view
        shift_geometry_batch(ctx.projections, y.p, y.n, y.lens, sc.batch);
        self.geo = batch_geometry(slot_l);
        self_ok = b.ok[slot_l];
    } else {
        self_ok = l.camera->shift_geometry(y.p, y.n, y.time, y.lens, &self.geo);
    }
    self_ok = self_ok && self.geo.density > 0.f;
    cand.push_back(self);
    if (self_ok) {
        const int nv = int(ctx.views.size());
        if (st_l) st_l->tried += uint64_t(nv - 1);
        ShiftCandidate c;
        for (int k = 0; k < nv; ++k) {
            if (k == slot_l) continue;
            ShiftTest test;
            if (ctx.static_shift) {
                float t_k = 0.f;
                shift_time(l, ctx.views[k], y.time, false, &t_k);
                test = accept_shift(ctx.views[k], k, y, t_k, b.ok[k], batch_geometry(k), &c);
            } else {
                test = shift_to_view(l, ctx.views[k], k, y, ctx.scene_moves, &c);
            }
            if (test != ShiftTest::Count) {
                if (st_l) ++st_l->rejected[int(test)];
                continue;
            }
            cand.push_back(c);
        }
    }
    const size_t m = cand.size();
    sc.lobe.resize(m);
    sc.n.resize(m);
    sc.s_sel.assign(m, 1.f);
    sc.visible.assign(m, 1);
    sc.selected.assign(m, 1);
    sc.alpha = bsdf.roughness(si);
    sc.material = ctx.cfg.select_material && (bsdf.flags() & BsdfGlossy);
    if (sc.material) sc.sm.assign(m * m, -1.f);
    for (size_t i = 0; i < m; ++i) {
        const ShiftCandidate &c = cand[i];
        sc.n[i] = float(ctx.native_map[c.slot][c.pixel]);
        Vec3f wi = i == 0 ? si.wi : si.to_local(normalize(c.geo.lens_point - si.p));
        sc.lobe[i] = sc.material ? view_lobe(bsdf, si, wi) : ViewLobe{wi, {}, 0.f};
    }
}

/// Visibility of y from every candidate's lens point (or only the selected ones), traced as
/// packets; fills sc.visible.
void trace_visibility(const MvContext &ctx, MvScratch &sc, const SurfaceInteraction &si, float t, bool selected_only,
                      RayCounters &counters, MvViewStats *st_l) {
    auto &rays = sc.rays;
    auto &ray_of = sc.ray_of;
    rays.clear();
    ray_of.clear();
    // Every candidate's lens point is on the native lens point's side of the surface (§3
    // orientation test), so all visibility rays leave from one offset origin.
    const Point3f o = si.offset_p(sc.cand[0].geo.lens_point - si.p);
    for (size_t i = 1; i < sc.cand.size(); ++i) {
        if (selected_only && !sc.selected[i]) {
            if (st_l) ++st_l->rejected[int(ShiftTest::Selection)];
            sc.visible[i] = 0;
            continue;
        }
        const ShiftCandidate &c = sc.cand[i];
        Vec3f d = c.geo.lens_point - o;
        float dist = norm(d);
        // Up to k's near clip plane: what is closer to the lens is invisible to its camera rays too.
        float len = c.geo.visible_length - (norm(c.geo.lens_point - si.p) - dist);
        if (!(len > 0.f)) continue; // y itself lies at the near plane: nothing can block
        rays.push_back(Ray{o, d / dist, 0.f, len * (1.f - ShadowEpsilon), t});
        ray_of.push_back(uint32_t(i));
    }
    auto &blocked = sc.blocked;
    blocked.assign(rays.size(), 0);
    if (!rays.empty()) ctx.scene->occluded(rays.data(), rays.size(), blocked.data(), true); // one origin: coherent
    counters.shadow_rays += rays.size();
    for (size_t r = 0; r < rays.size(); ++r) {
        uint32_t i = ray_of[r];
        sc.visible[i] = !blocked[r];
        if (!st_l) continue;
        if (!sc.visible[i]) ++st_l->rejected[int(ShiftTest::Visibility)];
        else if (!selected_only && !sc.selected[i]) ++st_l->rejected[int(ShiftTest::Selection)];
    }
}

/// D_k of §5 for the candidates `targets` (indices into sc.cand), into sc.d.
void balance_densities(const MvContext &ctx, MvScratch &sc, const Bsdf &bsdf, const SurfaceInteraction &si,
                       const std::vector<int> &targets) {
    const auto &cand = sc.cand;
    const size_t m = cand.size();
    //   D_k = sum_j n_j rho_{j->k},  rho_{j->k} = (dt_k/dt_j) (G_j/G_k) s_{j->k},  rho_{k->k} = 1,
    // over the strategies j whose shift to k is valid (visibility included).
    auto &valid_set = sc.valid_set;
    valid_set.clear();
    for (size_t j = 0; j < m; ++j)
        if (sc.visible[j]) valid_set.push_back(uint32_t(j));
    const bool material = sc.material;
    sc.d.assign(m, 0.f);
    const bool uniform_time = !ctx.scene_moves || ctx.all_time_compatible_equal_dt;
    if (!material && uniform_time && ctx.all_time_compatible) {
        // No pairwise terms: with r_j = G_j / G_k and s_{j->k} = min(1, r_j) (or 1),
        //   D_k = sum_j n_j r_j s_{j->k}   (j = k gives n_k),
        // summed in Lanes independent partial sums (vectorised; a fixed order, so deterministic).
        constexpr size_t Lanes = 8;
        const size_t nv = valid_set.size(), padded = (nv + Lanes - 1) / Lanes * Lanes;
        auto &g = sc.g_valid, &nn = sc.n_valid;
        g.assign(padded, 0.f); // padding: n = 0 adds nothing
        nn.assign(padded, 0.f);
        for (size_t i = 0; i < nv; ++i) {
            g[i] = cand[valid_set[i]].geo.density;
            nn[i] = sc.n[valid_set[i]];
        }
        const float *gp = g.data(), *np = nn.data();
        const bool jacobian = ctx.cfg.select_jacobian;
        for (int k : targets) {
            const float inv_gk = 1.f / cand[k].geo.density;
            float acc[Lanes] = {};
            if (jacobian) // r min(1, r) = min(r, r^2)
                for (size_t j0 = 0; j0 < padded; j0 += Lanes)
                    for (size_t q = 0; q < Lanes; ++q) {
                        float r = gp[j0 + q] * inv_gk;
                        acc[q] += np[j0 + q] * std::min(r, r * r);
                    }
            else
                for (size_t j0 = 0; j0 < padded; j0 += Lanes)
                    for (size_t q = 0; q < Lanes; ++q) acc[q] += np[j0 + q] * (gp[j0 + q] * inv_gk);
            float sum = 0.f;
            for (float a : acc) sum += a;
            sc.d[k] = sum;
        }
    } else {
        for (int k : targets) {
            const MvView &vk = ctx.views[cand[k].slot];
            const float inv_gk = 1.f / cand[k].geo.density;
            double sum = sc.n[k];
            for (uint32_t j : valid_set) {
                if (int(j) == k) continue;
                const MvView &vj = ctx.views[cand[j].slot];
                // Validity of j -> k is that of l -> j and l -> k except for time, which is not transitive.
                if (!ctx.all_time_compatible && !time_compatible(vj, vk, ctx.scene_moves)) continue;
                float ratio = cand[j].geo.density * inv_gk; // |T'_{k->j}| = G_j / G_k
                float s = ctx.cfg.select_jacobian ? std::min(1.f, ratio) : 1.f;
                if (material && s > 0.f) s *= cached_similarity(ctx, sc, bsdf, si, j, size_t(k));
                float tau = time_density_ratio(vk, vj, ctx.scene_moves);
                sum += double(sc.n[j]) * double(tau * ratio * s);
            }
            sc.d[k] = float(sum);
        }
    }
}

} // namespace

std::vector<std::pair<int, float>> mv_balance_densities(const MvContext &ctx, int slot, const SurfaceInteraction &hit,
                                                        Point3f lens_point, float time, Vec2f lens, MvScratch &sc) {
    const FilmDesc &film = ctx.views[slot].camera->film;
    SurfaceInteraction si = hit;
    si.wi = si.to_local(normalize(lens_point - si.p));
    ShiftGeometry geo;
    std::vector<std::pair<int, float>> out;
    if (!ctx.views[slot].camera->shift_geometry(si.p, si.n, time, lens, &geo) || !film.contains(geo.film)) return out;
    uint32_t pixel = uint32_t(int(geo.film.y) - film.crop_y) * uint32_t(film.crop_width) + uint32_t(int(geo.film.x) - film.crop_x);
    MvVertex y{si.p, si.n, time, lens, dot(si.n, lens_point - si.p)};
    const Bsdf &bsdf = *si.shape->bsdf;
    gather_shifts(ctx, slot, pixel, y, bsdf, si, sc, nullptr);
    RayCounters counters;
    trace_visibility(ctx, sc, si, time, false, counters, nullptr);
    std::vector<int> targets;
    for (size_t i = 0; i < sc.cand.size(); ++i)
        if (sc.visible[i]) targets.push_back(int(i));
    balance_densities(ctx, sc, bsdf, si, targets);
    for (int i : targets) out.emplace_back(sc.cand[i].slot, sc.d[i]);
    return out;
}

void mv_native_sample(const MvContext &ctx, int slot_l, int px, int py, uint32_t sample_index, MvScratch &sc,
                      MvSplatSink &sink, RayCounters &counters, MvViewStats *stats) {
    const Scene &scene = *ctx.scene;
    const PathConfig &pc = ctx.path->config();
    const uint32_t max_depth = pc.max_depth < 0 ? UINT_MAX : uint32_t(pc.max_depth);
    const MvView &l = ctx.views[slot_l];
    const Camera &cam = *l.camera;
    const FilmDesc &film = cam.film;
    const uint32_t pixel_l = uint32_t(py - film.crop_y) * uint32_t(film.crop_width) + uint32_t(px - film.crop_x);
    const float n_l = float(ctx.native_map[slot_l][pixel_l]);
    MvViewStats &st_l = stats[slot_l];
    const uint64_t rays_before = counters.rays + counters.shadow_rays;
    ++st_l.native;

    // ---------------- Native sample z_l = (t, x_l, xi) (§2) ----------------
    Sampler sampler(cam.sampler_kind, ctx.seeds[slot_l]);
    sampler.start(l.scene_index, uint32_t(px), uint32_t(py), sample_index);
    sampler.set_dimension(DimFilm);
    Vec2f u_film = sampler.next_2d();
    Vec2f u_lens = sampler.next_2d();
    float u_time = sampler.next_1d();
    // Box filter: x_l uniform in the pixel. xi is drawn for pinholes too: other views may have a lens.
    Vec2f film_pos(float(px) + u_film.x, float(py) + u_film.y);
    Vec2f xi = warp::square_to_uniform_disk_concentric(u_lens);
    float t = cam.sample_time(u_time);
    Ray ray = cam.generate_ray(film_pos, xi, t);
    ++counters.camera_rays;
    ++counters.rays;
    SurfaceInteraction si;
    bool hit = scene.intersect(ray, si);

    // Radiance only the native strategy produces goes to l's own pixel with the plain weight 1/n_l;
    // it still counts W = 1/n_l so that the weighted estimator's sum of W covers the whole pixel.
    auto native_only = [&](const Spectrum &L) {
        MvSplat own{slot_l, pixel_l, Spectrum(0.f), 1.f / n_l, L * (1.f / n_l), true};
        sink.splat(&own, 1);
        ++st_l.received;
        ++st_l.sharing;
        st_l.rays += counters.rays + counters.shadow_rays - rays_before;
    };
    const Light *env = scene.environment();
    if (!hit) {
        native_only(env && !pc.hide_emitters ? env->eval_environment(ray.d) : Spectrum(0.f));
        return;
    }
    const Bsdf &bsdf = *si.shape->bsdf;
    if (!bsdf.has_smooth() || max_depth <= 1 || ctx.views.size() < 2) {
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
    gather_shifts(ctx, slot_l, pixel_l, y, bsdf, si, sc, &st_l);
    const size_t m = sc.cand.size();
    auto &cand = sc.cand;
    for (size_t i = 1; i < m; ++i) {
        sc.s_sel[i] = selection(ctx, sc, bsdf, si, 0, i);
        if (sc.s_sel[i] >= 1.f) continue; // selected whatever the draw (u < 1)
        sampler.set_dimension(DimSelectBase + ctx.views[cand[i].slot].scene_index);
        sc.selected[i] = sampler.next_1d() < sc.s_sel[i];
    }
    // The balance estimator needs the visibility of every candidate (it enters D); the
    // published variant only that of the selected ones.
    trace_visibility(ctx, sc, si, t, ctx.cfg.mis_selected_only, counters, &st_l);
    // S: the views that shade the sample; V: the strategies in the sums D (§5).
    auto &sharing = sc.sharing;
    sharing.clear();
    for (size_t i = 0; i < m; ++i)
        if (sc.visible[i] && sc.selected[i]) sharing.push_back(int(i));
    const size_t ns = sharing.size();
    balance_densities(ctx, sc, bsdf, si, sharing);

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
    wis.resize(ns);
    for (size_t i = 0; i < ns; ++i) wis[i] = sc.lobe[sharing[i]].wi;
    const auto &lights = scene.lights();
    auto &f_nee = sc.nee_f;
    f_nee.resize(ns);
    Spectrum nee_weight(0.f); // light weight times MIS weight, zero when the light is not seen
    if (!lights.empty()) {
        size_t idx = std::min(size_t(u_light_select * float(lights.size())), lights.size() - 1);
        auto [ls, weight] = lights[idx]->sample_li(si.p, u_light, si.time);
        if (!weight.is_black()) {
            weight *= float(lights.size());
            Vec3f wo = si.to_local(ls.d);
            auto &pdf = sc.view_pdf;
            pdf.resize(ns);
            bsdf.eval_pdf_views(Ctx, si, wis.data(), ns, wo, f_nee.data(), pdf.data());
            bool any = false;
            float p_mix = 0.f; // the bounce's density: the lobe mixture (divided by |S| below)
            for (size_t i = 0; i < ns; ++i) {
                p_mix += pdf[i];
                any |= !f_nee[i].is_black();
            }
            if (any) {
                Ray shadow = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
                ++counters.shadow_rays;
                if (!scene.occluded(shadow))
                    nee_weight = weight * (ls.delta ? 1.f : mis_power(ls.pdf / float(lights.size()), p_mix / float(ns)));
            }
        }
    }
    const bool nee = !nee_weight.is_black();

    // ---------------- Shared bounce from the lobe mixture, one suffix (§7) ----------------
    sampler.set_dimension(DimBounceView);
    auto &fs = sc.mixture_f;
    fs.resize(ns);
    sc.view_pdf.resize(ns);
    MixtureSample mix =
        sample_lobe_mixture(bsdf, si, wis.data(), ns, sampler.next_1d(), u_lobe, u_dir, fs.data(), sc.view_pdf.data());
    const BsdfSample &bs = mix.bs;
    bool valid_after = valid || !(bs.sampled_type & BsdfNull);
    bool final_valid = valid_after;
    Spectrum suffix(0.f);
    float b_scale = 0.f; // b_i = fs[i] * b_scale (smooth), or mix.weight |S| b_scale for the delta view only
    if (!mix.weight.is_black() && mix.pdf > 0.f) {
        // A delta lobe's direction serves only the view that sampled it.
        float t_max = 0.f;
        if (mix.delta) {
            t_max = mix.weight.max_value() * float(ns);
        } else {
            for (size_t i = 0; i < ns; ++i) t_max = std::max(t_max, fs[i].max_value());
            t_max /= mix.pdf;
        }
        b_scale = mix.delta ? 1.f : 1.f / mix.pdf;
        bool alive = t_max > 0.f;
        if (alive && 1 >= pc.rr_depth) { // Russian roulette at y, as the path tracer does at depth 0
            float q = std::min(t_max * bs.eta * bs.eta, 0.95f);
            if (u_rr >= q) alive = false;
            else b_scale /= q;
        }
        if (alive) {
            PathState state;
            state.depth = 1;
            state.eta = bs.eta;
            state.prev_p = si.p;
            state.prev_bsdf_pdf = mix.pdf;
            state.prev_bsdf_delta = mix.delta;
            state.valid = valid_after;
            Ray next = si.spawn_ray(si.to_world(bs.wo));
            suffix = ctx.path->trace(scene, next, state, sampler, counters, nullptr, &final_valid);
        }
    }
    const bool bounce = !suffix.is_black();
    if (mix.delta) b_scale *= float(ns);

    // ---------------- Splat: L_i / D_i into each sharing view's pixel ----------------
    auto &splats = sc.splats;
    splats.resize(ns);
    for (size_t i = 0; i < ns; ++i) {
        int k = sharing[i];
        const ShiftCandidate &ck = cand[k];
        Spectrum L(0.f);
        if (nee) L = f_nee[i] * nee_weight;
        if (bounce && (!mix.delta || i == mix.view)) L += (mix.delta ? mix.weight : fs[i]) * b_scale * suffix;
        float w = 1.f / sc.d[k];
        MvSplat &s = splats[i];
        s.slot = ck.slot;
        s.pixel = ck.pixel;
        s.lw = final_valid ? L * w : Spectrum(0.f);
        s.w = w;
        s.has_e = k == 0;
        s.e = s.has_e ? le_y * (1.f / n_l) : Spectrum(0.f);
        ++stats[ck.slot].received;
    }
    sink.splat(splats.data(), ns);
    st_l.sharing += ns;
    st_l.rays += counters.rays + counters.shadow_rays - rays_before;
}

} // namespace mvpt
