// The path tracer of path.cpp as a wavefront: all paths of a batch (a render tile's
// camera rays) advance one vertex at a time, so that Embree traces their rays and shadow
// rays as 16-wide packets instead of one by one. The per-vertex arithmetic, the sample
// dimensions and the order in which contributions are summed are those of
// PathIntegrator::li, so each path's radiance is bit-identical to li's for the same hits
// (tests/cpp/test_path_batch.cpp checks this). trace_batch starts the paths from given
// states instead: multi-view path tracing's suffixes, bit-identical to `trace`.
#include "path.h"
#include "lane_gather.h"
#include "path_kernels.h"
#include "wavefront.h"

#include "../core/sampler_batch.h"
#include "../render/bsdf.h"
#include "../render/light.h"
#include "../render/shape.h"
#include "../render/texture.h"
#include "../scene/scene.h"

#include <climits>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace mvpt {

namespace {
/// One lane's emitter sample and weight L/pdf in the columns Ldx .. Ldx + 11 (direction,
/// point, distance, density, delta flag, weight), where the NEE kernels read them.
template <size_t Ldx>
inline void put_emitter_sample(float *col, size_t st, const LightSample &ls, const Spectrum &weight) {
    static_assert(ln_col::Wr == ln_col::Ldx + 9 && rn_col::Wr == rn_col::Ldx + 9, "emitter columns are contiguous");
    col[Ldx * st] = ls.d.x, col[(Ldx + 1) * st] = ls.d.y, col[(Ldx + 2) * st] = ls.d.z;
    col[(Ldx + 3) * st] = ls.p.x, col[(Ldx + 4) * st] = ls.p.y, col[(Ldx + 5) * st] = ls.p.z;
    col[(Ldx + 6) * st] = ls.dist, col[(Ldx + 7) * st] = ls.pdf, col[(Ldx + 8) * st] = ls.delta ? 1.f : 0.f;
    col[(Ldx + 9) * st] = weight.r, col[(Ldx + 10) * st] = weight.g, col[(Ldx + 11) * st] = weight.b;
}

/// One lane's shading frame (columns S0 .. S0 + 8), position and geometric normal (P0 .. P0 + 5)
/// and throughput (B0 .. B0 + 2), where the kernels' column blocks hold them.
template <size_t S0, size_t P0, size_t B0>
inline void put_vertex(float *col, size_t st, const SurfaceInteraction &si, const Spectrum &beta) {
    const Frame &f = si.sh_frame;
    const float v[9] = {f.s.x, f.s.y, f.s.z, f.t.x, f.t.y, f.t.z, f.n.x, f.n.y, f.n.z};
    for (size_t q = 0; q < 9; ++q) col[(S0 + q) * st] = v[q];
    col[P0 * st] = si.p.x, col[(P0 + 1) * st] = si.p.y, col[(P0 + 2) * st] = si.p.z;
    col[(P0 + 3) * st] = si.n.x, col[(P0 + 4) * st] = si.n.y, col[(P0 + 5) * st] = si.n.z;
    col[B0 * st] = beta.r, col[(B0 + 1) * st] = beta.g, col[(B0 + 2) * st] = beta.b;
}

/// The reflectance of a Lambertian vertex: its texture at the hit's uv (as DiffuseBsdf
/// evaluates it), or the constant.
inline Color3f lambert_reflectance(const LambertInfo &lam, const SurfaceInteraction &si) {
    return lam.texture ? lam.texture->eval(si.uv) : lam.reflectance;
}

/// Lanes per call of a Lambertian vector kernel: its columns (about 40 × 64 floats) stay in L1.
constexpr size_t LambertChunk = 64;
static_assert(LambertChunk % 16 == 0, "SoaColumns::resize(cols, LambertChunk) gives stride LambertChunk");

/// Lane m's columns of an emitter-sampling Lambertian kernel that gather_lambert_lanes leaves
/// out: whether the BSDF is two-sided and the chosen emitter's table row.
inline void put_lambert_lane(float *cols, size_t m, const LambertInfo &lam, int row) {
    cols[lam_col::TwoSided * LambertChunk + m] = lam.two_sided ? 1.f : 0.f;
    cols[lam_col::Emitter * LambertChunk + m] = float(row);
}

/// Per-thread buffers, reused across batches.
struct WaveBuffers {
    std::vector<WavePath> paths;
    /// The active paths' rays, in the order of `paths`.
    std::vector<Ray> rays;
    /// The vertex's shadow rays as columns (origin, direction, t_max, time), handed to Embree as they are.
    std::vector<float> shadow[8];
    std::vector<SurfaceInteraction> si;
    std::vector<uint8_t> hit, blocked, alive;
    std::vector<ScatterVertex> scatter;
    std::vector<PendingShadow> shadows;
    /// Per scattering vertex, its random numbers in li's order (u_light_select, u_light.x,
    /// u_light.y, u_lobe, u_dir.x, u_dir.y, u_rr) and, for independent samplers, the sample
    /// hash and first dimension they are drawn from.
    std::vector<float> u[7];
    std::vector<uint64_t> u_hash;
    std::vector<uint32_t> u_dim;
    /// Lambertian vertices: their columns for the vector kernels, and where each lane came from.
    SoaColumns lambert, quad, sphere;
    std::vector<uint32_t> lambert_index, quad_index, sphere_index;
    /// Their scattering vertices (gather_lambert_lanes reads the lanes' numbers and reflectance there).
    std::vector<uint32_t> lambert_vertex, quad_vertex, sphere_vertex;
    /// Constant rough conductor vertices, likewise (those sampling a sphere emitter apart).
    SoaColumns conductor, conductor_sphere;
    std::vector<uint32_t> conductor_index, conductor_sphere_index;
    /// Per light, its row in the QuadTable / SphereTable, or -1.
    std::vector<int> quad_of_light, sphere_of_light;
    /// The environment's batched lanes: escaped rays (path, origin, direction, emission,
    /// density), then NEE vertices (scatter index, point, numbers, time, sample, weight).
    std::vector<uint32_t> env_lane;
    std::vector<Point3f> env_ref;
    std::vector<Vec3f> env_d;
    std::vector<Spectrum> env_le, env_weight;
    std::vector<float> env_pdf, env_time;
    std::vector<Vec2f> env_u;
    std::vector<LightSample> env_ls;
};
} // namespace

