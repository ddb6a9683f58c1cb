// The path tracer of path.cpp as a wavefront: all paths of a batch (a render tile's
// camera rays) advance one vertex at a time, so that Embree traces their rays and shadow
// rays as 16-wide packets instead of one by one. The per-vertex arithmetic, the sample
// dimensions and the order in which contributions are summed are those of
// PathIntegrator::li, so each path's radiance is bit-identical to li's for the same hits
// (tests/cpp/test_path_batch.cpp checks this). trace_batch starts the paths from given
// states instead: multi-view path tracing's suffixes, bit-identical to `trace`.
#include "path.h"
#include "../../render/shapes/sphere_cone.h"
#include "lane_gather.h"
#include "path_kernels.h"
#include "path_steps.h"
#include "wavefront.h"

#include "../../core/per_thread.h"
#include "../../core/sampler_batch.h"
#include "../../render/bsdf.h"
#include "../../render/bsdfs/bsdf_form.h"
#include "../../render/light.h"
#include "../../render/lights/area.h"
#include "../../render/shape.h"
#include "../../render/texture.h"
#include "../../accel/scene.h"

#include <array>
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

/// The reflectance of a Lambertian vertex: its texture at the hit (as DiffuseBsdf
/// evaluates it), or the constant.
inline Color3f lambert_reflectance(const LambertInfo &lam, const SurfaceInteraction &si) {
    return lam.texture ? lam.texture->eval(si) : lam.reflectance;
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

/// The forms (bsdf_form) of the BSDFs met at one vertex of a batch, each found once: a
/// direct-mapped table by BSDF address in front of the forms found (the casts that find a form
/// cost more than the kernels save, if made at every vertex).
class BsdfForms {
public:
    /// Empties the table, with room for n forms (their addresses stay fixed until the next reset).
    void reset(size_t n) {
        m_slots.fill(Slot{});
        m_forms.clear();
        m_forms.reserve(n);
    }
    const BsdfForm *find(const Bsdf *bsdf) {
        Slot &s = m_slots[(uint64_t(uintptr_t(bsdf)) * 0x9E3779B97F4A7C15ull) >> (64 - SlotBits)];
        if (s.bsdf != bsdf) s = {bsdf, &m_forms.emplace_back(bsdf_form(*bsdf))};
        return s.form;
    }

private:
    static constexpr int SlotBits = 6;
    struct Slot {
        const Bsdf *bsdf = nullptr;
        const BsdfForm *form = nullptr;
    };
    std::array<Slot, size_t(1) << SlotBits> m_slots;
    std::vector<BsdfForm> m_forms;
};

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
    BsdfForms forms;
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

    /// Every buffer sized for a batch of n paths (the environment's lanes only when `env`).
    void size_for(size_t n, bool env) {
        paths.resize(n);
        si.resize(n);
        hit.resize(n);
        alive.resize(n);
        for (auto &c : shadow) c.resize(n + 16); // append_shadow_rays stores whole 16-lane steps
        blocked.resize(n);
        scatter.resize(n);
        shadows.resize(n);
        for (auto &c : u) c.resize(n);
        u_hash.resize(n);
        u_dim.resize(n);
        if (env) {
            for (auto *v : {&env_pdf, &env_time}) v->resize(n);
            for (auto *v : {&env_le, &env_weight}) v->resize(n);
            env_lane.resize(n), env_ref.resize(n), env_d.resize(n), env_u.resize(n), env_ls.resize(n);
        }
        for (auto *v : {&lambert_index, &quad_index, &sphere_index, &lambert_vertex, &quad_vertex, &sphere_vertex,
                        &conductor_index, &conductor_sphere_index})
            v->resize(LambertChunk);
    }
};

/// The scene's quad and sphere emitters of constant radiance as the vector kernels' tables.
struct EmitterTables {
    QuadTable quads;
    SphereTable spheres;
    /// Per sphere, the squared radius below which a point counts as inside.
    float sphere_radius_adj2[SphereTable::Max];
    /// Per light, its row in `quads` / `spheres`, or -1 (WaveBuffers' quad_of_light, sphere_of_light).
    const int *quad_row = nullptr, *sphere_row = nullptr;

