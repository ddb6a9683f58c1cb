// The path tracer of path.cpp as a wavefront: all paths of a batch (a render tile's
// camera rays) advance one vertex at a time, so that Embree traces their rays and shadow
// rays as 16-wide packets instead of one by one. The per-vertex arithmetic, the sample
// dimensions and the order in which contributions are summed are those of
// PathIntegrator::li, so each path's radiance is bit-identical to li's for the same hits
// (tests/cpp/test_path_batch.cpp checks this).
#include "path.h"

#include "../render/bsdf.h"
#include "../render/light.h"
#include "../render/shape.h"
#include "../scene/scene.h"

#include <climits>
#include <new>
#include <utility>
#include <vector>

namespace mvpt {

namespace {
/// One path between two vertices: li's loop variables.
struct WavePath {
    Spectrum result{0.f}, throughput{1.f};
    float eta = 1.f;
    Ray ray;
    Point3f prev_p;
    float prev_bsdf_pdf = 1.f;
    bool prev_bsdf_delta = true;
    bool valid = false;
    uint32_t depth = 0;
    /// Index of the camera ray (sampler and output slot).
    uint32_t slot = 0;
};

/// A path that scatters at its current vertex: the vertex's random numbers (drawn in li's
/// order) and its emitter sample, carried between the shading loops.
struct ScatterVertex {
    /// Index of the path among the active ones.
    uint32_t path;
    float u_light_select, u_lobe, u_rr;
    Vec2f u_light, u_dir;
    /// Next-event estimation: whether an emitter was sampled, the sample and its weight.
    bool nee = false;
    std::pair<LightSample, Spectrum> emitter_sample;
};

/// Next-event estimate waiting for its shadow ray: added to `path`'s result if unblocked.
struct PendingShadow {
    uint32_t path;
    Spectrum contribution;
};

/// Per-thread buffers, reused across batches.
struct WaveBuffers {
    std::vector<WavePath> paths;
    std::vector<Ray> rays, shadow_rays;
    std::vector<SurfaceInteraction> si;
    std::vector<uint8_t> hit, blocked, alive;
    std::vector<ScatterVertex> scatter;
    std::vector<PendingShadow> shadows;
};
} // namespace

void PathIntegrator::li_batch(const Scene &scene, const Ray *camera_rays, Sampler *samplers, Spectrum *out, size_t n,
                              RayCounters &counters) const {
    const auto &lights = scene.lights();
    const uint32_t max_depth = m_cfg.max_depth < 0 ? UINT_MAX : uint32_t(m_cfg.max_depth);
    const BsdfContext ctx;
    const bool valid0 = !m_cfg.hide_emitters && scene.environment() != nullptr;

    thread_local WaveBuffers buf;
    auto &paths = buf.paths;
    paths.assign(n, WavePath{});
    for (size_t i = 0; i < n; ++i) {
        paths[i].ray = camera_rays[i];
        paths[i].valid = valid0;
        paths[i].slot = uint32_t(i);
    }
    buf.rays.resize(n);
    buf.si.resize(n);
    buf.hit.resize(n);
    buf.alive.resize(n);
    buf.shadow_rays.resize(n);
    buf.blocked.resize(n);
    buf.scatter.resize(n);
    buf.shadows.resize(n);

    // Each vertex runs as a few loops over all paths, one step of li's loop body each, so
    // that the paths' long dependency chains (square roots, divisions, virtual calls)
    // overlap; every path still sees li's operations in li's order.
    size_t active = n;
    for (bool first = true; active > 0; first = false) {
        for (size_t k = 0; k < active; ++k) {
            buf.rays[k] = paths[k].ray;
            buf.si[k] = SurfaceInteraction();
        }
        counters.rays += active;
        scene.intersect(buf.rays.data(), active, buf.si.data(), buf.hit.data(), first);

        // ---------------- Emission (hit by BSDF sampling, MIS against NEE) ----------------
        size_t n_scatter = 0;
        for (size_t k = 0; k < active; ++k) {
            WavePath &p = paths[k];
            Sampler &sampler = samplers[p.slot];
            const SurfaceInteraction &si_hit = buf.si[k];
            const bool hit = buf.hit[k] != 0;
            const Ray &ray = p.ray;
            buf.alive[k] = 0;
            sampler.set_dimension(DimCameraEnd + p.depth * DimsPerVertex);

            const Light *emitter = hit ? si_hit.shape->emitter.get() : scene.environment();
            if (emitter && !m_cfg.hide_emitters && hit) p.valid = true;
            if (emitter && !(p.depth == 0 && m_cfg.hide_emitters)) {
                Spectrum le = hit ? emitter->eval(si_hit, -ray.d) : emitter->eval_environment(ray.d);
                if (!le.is_black()) {
                    float w = 1.f;
                    if (!p.prev_bsdf_delta)
                        w = mis_power(p.prev_bsdf_pdf, emitter_pdf(scene, emitter, p.prev_p, si_hit, ray.d));
                    p.result += p.throughput * le * w;
                }
            }
            if (!hit || p.depth + 1 >= max_depth) continue;

            SurfaceInteraction &si = buf.si[k];
            si.wi = si.to_local(-ray.d);
            // The vertex's sample dimensions, in li's order (u_rr is unused when li stops earlier).
            ScatterVertex &v = buf.scatter[n_scatter++];
            v.path = uint32_t(k);
            v.u_light_select = sampler.next_1d();
            v.u_light = sampler.next_2d();
            v.u_lobe = sampler.next_1d();
            v.u_dir = sampler.next_2d();
            v.u_rr = sampler.next_1d();
        }

        // ---------------- Next-event estimation: emitter samples ----------------
        for (size_t j = 0; j < n_scatter; ++j) {
            ScatterVertex &v = buf.scatter[j];
            const SurfaceInteraction &si = buf.si[v.path];
            v.nee = si.shape->bsdf->has_smooth() && !lights.empty();
            if (!v.nee) continue;
            size_t idx = std::min(size_t(v.u_light_select * float(lights.size())), lights.size() - 1);
            const Light &light = *lights[idx];
            // Constructed in place (guaranteed copy elision): copying the returned pair with wide
            // loads right after the callee's narrow stores would stall on store forwarding.
            ::new (&v.emitter_sample) std::pair<LightSample, Spectrum>(light.sample_li(si.p, v.u_light, si.time));
        }

        // ---------------- Next-event estimation: BSDF and shadow rays (traced below) ----------------
        size_t n_shadow = 0;
        for (size_t j = 0; j < n_scatter; ++j) {
            ScatterVertex &v = buf.scatter[j];
            if (!v.nee || v.emitter_sample.second.is_black()) continue;
            const SurfaceInteraction &si = buf.si[v.path];
            const Bsdf &bsdf = *si.shape->bsdf;
            const LightSample &ls = v.emitter_sample.first;
            Spectrum weight = v.emitter_sample.second;
            weight *= float(lights.size());
            Vec3f wo = si.to_local(ls.d);
            Spectrum f = bsdf.eval(ctx, si, si.wi, wo);
            if (!f.is_black()) {
                buf.shadow_rays[n_shadow] = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
                float w = ls.delta ? 1.f : mis_power(ls.pdf / float(lights.size()), bsdf.pdf(ctx, si, si.wi, wo));
                buf.shadows[n_shadow++] = {v.path, paths[v.path].throughput * f * weight * w};
            }
        }

        // ---------------- BSDF sampling and Russian roulette ----------------
        for (size_t j = 0; j < n_scatter; ++j) {
            const ScatterVertex &v = buf.scatter[j];
            const size_t k = v.path;
            WavePath &p = paths[k];
            const SurfaceInteraction &si = buf.si[k];
            const Bsdf &bsdf = *si.shape->bsdf;
            auto [bs, bsdf_weight] = bsdf.sample(ctx, si, si.wi, v.u_lobe, v.u_dir);
            if (!(bs.sampled_type & BsdfNull)) p.valid = true;
            if (bsdf_weight.is_black()) continue;
            Vec3f wo_world = si.to_world(bs.wo);
            p.ray = si.spawn_ray(wo_world);
            p.throughput *= bsdf_weight;
            p.eta *= bs.eta;
            p.prev_p = si.p;
            p.prev_bsdf_pdf = bs.pdf;
            p.prev_bsdf_delta = (bs.sampled_type & BsdfDelta) != 0;

            float t_max = p.throughput.max_value();
            if (!(t_max > 0.f)) continue;
            if (p.depth + 1 >= uint32_t(m_cfg.rr_depth)) {
                float q = std::min(t_max * p.eta * p.eta, 0.95f);
                if (v.u_rr >= q) continue;
                p.throughput *= 1.f / q;
            }
            ++p.depth;
            buf.alive[k] = 1;
        }

        // ---------------- Shadow rays of this vertex ----------------
        counters.shadow_rays += n_shadow;
        scene.occluded(buf.shadow_rays.data(), n_shadow, buf.blocked.data());
        for (size_t j = 0; j < n_shadow; ++j)
            if (!buf.blocked[j]) paths[buf.shadows[j].path].result += buf.shadows[j].contribution;

        // Finished paths leave; the others move to the front (their order is kept).
        size_t next = 0;
        for (size_t k = 0; k < active; ++k) {
            if (buf.alive[k]) {
                if (next != k) paths[next] = paths[k];
                ++next;
            } else {
                out[paths[k].slot] = paths[k].valid ? paths[k].result : Spectrum(0.f);
            }
        }
        active = next;
    }
}

} // namespace mvpt