void PathIntegrator::li_batch(const Scene &scene, const Ray *camera_rays, Sampler *samplers, Spectrum *out, size_t n,
                              RayCounters &counters, const Medium *) const {
    // Media are ignored, as by Mitsuba's `path` (Scene notes it).
    trace_batch(scene, camera_rays, nullptr, samplers, out, nullptr, n, counters);
}

void PathIntegrator::trace_batch(const Scene &scene, const Ray *start_rays, const PathState *states, Sampler *samplers,
                                 Spectrum *out, uint8_t *valid_out, size_t n, RayCounters &counters) const {
    const auto &lights = scene.lights();
    const uint32_t max_depth = m_cfg.max_depth < 0 ? UINT_MAX : uint32_t(m_cfg.max_depth);
    const BsdfContext ctx;
    const Light *const env = scene.environment();
    const bool valid0 = !m_cfg.hide_emitters && env != nullptr;

    // Through a pointer the compiler cannot see through (an empty asm): otherwise GCC recomputes
    // the thread_local's address, a __tls_get_addr call in a shared library, at every use.
    thread_local WaveBuffers tls_buffers;
    WaveBuffers *buf_ptr = &tls_buffers;
    asm("" : "+r"(buf_ptr));
    WaveBuffers &buf = *buf_ptr;
    // Raw pointers into the buffers (sized first): through a vector, GCC reloads the data
    // pointer after every byte store (a char may alias it).
    buf.paths.resize(n);
    WavePath *const paths = buf.paths.data();
    buf.rays.assign(start_rays, start_rays + n);
    bool independent = true; // then the vertices' numbers are drawn in one batched loop
    for (size_t i = 0; i < n; ++i) {
        paths[i] = WavePath{};
        paths[i].valid = valid0;
        if (states) { // trace's loop variables at the start
            const PathState &st = states[i];
            paths[i].throughput = st.throughput;
            paths[i].eta = st.eta;
            paths[i].prev_p = st.prev_p;
            paths[i].prev_bsdf_pdf = st.prev_bsdf_pdf;
            paths[i].prev_bsdf_delta = st.prev_bsdf_delta;
            paths[i].valid = st.valid;
            paths[i].depth = st.depth;
        }
        paths[i].slot = uint32_t(i);
        independent &= samplers[i].kind() == SamplerKind::Independent;
    }
    buf.si.resize(n);
    buf.hit.resize(n);
    buf.alive.resize(n);
    for (auto &c : buf.shadow) c.resize(n + 16); // append_shadow_rays stores whole 16-lane steps
    float *const shadow[8] = {buf.shadow[0].data(), buf.shadow[1].data(), buf.shadow[2].data(), buf.shadow[3].data(),
                              buf.shadow[4].data(), buf.shadow[5].data(), buf.shadow[6].data(), buf.shadow[7].data()};
    buf.blocked.resize(n);
    buf.scatter.resize(n);
    buf.shadows.resize(n + 16);
    SurfaceInteraction *const sis = buf.si.data();
    Ray *const rays = buf.rays.data();
    uint8_t *const hits = buf.hit.data(), *const alive = buf.alive.data(), *const blocked = buf.blocked.data();
    ScatterVertex *const scatter = buf.scatter.data();
    PendingShadow *const shadows = buf.shadows.data();
    for (auto &u : buf.u) u.resize(n);
    buf.u_hash.resize(n);
    buf.u_dim.resize(n);
    if (env) {
        buf.env_lane.resize(n);
        buf.env_ref.resize(n);
        buf.env_d.resize(n);
        buf.env_le.resize(n);
        buf.env_weight.resize(n);
        buf.env_pdf.resize(n);
        buf.env_time.resize(n);
        buf.env_u.resize(n);
        buf.env_ls.resize(n);
    }
    buf.lambert_index.resize(LambertChunk);
    buf.quad_index.resize(LambertChunk);
    buf.sphere_index.resize(LambertChunk);
    buf.lambert_vertex.resize(LambertChunk);
    buf.quad_vertex.resize(LambertChunk);
    buf.sphere_vertex.resize(LambertChunk);
    buf.conductor_index.resize(LambertChunk);
    buf.conductor_sphere_index.resize(LambertChunk);
    uint32_t *const lambert_index = buf.lambert_index.data(), *const quad_index = buf.quad_index.data(),
                   *const sphere_index = buf.sphere_index.data(), *const conductor_index = buf.conductor_index.data(),
                   *const conductor_sphere_index = buf.conductor_sphere_index.data();
    uint32_t *const lambert_vertex = buf.lambert_vertex.data(), *const quad_vertex = buf.quad_vertex.data(),
                   *const sphere_vertex = buf.sphere_vertex.data();
    // Quad emitters (constant-radiance parallelograms) for the vector kernel: their table row per light, or -1.
    QuadTable quads;
    std::vector<int> &quad_of_light = buf.quad_of_light;
    quad_of_light.assign(lights.size(), -1);
    for (size_t l = 0, nq = 0; l < lights.size() && nq < QuadTable::Max; ++l) {
        QuadEmitter q;
        if (!lights[l]->quad_emitter(q)) continue;
        const float row[QuadTable::Params] = {q.origin.x, q.origin.y, q.origin.z, q.e1.x, q.e1.y, q.e1.z, q.e2.x, q.e2.y,
                                              q.e2.z, q.n.x, q.n.y, q.n.z, q.inv_area, q.radiance.r, q.radiance.g,
                                              q.radiance.b};
        for (size_t r = 0; r < QuadTable::Params; ++r) quads.at(r, nq) = row[r];
        quad_of_light[l] = int(nq++);
    }
    // Sphere emitters of constant radiance, likewise.
    SphereTable spheres;
    float sphere_radius_adj2[SphereTable::Max]; // squared radius below which a point counts as inside
    std::vector<int> &sphere_of_light = buf.sphere_of_light;
    sphere_of_light.assign(lights.size(), -1);
    for (size_t l = 0, ns = 0; l < lights.size() && ns < SphereTable::Max; ++l) {
        SphereEmitter e;
        if (!lights[l]->sphere_emitter(e)) continue;
        const float row[SphereTable::Params] = {e.center.x, e.center.y, e.center.z, e.radius, e.flip_normals ? 1.f : 0.f,
                                                e.radiance.r, e.radiance.g, e.radiance.b};
        for (size_t r = 0; r < SphereTable::Params; ++r) spheres.at(r, ns) = row[r];
        float radius_adj = e.radius * (e.flip_normals ? (1.f + RayEpsilon) : (1.f - RayEpsilon));
        sphere_radius_adj2[ns] = radius_adj * radius_adj;
        sphere_of_light[l] = int(ns++);
    }
    // Loop invariants in locals: the loops' byte stores (flags) would make GCC reload them from memory.
    const size_t n_lights = lights.size();
    const float n_lights_f = float(n_lights);
    const int *const quad_row = quad_of_light.data(), *const sphere_row = sphere_of_light.data();
    // The parameter and frame columns shared by both rough conductor kernels (rs_col and rn_col agree up to Nz).
    static_assert(size_t(rs_col::Alpha) == size_t(rn_col::Alpha) && size_t(rs_col::SpB) == size_t(rn_col::SpB));
    auto gather_conductor = [](float *col, size_t st, const SurfaceInteraction &si, const RoughConductorInfo &rc) {
        using namespace rn_col;
        col[WiX * st] = si.wi.x, col[WiY * st] = si.wi.y, col[WiZ * st] = si.wi.z;
        col[TwoSided * st] = rc.two_sided ? 1.f : 0.f;
        col[Beckmann * st] = rc.beckmann ? 1.f : 0.f;
        col[Alpha * st] = rc.alpha;
        col[EtaR * st] = rc.eta.r, col[EtaG * st] = rc.eta.g, col[EtaB * st] = rc.eta.b;
        col[KR * st] = rc.k.r, col[KG * st] = rc.k.g, col[KB * st] = rc.k.b;
        col[SpR * st] = rc.specular.r, col[SpG * st] = rc.specular.g, col[SpB * st] = rc.specular.b;
    };
    // The vertex columns of rough_conductor_nee_kernel (also those of its sphere variant).
    auto gather_conductor_nee = [&](float *col, size_t st, const SurfaceInteraction &si, const RoughConductorInfo &rc,
                                    const Spectrum &beta) {
        gather_conductor(col, st, si, rc);
        put_vertex<rn_col::Sx, rn_col::Px, rn_col::Br>(col, st, si, beta);
    };
    float *const u[7] = {buf.u[0].data(), buf.u[1].data(), buf.u[2].data(), buf.u[3].data(),
                         buf.u[4].data(), buf.u[5].data(), buf.u[6].data()};
    // The vertex columns of rough_conductor_sample_kernel (cond_col: those of the NEE kernels
    // too) from scattering vertex j.
    auto gather_conductor_sample = [&, u](float *col, size_t st, const SurfaceInteraction &si,
                                       const RoughConductorInfo &rc, const WavePath &p, size_t j) {
        using namespace rs_col;
        gather_conductor_nee(col, st, si, rc, p.throughput);
        col[Ux * st] = u[4][j], col[Uy * st] = u[5][j];
        col[Eta * st] = p.eta, col[URr * st] = u[6][j];
        col[RrOn * st] = p.depth + 1 >= uint32_t(m_cfg.rr_depth) ? 1.f : 0.f;
    };
    // The paths of a sampling kernel's lanes take its next rays (columns from O0: origin,
    // direction, density, alive; throughput from B0). Lambertian and rough conductor samples
    // are never null lobes (the path becomes valid), have eta 1 and are not deltas.
    auto take_samples = [paths, sis, rays, alive](SoaColumns &cols, const uint32_t *index, size_t &count, auto o0,
                                                  auto b0) {
        constexpr size_t O0 = decltype(o0)::value, B0 = decltype(b0)::value;
        const float *const cd = cols.data.data(); // LambertChunk lanes per column
        // The captured pointers in locals: through the closure, GCC reloads them after every byte store.
        WavePath *const pa = paths;
        Ray *const ra = rays;
        const SurfaceInteraction *const si_of = sis;
        uint8_t *const al = alive;
        for (size_t m = 0; m < count; ++m) {
            auto at = [cd, m](size_t col) { return cd[col * LambertChunk + m]; };
            const uint32_t k = index[m];
            WavePath &p = pa[k];
            p.valid = true;
            if (!(at(O0 + 7) > 0.f)) continue;
            const SurfaceInteraction &si = si_of[k];
            ra[k] = Ray{{at(O0), at(O0 + 1), at(O0 + 2)}, {at(O0 + 3), at(O0 + 4), at(O0 + 5)}, 0.f, Infinity, si.time};
            p.throughput = Spectrum(at(B0), at(B0 + 1), at(B0 + 2));
            p.prev_p = si.p;
            p.prev_bsdf_pdf = at(O0 + 6);
            p.prev_bsdf_delta = false;
            ++p.depth;
            al[k] = 1;
        }
        count = 0;
    };

    // Each vertex runs as a few loops over all paths, one step of li's loop body each, so
    // that the paths' long dependency chains (square roots, divisions, virtual calls)
    // overlap; every path still sees li's operations in li's order.
    size_t active = n;
    for (bool first = true; active > 0; first = false) {
        // No reset of the interactions: a hit's fill_interaction sets every field that li reads
        // (Shape::fill_interaction's contract; wi is set below), and a miss's is never read.
        counters.rays += active;
        scene.intersect(rays, active, sis, hits, first && !states); // camera rays: coherent

        // ---------------- Emission (hit by BSDF sampling, MIS against NEE) ----------------
        // Escaped rays are evaluated after this loop, all at once (their densities wanted:
        // env_lane[0, n_env_mis); not wanted: env_lane[env_nomis, active)).
        size_t n_scatter = 0, n_env_mis = 0, env_nomis = active;
        std::fill(alive, alive + active, uint8_t(0)); // before the loop: a byte store in it makes GCC reload pointers
        for (size_t k = 0; k < active; ++k) {
            WavePath &p = paths[k];
            Sampler &sampler = samplers[p.slot];
            const SurfaceInteraction &si_hit = sis[k];
            const bool hit = hits[k] != 0;
            const Ray &ray = rays[k];
            sampler.set_dimension(DimCameraEnd + p.depth * DimsPerVertex);

            const Light *emitter = hit ? si_hit.shape->emitter.get() : scene.environment();
            if (emitter && !m_cfg.hide_emitters && hit) p.valid = true;
            if (emitter && !(p.depth == 0 && m_cfg.hide_emitters)) {
                if (!hit) {
                    const size_t e = p.prev_bsdf_delta ? --env_nomis : n_env_mis++;
                    buf.env_lane[e] = uint32_t(k);
                    buf.env_ref[e] = p.prev_p;
                    buf.env_d[e] = ray.d;
                    continue;
                }
                Spectrum le = emitter->eval(si_hit, -ray.d);
                if (!le.is_black()) {
                    float w = 1.f;
                    if (!p.prev_bsdf_delta)
                        w = mis_power(p.prev_bsdf_pdf, emitter_pdf(scene, emitter, p.prev_p, si_hit, ray.d));
                    p.result += p.throughput * le * w;
                }
            }
            if (!hit || p.depth + 1 >= max_depth) continue;

            SurfaceInteraction &si = sis[k];
            // The vertex's sample dimensions, in li's order (u_rr is unused when li stops earlier).
            const size_t j = n_scatter++;
            scatter[j].path = uint32_t(k);
            scatter[j].sampled = false;
            scatter[j].bsdf = si.shape->bsdf.get();
            // A Lambertian vertex's kernels read only wi's z, which their gather computes.
            if (const LambertInfo *lam = scatter[j].bsdf->lambert()) scatter[j].refl = lambert_reflectance(*lam, si);
            else si.wi = si.to_local(-ray.d);
            if (independent) {
                buf.u_hash[j] = sampler.sample_hash();
                buf.u_dim[j] = sampler.dimension();
                sampler.set_dimension(sampler.dimension() + DimsPerVertex);
            } else {
                u[0][j] = sampler.next_1d();
                Vec2f u_light = sampler.next_2d();
                u[1][j] = u_light.x, u[2][j] = u_light.y;
                u[3][j] = sampler.next_1d();
                Vec2f u_dir = sampler.next_2d();
                u[4][j] = u_dir.x, u[5][j] = u_dir.y;
                u[6][j] = sampler.next_1d();
            }
        }
        if (independent) independent_vertex_draws(buf.u_hash.data(), buf.u_dim.data(), n_scatter, u);
        if (n_env_mis > 0)
            env->eval_environment_batch(n_env_mis, buf.env_ref.data(), buf.env_d.data(), buf.env_le.data(),
                                        buf.env_pdf.data());
        if (env_nomis < active)
            env->eval_environment_batch(active - env_nomis, buf.env_ref.data() + env_nomis,
                                        buf.env_d.data() + env_nomis, buf.env_le.data() + env_nomis, nullptr);
        auto add_escaped = [&, paths](size_t e, bool mis) {
            WavePath &p = paths[buf.env_lane[e]];
            const Spectrum &le = buf.env_le[e];
            if (le.is_black()) return;
            const float w = mis ? mis_power(p.prev_bsdf_pdf, emitter_pdf_from(scene, env, buf.env_pdf[e])) : 1.f;
            p.result += p.throughput * le * w;
        };
        for (size_t e = 0; e < n_env_mis; ++e) add_escaped(e, true);
        for (size_t e = env_nomis; e < active; ++e) add_escaped(e, false);

        // ---------------- Next-event estimation: emitter samples ----------------
        // A Lambertian vertex that chose a quad emitter is done whole (emitter sample, BSDF,
        // MIS, shadow ray) by a vector kernel; the others sample their emitter here.
        size_t n_shadow = 0, n_quad = 0;
        int quad_one = -1; // the quad emitter that all of the chunk's lanes chose, or -1
        SoaColumns &qc = buf.quad;
        qc.resize(lq_col::Count, LambertChunk);
        size_t n_sph = 0;
        SoaColumns &sc = buf.sphere;
        sc.resize(lq_col::Count, LambertChunk);
        // The next-event estimates of a kernel's lanes (paths index[m]) wait for their shadow
        // rays (columns from O0: origin, direction, t_max, contribution, whether it counts).
        auto take_shadow_rays = [&n_shadow, shadow, shadows, sis](SoaColumns &cols, const uint32_t *index, size_t count,
                                                                  auto o0) {
            n_shadow = append_shadow_rays(cols.data.data(), LambertChunk, count, decltype(o0)::value, index, sis, shadow,
                                          shadows, n_shadow);
        };
        // Their lanes hold the whole vertex (lam_col): the BSDF is sampled right after NEE.
        const LaneSources lanes{sis, rays, paths, scatter, u, uint32_t(m_cfg.rr_depth)};
        auto flush_quad = [&] {
            if (n_quad == 0) return;
            gather_lambert_lanes(qc.data.data(), LambertChunk, n_quad, quad_index, quad_vertex, lanes, true);
            lambert_quad_nee_kernel(qc, n_quad, quads, n_lights_f, quad_one);
            take_shadow_rays(qc, quad_index, n_quad, std::integral_constant<size_t, lq_col::Ox>{});
            lambert_sample_kernel(qc, n_quad);
            take_samples(qc, quad_index, n_quad, std::integral_constant<size_t, ls_col::Ox>{},
                         std::integral_constant<size_t, ls_col::Br>{});
        };
        auto flush_sphere = [&] {
            if (n_sph == 0) return;
            gather_lambert_lanes(sc.data.data(), LambertChunk, n_sph, sphere_index, sphere_vertex, lanes, true);
            lambert_sphere_nee_kernel(sc, n_sph, spheres, n_lights_f);
            take_shadow_rays(sc, sphere_index, n_sph, std::integral_constant<size_t, lq_col::Ox>{});
            lambert_sample_kernel(sc, n_sph);
            take_samples(sc, sphere_index, n_sph, std::integral_constant<size_t, ls_col::Ox>{},
                         std::integral_constant<size_t, ls_col::Br>{});
        };
        // Rough conductor vertices that chose a sphere emitter seen from outside: a kernel too.
        size_t n_csph = 0;
        SoaColumns &csc = buf.conductor_sphere;
        csc.resize(cond_col::Count, LambertChunk);
        // Their lanes hold the whole vertex (cond_col): the BSDF is sampled right after NEE.
        auto flush_conductor_sphere = [&] {
            if (n_csph == 0) return;
            rough_conductor_sphere_nee_kernel(csc, n_csph, spheres, n_lights_f);
            take_shadow_rays(csc, conductor_sphere_index, n_csph, std::integral_constant<size_t, rn_col::Ox>{});
            rough_conductor_sample_kernel(csc, n_csph);
            take_samples(csc, conductor_sphere_index, n_csph, std::integral_constant<size_t, rs_col::Ox>{},
                         std::integral_constant<size_t, rs_col::Br>{});
        };
        // Whether p is outside sphere emitter `row` (Sphere::sample_solid_angle's test).
        auto outside_sphere = [&](int row, Point3f p) {
            Vec3f dc = Point3f(spheres.at(SphereTable::Cx, row), spheres.at(SphereTable::Cy, row),
                               spheres.at(SphereTable::Cz, row)) - p;
            return squared_norm(dc) > sphere_radius_adj2[row];
        };
        // Vertices that chose the environment sample it after this loop, all at once.
        size_t n_env = 0;
        // The kernels' columns (sized above), in locals: GCC would reload them after each byte store.
        float *const quad_cols = qc.data.data(), *const sphere_cols = sc.data.data(),
                    *const csph_cols = csc.data.data();
        for (size_t j = 0; j < n_scatter; ++j) {
            ScatterVertex &v = scatter[j];
            const SurfaceInteraction &si = sis[v.path];
            const Bsdf &bsdf = *v.bsdf;
            v.nee = bsdf.has_smooth() && n_lights != 0;
            if (!v.nee) continue;
            size_t idx = std::min(size_t(u[0][j] * n_lights_f), n_lights - 1);
            if (const LambertInfo *lam = bsdf.lambert()) {
                if (const int row = quad_row[idx]; row >= 0) {
                    quad_one = n_quad == 0 || quad_one == row ? row : -1;
                    put_lambert_lane(quad_cols, n_quad, *lam, row);
                    quad_index[n_quad] = v.path;
                    quad_vertex[n_quad++] = uint32_t(j);
                    v.nee = false; // handled by the kernel, BSDF sampling too
                    v.sampled = true;
                    if (n_quad == LambertChunk) flush_quad();
                    continue;
                }
                if (const int row = sphere_row[idx]; row >= 0 && outside_sphere(row, si.p)) {
                    put_lambert_lane(sphere_cols, n_sph, *lam, row);
                    sphere_index[n_sph] = v.path;
                    sphere_vertex[n_sph++] = uint32_t(j);
                    v.nee = false;
                    v.sampled = true;
                    if (n_sph == LambertChunk) flush_sphere();
                    continue;
                }
            } else if (const RoughConductorInfo *cond = bsdf.rough_conductor()) {
                if (const int row = sphere_row[idx]; row >= 0 && outside_sphere(row, si.p)) {
                    const size_t m = n_csph++;
                    conductor_sphere_index[m] = v.path;
                    float *col = csph_cols + m;
                    constexpr size_t st = LambertChunk;
                    gather_conductor_sample(col, st, si, *cond, paths[v.path], j);
                    col[rsn_col::Ux * st] = u[1][j], col[rsn_col::Uy * st] = u[2][j];
                    col[rsn_col::Sphere * st] = float(row);
                    v.nee = false; // handled by the kernel, BSDF sampling too
                    v.sampled = true;
                    if (n_csph == LambertChunk) flush_conductor_sphere();
                    continue;
                }
            }
            const Light &light = *lights[idx];
            if (&light == env) {
                const size_t m = n_env++;
                buf.env_lane[m] = uint32_t(j);
                buf.env_ref[m] = si.p;
                buf.env_u[m] = {u[1][j], u[2][j]};
                buf.env_time[m] = si.time;
                continue;
            }
            // Constructed in place (guaranteed copy elision): copying the returned pair with wide
            // loads right after the callee's narrow stores would stall on store forwarding.
            ::new (&v.emitter_sample) std::pair<LightSample, Spectrum>(light.sample_li(si.p, {u[1][j], u[2][j]}, si.time));
        }
        if (n_env > 0) {
            env->sample_li_batch(n_env, buf.env_ref.data(), buf.env_u.data(), buf.env_time.data(), buf.env_ls.data(),
                                 buf.env_weight.data());
            // Member by member: a pair temporary would be built on the stack with narrow stores
            // and copied out with wide loads across them (failed store-to-load forwards).
            for (size_t m = 0; m < n_env; ++m) {
                auto &[ls, weight] = scatter[buf.env_lane[m]].emitter_sample;
                ls = buf.env_ls[m];
                weight = buf.env_weight[m];
            }
        }
        flush_quad();
        flush_sphere();
        flush_conductor_sphere();

        // ---------------- Next-event estimation: BSDF and shadow rays (traced below) ----------------
        // Lambertian vertices go to a vector kernel (path_kernels.cpp), the others one by one.
        size_t n_lam = 0;
        SoaColumns &lc = buf.lambert;
        lc.resize(ln_col::Count, LambertChunk);
        auto flush_nee = [&] {
            if (n_lam == 0) return;
            gather_lambert_nee_lanes(lc.data.data(), LambertChunk, n_lam, lambert_index, lambert_vertex, lanes);
            lambert_nee_kernel(lc, n_lam, n_lights_f);
            take_shadow_rays(lc, lambert_index, n_lam, std::integral_constant<size_t, ln_col::Ox>{});
            n_lam = 0;
        };
        size_t n_rc = 0;
        SoaColumns &rc = buf.conductor;
        rc.resize(cond_col::Count, LambertChunk);
        auto flush_rc_nee = [&] {
            if (n_rc == 0) return;
            rough_conductor_nee_kernel(rc, n_rc, n_lights_f);
            take_shadow_rays(rc, conductor_index, n_rc, std::integral_constant<size_t, rn_col::Ox>{});
            n_rc = 0;
        };
        for (size_t j = 0; j < n_scatter; ++j) {
            ScatterVertex &v = scatter[j];
            if (!v.nee || v.emitter_sample.second.is_black()) continue;
            const SurfaceInteraction &si = sis[v.path];
            const Bsdf &bsdf = *v.bsdf;
            const LightSample &ls = v.emitter_sample.first;
            if (const LambertInfo *lam = bsdf.lambert()) {
                const size_t m = n_lam++;
                lambert_index[m] = v.path;
                lambert_vertex[m] = uint32_t(j);
                lc[ln_col::TwoSided][m] = lam->two_sided ? 1.f : 0.f;
                if (n_lam == LambertChunk) flush_nee();
                continue;
            }
            if (const RoughConductorInfo *cond = bsdf.rough_conductor()) {
                using namespace rn_col;
                const size_t m = n_rc++;
                conductor_index[m] = v.path;
                const Spectrum &beta = paths[v.path].throughput, &weight = v.emitter_sample.second;
                float *col = rc.data.data() + m;
                constexpr size_t st = LambertChunk;
                gather_conductor_nee(col, st, si, *cond, beta);
                put_emitter_sample<Ldx>(col, st, ls, weight);
                if (n_rc == LambertChunk) flush_rc_nee();
                continue;
            }
            Spectrum weight = v.emitter_sample.second;
            weight *= n_lights_f;
            Vec3f wo = si.to_local(ls.d);
            Spectrum f = bsdf.eval(ctx, si, si.wi, wo);
            if (!f.is_black()) {
                const Ray r = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
                const float ray_cols[8] = {r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z, r.tmax, r.time};
                for (size_t q = 0; q < 8; ++q) shadow[q][n_shadow] = ray_cols[q];
                float w = ls.delta ? 1.f : mis_power(ls.pdf / n_lights_f, bsdf.pdf(ctx, si, si.wi, wo));
                shadows[n_shadow++] = {v.path, paths[v.path].throughput * f * weight * w};
            }
        }
        flush_nee();
        flush_rc_nee();

        // ---------------- BSDF sampling and Russian roulette ----------------
        lc.resize(ls_col::Count, LambertChunk);
        auto flush_sample = [&] {
            if (n_lam == 0) return;
            gather_lambert_lanes(lc.data.data(), LambertChunk, n_lam, lambert_index, lambert_vertex, lanes, false);
            lambert_sample_kernel(lc, n_lam);
            take_samples(lc, lambert_index, n_lam, std::integral_constant<size_t, ls_col::Ox>{},
                         std::integral_constant<size_t, ls_col::Br>{});
        };
        auto flush_rc_sample = [&] {
            if (n_rc == 0) return;
            rough_conductor_sample_kernel(rc, n_rc);
            take_samples(rc, conductor_index, n_rc, std::integral_constant<size_t, rs_col::Ox>{},
                         std::integral_constant<size_t, rs_col::Br>{});
        };
        for (size_t j = 0; j < n_scatter; ++j) {
            const ScatterVertex &v = scatter[j];
            if (v.sampled) continue;
            const size_t k = v.path;
            WavePath &p = paths[k];
            const SurfaceInteraction &si = sis[k];
            const Bsdf &bsdf = *v.bsdf;
            if (const LambertInfo *lam = bsdf.lambert()) {
                const size_t m = n_lam++;
                lambert_index[m] = uint32_t(k);
                lambert_vertex[m] = uint32_t(j);
                lc[ls_col::TwoSided][m] = lam->two_sided ? 1.f : 0.f;
                if (n_lam == LambertChunk) flush_sample();
                continue;
            }
            if (const RoughConductorInfo *cond = bsdf.rough_conductor()) {
                const size_t m = n_rc++;
                conductor_index[m] = uint32_t(k);
                gather_conductor_sample(rc.data.data() + m, LambertChunk, si, *cond, p, j);
                if (n_rc == LambertChunk) flush_rc_sample();
                continue;
            }
            auto [bs, bsdf_weight] = bsdf.sample(ctx, si, si.wi, u[3][j], {u[4][j], u[5][j]});
            if (!(bs.sampled_type & BsdfNull)) p.valid = true;
            if (bsdf_weight.is_black()) continue;
            Vec3f wo_world = si.to_world(bs.wo);
            rays[k] = si.spawn_ray(wo_world);
            p.throughput *= bsdf_weight;
            p.eta *= bs.eta;
            p.prev_p = si.p;
            p.prev_bsdf_pdf = bs.pdf;
            p.prev_bsdf_delta = (bs.sampled_type & BsdfDelta) != 0;

            float t_max = p.throughput.max_value();
            if (!(t_max > 0.f)) continue;
            if (p.depth + 1 >= uint32_t(m_cfg.rr_depth)) {
                float q = std::min(t_max * p.eta * p.eta, 0.95f);
                if (u[6][j] >= q) continue;
                p.throughput *= 1.f / q;
            }
            ++p.depth;
            alive[k] = 1;
        }
        flush_sample();
        flush_rc_sample();

        // ---------------- Shadow rays of this vertex ----------------
        counters.shadow_rays += n_shadow;
        scene.occluded(RayColumns{shadow[0], shadow[1], shadow[2], shadow[3], shadow[4], shadow[5], shadow[6], shadow[7]},
                       n_shadow, blocked);
        for (size_t j = 0; j < n_shadow; ++j)
            if (!blocked[j]) paths[shadows[j].path].result += shadows[j].contribution;

        // Finished paths leave; the others move to the front (their order is kept).
        size_t next = 0;
        for (size_t k = 0; k < active; ++k) {
            if (alive[k]) {
                if (next != k) {
                    paths[next] = paths[k];
                    rays[next] = rays[k];
                }
                ++next;
            } else {
                out[paths[k].slot] = paths[k].valid ? paths[k].result : Spectrum(0.f);
                if (valid_out) valid_out[paths[k].slot] = paths[k].valid;
            }
        }
        active = next;
    }
}

} // namespace mvpt