    void build(const std::vector<std::shared_ptr<Light>> &lights, WaveBuffers &buf) {
        buf.quad_of_light.assign(lights.size(), -1);
        for (size_t l = 0, nq = 0; l < lights.size() && nq < QuadTable::Max; ++l) {
            const std::optional<QuadEmitter> quad = quad_emitter(*lights[l]);
            if (!quad) continue;
            const QuadEmitter &q = *quad;
            const float row[QuadTable::Params] = {q.origin.x, q.origin.y, q.origin.z, q.e1.x, q.e1.y, q.e1.z,
                                                  q.e2.x, q.e2.y, q.e2.z, q.n.x, q.n.y, q.n.z, q.inv_area,
                                                  q.radiance.r, q.radiance.g, q.radiance.b};
            for (size_t r = 0; r < QuadTable::Params; ++r) quads.at(r, nq) = row[r];
            buf.quad_of_light[l] = int(nq++);
        }
        buf.sphere_of_light.assign(lights.size(), -1);
        for (size_t l = 0, ns = 0; l < lights.size() && ns < SphereTable::Max; ++l) {
            const std::optional<SphereEmitter> sphere = sphere_emitter(*lights[l]);
            if (!sphere) continue;
            const SphereEmitter &e = *sphere;
            const float row[SphereTable::Params] = {e.center.x, e.center.y, e.center.z, e.radius,
                                                    e.flip_normals ? 1.f : 0.f, e.radiance.r, e.radiance.g,
                                                    e.radiance.b};
            for (size_t r = 0; r < SphereTable::Params; ++r) spheres.at(r, ns) = row[r];
            float radius_adj = cone_test_radius(e.radius, e.flip_normals);
            sphere_radius_adj2[ns] = radius_adj * radius_adj;
            buf.sphere_of_light[l] = int(ns++);
        }
        quad_row = buf.quad_of_light.data(), sphere_row = buf.sphere_of_light.data();
    }

    /// Whether p is outside sphere emitter `row` (Sphere::sample_solid_angle's test).
    bool outside_sphere(int row, Point3f p) const {
        const size_t r = size_t(row);
        const Vec3f dc = Point3f(spheres.at(SphereTable::Cx, r), spheres.at(SphereTable::Cy, r), spheres.at(SphereTable::Cz, r)) - p;
        return squared_norm(dc) > sphere_radius_adj2[row];
    }
};

// The parameter and frame columns shared by both rough conductor kernels (rs_col and rn_col agree up to Nz).
static_assert(size_t(rs_col::Alpha) == size_t(rn_col::Alpha) && size_t(rs_col::SpB) == size_t(rn_col::SpB));

/// The vertex columns of rough_conductor_nee_kernel (also those of its sphere variant).
inline void gather_conductor_nee(float *col, size_t st, const SurfaceInteraction &si, const RoughConductorInfo &rc,
                                 const Spectrum &beta) {
    using namespace rn_col;
    col[WiX * st] = si.wi.x, col[WiY * st] = si.wi.y, col[WiZ * st] = si.wi.z;
    col[TwoSided * st] = rc.two_sided ? 1.f : 0.f;
    col[Beckmann * st] = rc.beckmann ? 1.f : 0.f;
    col[Alpha * st] = rc.alpha;
    col[EtaR * st] = rc.eta.r, col[EtaG * st] = rc.eta.g, col[EtaB * st] = rc.eta.b;
    col[KR * st] = rc.k.r, col[KG * st] = rc.k.g, col[KB * st] = rc.k.b;
    col[SpR * st] = rc.specular.r, col[SpG * st] = rc.specular.g, col[SpB * st] = rc.specular.b;
    put_vertex<rn_col::Sx, rn_col::Px, rn_col::Br>(col, st, si, beta);
}

/// One batch of paths advancing a vertex at a time (PathIntegrator::trace_batch). Each stage
/// of a vertex is one step of li's loop body as a loop over the active paths, so that the
/// paths' long dependency chains (square roots, divisions, virtual calls) overlap; every path
/// still sees li's operations in li's order. Lambertian and constant rough conductor vertices
/// go to vector kernels (path_kernels*.cpp) in chunks of LambertChunk lanes, the others one by one.
class Wavefront {
public:
    Wavefront(const Scene &scene, const PathConfig &cfg, Sampler *samplers, WaveBuffers &buf, RayCounters &counters)
        : m_scene(scene), m_cfg(cfg), m_samplers(samplers), m_buf(buf), m_counters(counters),
          m_env(scene.environment()), m_lights(scene.lights().size()), m_lights_f(float(m_lights)),
          m_max_depth(cfg.max_depth < 0 ? UINT_MAX : uint32_t(cfg.max_depth)) {}

    /// Paths along rays[0..n) continuing from states[i] (null: li's start, camera rays), run to
    /// their ends: path i's radiance into out[i], its valid-path flag into valid_out[i] if given.
    void run(const Ray *rays, const PathState *states, size_t n, Spectrum *out, uint8_t *valid_out) {
        start(rays, states, n);
        size_t active = n;
        for (bool first = true; active > 0; first = false) {
            // No reset of the interactions: a hit's fill_interaction sets every field that li
            // reads (Shape::fill_interaction's contract; wi is set by emission), and a miss's is never read.
            m_counters.rays += active;
            m_scene.intersect(m_buf.rays.data(), active, m_buf.si.data(), m_buf.hit.data(), first && !states);
            const size_t n_scatter = emission(active);
            escaped(active);
            m_n_shadow = 0;
            sample_emitters(n_scatter);
            emitter_nee(n_scatter);
            sample_bsdfs(n_scatter);
            trace_shadow_rays();
            active = compact(active, out, valid_out);
        }
    }

private:
    void start(const Ray *rays, const PathState *states, size_t n);
    size_t emission(size_t active);
    void escaped(size_t active);
    void sample_emitters(size_t n_scatter);
    bool emitter_kernel_lane(size_t j, size_t light);
    void emitter_nee(size_t n_scatter);
    void sample_bsdfs(size_t n_scatter);
    void trace_shadow_rays();
    size_t compact(size_t active, Spectrum *out, uint8_t *valid_out);

    void flush_quad(size_t &n, int quad_one);
    void flush_sphere(size_t &n);
    void flush_conductor_sphere(size_t &n);
    void flush_lambert_nee(size_t &n);
    void flush_conductor_nee(size_t &n);
    void flush_lambert_samples(size_t &n);
    void flush_conductor_samples(size_t &n);
    template <size_t O0> void take_shadow_rays(SoaColumns &cols, const uint32_t *index, size_t count);
    template <size_t O0, size_t B0> void take_samples(SoaColumns &cols, const uint32_t *index, size_t &count);
    void gather_conductor_sample(float *col, const RoughConductorInfo &rc, uint32_t path, size_t j) const;
    /// The records the Lambertian kernels' lanes are gathered from.
    LaneSources lanes() const {
        return {m_buf.si.data(), m_buf.rays.data(), m_buf.paths.data(), m_buf.scatter.data(), m_u.data(),
                uint32_t(m_cfg.rr_depth)};
    }

    const Scene &m_scene;
    const PathConfig &m_cfg;
    Sampler *const m_samplers;
    WaveBuffers &m_buf;
    RayCounters &m_counters;
    const Light *const m_env;
    const size_t m_lights;
    const float m_lights_f;
    const uint32_t m_max_depth;
    const BsdfContext m_ctx;
    EmitterTables m_tables;
    /// Whether every sampler is independent: the vertices' numbers are then drawn in one batched loop.
    bool m_independent = true;
    /// The columns of m_buf.u and m_buf.shadow.
    std::array<float *, 7> m_u{};
    std::array<float *, 8> m_shadow{};
    /// Escaped rays whose emission wants its MIS density: env_lane[0, m_env_mis); the others
    /// (after a delta lobe or hidden camera rays): env_lane[m_env_nomis, active).
    size_t m_env_mis = 0, m_env_nomis = 0;
    /// Shadow rays of the current vertex.
    size_t m_n_shadow = 0;
    /// Lanes in the chunks of the whole-vertex kernels (sample_emitters), and the quad that all
    /// of the quad kernel's lanes chose (or -1).
    size_t m_n_quad = 0, m_n_sphere = 0, m_n_conductor_sphere = 0;
    int m_quad_one = -1;
};

void Wavefront::start(const Ray *rays, const PathState *states, size_t n) {
    m_buf.size_for(n, m_env != nullptr);
    m_buf.rays.assign(rays, rays + n);
    const bool valid0 = !m_cfg.hide_emitters && m_env != nullptr;
    WavePath *const paths = m_buf.paths.data();
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
        m_independent &= m_samplers[i].kind() == SamplerKind::Independent;
    }
    for (size_t q = 0; q < 7; ++q) m_u[q] = m_buf.u[q].data();
    for (size_t q = 0; q < 8; ++q) m_shadow[q] = m_buf.shadow[q].data();
    m_tables.build(m_scene.lights(), m_buf);
}

namespace {

/// Scattering vertex j's sample dimensions, in li's order (u_rr is unused when li stops
/// earlier): drawn now into the columns `u`, or, from an independent sampler, their hash and
/// first dimension kept for independent_vertex_draws.
inline void vertex_draws(Sampler &sampler, size_t j, bool independent, const std::array<float *, 7> &u,
                         WaveBuffers &buf) {
    if (independent) {
        buf.u_hash[j] = sampler.sample_hash();
        buf.u_dim[j] = sampler.dimension();
        sampler.set_dimension(sampler.dimension() + DimsPerVertex);
        return;
    }
    u[0][j] = sampler.next_1d();
    Vec2f u_light = sampler.next_2d();
    u[1][j] = u_light.x, u[2][j] = u_light.y;
    u[3][j] = sampler.next_1d();
    Vec2f u_dir = sampler.next_2d();
    u[4][j] = u_dir.x, u[5][j] = u_dir.y;
    u[6][j] = sampler.next_1d();
}

} // namespace

size_t Wavefront::emission(size_t active) {
    // Raw pointers in locals: through the buffers or `this`, GCC reloads them after every byte store.
    WavePath *const paths = m_buf.paths.data();
    SurfaceInteraction *const sis = m_buf.si.data();
    const Ray *const rays = m_buf.rays.data();
    const uint8_t *const hits = m_buf.hit.data();
    ScatterVertex *const scatter = m_buf.scatter.data();
    const std::array<float *, 7> u = m_u;
    const bool independent = m_independent;
    WaveBuffers &buf = m_buf;
    // Escaped rays are evaluated afterwards, all at once (`escaped`).
    size_t n_scatter = 0, n_env_mis = 0, env_nomis = active;
    std::fill(buf.alive.data(), buf.alive.data() + active, uint8_t(0)); // before the loop: see above
    buf.forms.reset(active);
    for (size_t k = 0; k < active; ++k) {
        WavePath &p = paths[k];
        Sampler &sampler = m_samplers[p.slot];
        const SurfaceInteraction &si_hit = sis[k];
        const bool hit = hits[k] != 0;
        const Ray &ray = rays[k];
        sampler.set_dimension(DimCameraEnd + p.depth * DimsPerVertex);

        // Emission, hit by BSDF sampling: MIS against next-event estimation.
        const Light *emitter = hit ? si_hit.shape->emitter.get() : m_env;
        if (emitter && !m_cfg.hide_emitters && hit) p.valid = true;
        if (emitter && !(p.depth == 0 && m_cfg.hide_emitters)) {
            if (!hit) {
                const size_t e = p.prev_bsdf_delta ? --env_nomis : n_env_mis++;
                buf.env_lane[e] = uint32_t(k);
                buf.env_ref[e] = p.prev_p;
                buf.env_d[e] = ray.d;
                continue;
            }
            float w;
            const Spectrum le = emitted_radiance(m_scene, emitter, ray, true, si_hit, p.prev_p, p.prev_bsdf_pdf,
                                                 p.prev_bsdf_delta, w);
            if (!le.is_black()) p.result += p.throughput * le * w;
        }
        if (!hit || p.depth + 1 >= m_max_depth) continue;

        SurfaceInteraction &si = sis[k];
        const size_t j = n_scatter++;
        scatter[j].path = uint32_t(k);
        scatter[j].sampled = false;
        scatter[j].bsdf = si.shape->bsdf.get();
        const BsdfForm *form = scatter[j].form = buf.forms.find(scatter[j].bsdf);
        // A Lambertian vertex's kernels read only wi's z, which their gather computes.
        if (form->kind == BsdfForm::Lambert) scatter[j].refl = lambert_reflectance(form->lambert, si);
        else si.wi = si.to_local(-ray.d);
        vertex_draws(sampler, j, independent, u, buf);
    }
    if (independent) independent_vertex_draws(buf.u_hash.data(), buf.u_dim.data(), n_scatter, u.data());
    m_env_mis = n_env_mis, m_env_nomis = env_nomis;
    return n_scatter;
}

void Wavefront::escaped(size_t active) {
    WaveBuffers &buf = m_buf;
    const size_t n_mis = m_env_mis, nomis = m_env_nomis;
    if (n_mis > 0)
        m_env->eval_environment_batch(n_mis, buf.env_ref.data(), buf.env_d.data(), buf.env_le.data(), buf.env_pdf.data());
    if (nomis < active)
        m_env->eval_environment_batch(active - nomis, buf.env_ref.data() + nomis, buf.env_d.data() + nomis,
                                      buf.env_le.data() + nomis, nullptr);
    auto add_escaped = [&](size_t e, bool mis) {
        WavePath &p = buf.paths[buf.env_lane[e]];
        const Spectrum &le = buf.env_le[e];
        if (le.is_black()) return;
        const float w = mis ? mis_power(p.prev_bsdf_pdf, emitter_pdf_from(m_scene, m_env, buf.env_pdf[e])) : 1.f;
        p.result += p.throughput * le * w;
    };
    for (size_t e = 0; e < n_mis; ++e) add_escaped(e, true);
    for (size_t e = nomis; e < active; ++e) add_escaped(e, false);
}

/// The next-event estimates of a kernel's lanes (paths index[m]) wait for their shadow rays
/// (columns from O0: origin, direction, t_max, contribution, whether it counts).
template <size_t O0> void Wavefront::take_shadow_rays(SoaColumns &cols, const uint32_t *index, size_t count) {
    m_n_shadow = append_shadow_rays(cols.data.data(), LambertChunk, count, O0, index, m_buf.si.data(), m_shadow.data(),
                                    m_buf.shadows.data(), m_n_shadow);
}

/// The paths of a sampling kernel's lanes take its next rays (columns from O0: origin,
/// direction, density, alive; throughput from B0). Lambertian and rough conductor samples are
/// never null lobes (the path becomes valid), have eta 1 and are not deltas.
template <size_t O0, size_t B0> void Wavefront::take_samples(SoaColumns &cols, const uint32_t *index, size_t &count) {
    const float *const cd = cols.data.data(); // LambertChunk lanes per column
    WavePath *const pa = m_buf.paths.data();
    Ray *const ra = m_buf.rays.data();
    const SurfaceInteraction *const si_of = m_buf.si.data();
    uint8_t *const al = m_buf.alive.data();
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
}

/// The vertex columns of rough_conductor_sample_kernel (cond_col: those of the NEE kernels too)
/// of path `path` at scattering vertex j, into lane `col` (stride LambertChunk).
void Wavefront::gather_conductor_sample(float *col, const RoughConductorInfo &rc, uint32_t path, size_t j) const {
    using namespace rs_col;
    constexpr size_t st = LambertChunk;
    const WavePath &p = m_buf.paths[path];
    gather_conductor_nee(col, st, m_buf.si[path], rc, p.throughput);
    col[Ux * st] = m_u[4][j], col[Uy * st] = m_u[5][j];
    col[Eta * st] = p.eta, col[URr * st] = m_u[6][j];
    col[RrOn * st] = p.depth + 1 >= uint32_t(m_cfg.rr_depth) ? 1.f : 0.f;
}

// Kernels that take a whole vertex (emitter sample, BSDF, MIS, shadow ray, then the BSDF sample).
void Wavefront::flush_quad(size_t &n, int quad_one) {
    if (n == 0) return;
    SoaColumns &qc = m_buf.quad;
    gather_lambert_lanes(qc.data.data(), LambertChunk, n, m_buf.quad_index.data(), m_buf.quad_vertex.data(), lanes(),
                         true);
    lambert_quad_nee_kernel(qc, n, m_tables.quads, m_lights_f, quad_one);
    take_shadow_rays<lq_col::Ox>(qc, m_buf.quad_index.data(), n);
    lambert_sample_kernel(qc, n);
    take_samples<ls_col::Ox, ls_col::Br>(qc, m_buf.quad_index.data(), n);
}

void Wavefront::flush_sphere(size_t &n) {
    if (n == 0) return;
    SoaColumns &sc = m_buf.sphere;
    gather_lambert_lanes(sc.data.data(), LambertChunk, n, m_buf.sphere_index.data(), m_buf.sphere_vertex.data(),
                         lanes(), true);
    lambert_sphere_nee_kernel(sc, n, m_tables.spheres, m_lights_f);
    take_shadow_rays<lq_col::Ox>(sc, m_buf.sphere_index.data(), n);
    lambert_sample_kernel(sc, n);
    take_samples<ls_col::Ox, ls_col::Br>(sc, m_buf.sphere_index.data(), n);
}

void Wavefront::flush_conductor_sphere(size_t &n) {
    if (n == 0) return;
    SoaColumns &csc = m_buf.conductor_sphere;
    rough_conductor_sphere_nee_kernel(csc, n, m_tables.spheres, m_lights_f);
    take_shadow_rays<rn_col::Ox>(csc, m_buf.conductor_sphere_index.data(), n);
    rough_conductor_sample_kernel(csc, n);
    take_samples<rs_col::Ox, rs_col::Br>(csc, m_buf.conductor_sphere_index.data(), n);
}

/// Scattering vertex j, whose BSDF and chosen emitter (the scene's `light`) a whole-vertex
/// kernel handles, into that kernel's chunk (true); false leaves it to the scalar emitter sampling.
bool Wavefront::emitter_kernel_lane(size_t j, size_t light) {
    ScatterVertex &v = m_buf.scatter[j];
    const Point3f p = m_buf.si[v.path].p;
    const int quad = m_tables.quad_row[light], sphere = m_tables.sphere_row[light];
    if (v.form->kind == BsdfForm::Lambert) {
        const LambertInfo &lam = v.form->lambert;
        if (quad >= 0) {
            m_quad_one = m_n_quad == 0 || m_quad_one == quad ? quad : -1;
            put_lambert_lane(m_buf.quad.data.data(), m_n_quad, lam, quad);
            m_buf.quad_index[m_n_quad] = v.path;
            m_buf.quad_vertex[m_n_quad++] = uint32_t(j);
            if (m_n_quad == LambertChunk) flush_quad(m_n_quad, m_quad_one);
            return true;
        }
        if (sphere < 0 || !m_tables.outside_sphere(sphere, p)) return false;
        size_t &n = m_n_sphere;
        put_lambert_lane(m_buf.sphere.data.data(), n, lam, sphere);
        m_buf.sphere_index[n] = v.path;
        m_buf.sphere_vertex[n++] = uint32_t(j);
        if (n == LambertChunk) flush_sphere(n);
        return true;
    }
    if (v.form->kind != BsdfForm::RoughConductor || sphere < 0 || !m_tables.outside_sphere(sphere, p)) return false;
    size_t &n = m_n_conductor_sphere;
    const size_t m = n++;
    m_buf.conductor_sphere_index[m] = v.path;
    float *col = m_buf.conductor_sphere.data.data() + m;
    constexpr size_t st = LambertChunk;
    gather_conductor_sample(col, v.form->conductor, v.path, j);
    col[rsn_col::Ux * st] = m_u[1][j], col[rsn_col::Uy * st] = m_u[2][j];
    col[rsn_col::Sphere * st] = float(sphere);
    if (n == LambertChunk) flush_conductor_sphere(n);
    return true;
}

void Wavefront::sample_emitters(size_t n_scatter) {
    // Next-event estimation's emitter samples: a vertex that a whole-vertex kernel takes is done
    // there (BSDF sampling too); vertices that chose the environment sample it after this loop,
    // all at once; the others sample their emitter here.
    WaveBuffers &buf = m_buf;
    buf.quad.resize(lq_col::Count, LambertChunk);
    buf.sphere.resize(lq_col::Count, LambertChunk);
    buf.conductor_sphere.resize(cond_col::Count, LambertChunk);
    m_n_quad = m_n_sphere = m_n_conductor_sphere = 0;
    m_quad_one = -1;
    ScatterVertex *const scatter = buf.scatter.data();
    const SurfaceInteraction *const sis = buf.si.data();
    const std::array<float *, 7> u = m_u;
    const auto &lights = m_scene.lights();
    size_t n_env = 0;
    for (size_t j = 0; j < n_scatter; ++j) {
        ScatterVertex &v = scatter[j];
        const SurfaceInteraction &si = sis[v.path];
        v.nee = v.bsdf->has_smooth() && m_lights != 0;
        if (!v.nee) continue;
        const size_t idx = uniform_emitter_index(u[0][j], m_lights);
        if (emitter_kernel_lane(j, idx)) {
            v.nee = false; // handled by the kernel, BSDF sampling too
            v.sampled = true;
            continue;
        }
        const Light &light = *lights[idx];
        if (&light == m_env) {
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
        m_env->sample_li_batch(n_env, buf.env_ref.data(), buf.env_u.data(), buf.env_time.data(), buf.env_ls.data(),
                               buf.env_weight.data());
        // Member by member: a pair temporary would be built on the stack with narrow stores and
        // copied out with wide loads across them (failed store-to-load forwards).
        for (size_t m = 0; m < n_env; ++m) {
            auto &[ls, weight] = scatter[buf.env_lane[m]].emitter_sample;
            ls = buf.env_ls[m];
            weight = buf.env_weight[m];
        }
    }
    flush_quad(m_n_quad, m_quad_one);
    flush_sphere(m_n_sphere);
    flush_conductor_sphere(m_n_conductor_sphere);
}

void Wavefront::flush_lambert_nee(size_t &n) {
    if (n == 0) return;
    SoaColumns &lc = m_buf.lambert;
    gather_lambert_nee_lanes(lc.data.data(), LambertChunk, n, m_buf.lambert_index.data(), m_buf.lambert_vertex.data(),
                             lanes());
    lambert_nee_kernel(lc, n, m_lights_f);
    take_shadow_rays<ln_col::Ox>(lc, m_buf.lambert_index.data(), n);
    n = 0;
}

void Wavefront::flush_conductor_nee(size_t &n) {
    if (n == 0) return;
    rough_conductor_nee_kernel(m_buf.conductor, n, m_lights_f);
    take_shadow_rays<rn_col::Ox>(m_buf.conductor, m_buf.conductor_index.data(), n);
    n = 0;
}

void Wavefront::emitter_nee(size_t n_scatter) {
    // Next-event estimation of the vertices with an emitter sample: BSDF, MIS and shadow ray.
    WaveBuffers &buf = m_buf;
    SoaColumns &lc = buf.lambert, &rc = buf.conductor;
    lc.resize(ln_col::Count, LambertChunk);
    rc.resize(cond_col::Count, LambertChunk);
    const WavePath *const paths = buf.paths.data();
    const SurfaceInteraction *const sis = buf.si.data();
    size_t n_lam = 0, n_rc = 0;
    for (size_t j = 0; j < n_scatter; ++j) {
        ScatterVertex &v = buf.scatter[j];
        if (!v.nee || v.emitter_sample.second.is_black()) continue;
        const SurfaceInteraction &si = sis[v.path];
        const Bsdf &bsdf = *v.bsdf;
        const LightSample &ls = v.emitter_sample.first;
        if (v.form->kind == BsdfForm::Lambert) {
            const size_t m = n_lam++;
            buf.lambert_index[m] = v.path;
            buf.lambert_vertex[m] = uint32_t(j);
            lc[ln_col::TwoSided][m] = v.form->lambert.two_sided ? 1.f : 0.f;
            if (n_lam == LambertChunk) flush_lambert_nee(n_lam);
            continue;
        }
        if (v.form->kind == BsdfForm::RoughConductor) {
            const size_t m = n_rc++;
            buf.conductor_index[m] = v.path;
            float *col = rc.data.data() + m;
            gather_conductor_nee(col, LambertChunk, si, v.form->conductor, paths[v.path].throughput);
            put_emitter_sample<rn_col::Ldx>(col, LambertChunk, ls, v.emitter_sample.second);
            if (n_rc == LambertChunk) flush_conductor_nee(n_rc);
            continue;
        }
        Spectrum contribution;
        Ray r;
        if (!nee_step(bsdf, m_ctx, si, paths[v.path].throughput, ls, v.emitter_sample.second, m_lights_f, contribution, r))
            continue;
        const float ray_cols[8] = {r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z, r.tmax, r.time};
        for (size_t q = 0; q < 8; ++q) m_shadow[q][m_n_shadow] = ray_cols[q];
        buf.shadows[m_n_shadow++] = {v.path, contribution};
    }
    flush_lambert_nee(n_lam);
    flush_conductor_nee(n_rc);
}

void Wavefront::flush_lambert_samples(size_t &n) {
    if (n == 0) return;
    SoaColumns &lc = m_buf.lambert;
    gather_lambert_lanes(lc.data.data(), LambertChunk, n, m_buf.lambert_index.data(), m_buf.lambert_vertex.data(),
                         lanes(), false);
    lambert_sample_kernel(lc, n);
    take_samples<ls_col::Ox, ls_col::Br>(lc, m_buf.lambert_index.data(), n);
}

void Wavefront::flush_conductor_samples(size_t &n) {
    if (n == 0) return;
    rough_conductor_sample_kernel(m_buf.conductor, n);
    take_samples<rs_col::Ox, rs_col::Br>(m_buf.conductor, m_buf.conductor_index.data(), n);
}

void Wavefront::sample_bsdfs(size_t n_scatter) {
    // BSDF sampling and Russian roulette of the vertices no whole-vertex kernel took.
    WaveBuffers &buf = m_buf;
    SoaColumns &lc = buf.lambert;
    lc.resize(ls_col::Count, LambertChunk);
    buf.conductor.resize(cond_col::Count, LambertChunk);
    WavePath *const paths = buf.paths.data();
    Ray *const rays = buf.rays.data();
    const SurfaceInteraction *const sis = buf.si.data();
    uint8_t *const alive = buf.alive.data();
    const std::array<float *, 7> u = m_u;
    size_t n_lam = 0, n_rc = 0;
    for (size_t j = 0; j < n_scatter; ++j) {
        const ScatterVertex &v = buf.scatter[j];
        if (v.sampled) continue;
        const size_t k = v.path;
        WavePath &p = paths[k];
        const SurfaceInteraction &si = sis[k];
        const Bsdf &bsdf = *v.bsdf;
        if (v.form->kind == BsdfForm::Lambert) {
            const size_t m = n_lam++;
            buf.lambert_index[m] = uint32_t(k);
            buf.lambert_vertex[m] = uint32_t(j);
            lc[ls_col::TwoSided][m] = v.form->lambert.two_sided ? 1.f : 0.f;
            if (n_lam == LambertChunk) flush_lambert_samples(n_lam);
            continue;
        }
        if (v.form->kind == BsdfForm::RoughConductor) {
            const size_t m = n_rc++;
            buf.conductor_index[m] = uint32_t(k);
            gather_conductor_sample(buf.conductor.data.data() + m, v.form->conductor, uint32_t(k), j);
            if (n_rc == LambertChunk) flush_conductor_samples(n_rc);
            continue;
        }
        const auto [bs, bsdf_weight] = bsdf.sample(m_ctx, si, si.wi, u[3][j], {u[4][j], u[5][j]});
        if (!follow_bsdf_sample(p, si, bs, bsdf_weight, u[6][j], p.depth, m_cfg.rr_depth, rays[k])) continue;
        ++p.depth;
        alive[k] = 1;
    }
    flush_lambert_samples(n_lam);
    flush_conductor_samples(n_rc);
}

void Wavefront::trace_shadow_rays() {
    const size_t n = m_n_shadow;
    m_counters.shadow_rays += n;
    float *const *s = m_shadow.data();
    uint8_t *const blocked = m_buf.blocked.data();
    m_scene.occluded(RayColumns{s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]}, n, blocked);
    for (size_t j = 0; j < n; ++j)
        if (!blocked[j]) m_buf.paths[m_buf.shadows[j].path].result += m_buf.shadows[j].contribution;
}

size_t Wavefront::compact(size_t active, Spectrum *out, uint8_t *valid_out) {
    // Finished paths leave; the others move to the front (their order is kept).
    WavePath *const paths = m_buf.paths.data();
    Ray *const rays = m_buf.rays.data();
    const uint8_t *const alive = m_buf.alive.data();
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
    return next;
}
} // namespace

void PathIntegrator::li_batch(const Scene &scene, const Ray *camera_rays, Sampler *samplers, Spectrum *out, size_t n,
                              RayCounters &counters, const Medium *) const {
    // Media are ignored, as by Mitsuba's `path` (Scene notes it).
    trace_batch(scene, camera_rays, nullptr, samplers, out, nullptr, n, counters);
}

void PathIntegrator::trace_batch(const Scene &scene, const Ray *start_rays, const PathState *states, Sampler *samplers,
                                 Spectrum *out, uint8_t *valid_out, size_t n, RayCounters &counters) const {
    Wavefront(scene, m_cfg, samplers, per_thread<WaveBuffers>(), counters).run(start_rays, states, n, out, valid_out);
}

} // namespace mvpt
