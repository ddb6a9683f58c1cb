// The wavefront path tracer (PathIntegrator::li_batch, trace_batch) and the batched scene
// queries against their one-ray-at-a-time counterparts, on every per-feature scene: the
// same hits and bit-identical radiance per path (the renderer uses the batches, for camera
// paths and for multi-view suffixes; tests use li and trace).
#include "batch_checks.h"
#include "mvpt/core/simd_gather.h"
#include "mvpt/core/warp.h"
#include "mvpt/integrators/path/path.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include <cstring>
#include <filesystem>
#include <vector>

using namespace mvpt;

namespace {

std::vector<std::filesystem::path> feature_scenes() {
    std::vector<std::filesystem::path> out;
    // Next to this file (CMake compiles it by absolute path), whatever the working directory.
    auto dir = std::filesystem::path(__FILE__).parent_path().parent_path() / "scenes" / "features";
    for (auto &e : std::filesystem::directory_iterator(dir))
        // The envmap and bump-map scenes need an EXR that their Python test writes (the constant
        // emitter covers escaping paths).
        if (e.path().extension() == ".xml" && e.path().stem() != "emitter_envmap" && e.path().stem() != "bsdf_bumpmap")
            out.push_back(e.path());
    std::sort(out.begin(), out.end());
    return out;
}

using test::camera_rays;
using test::same_bits;

/// Whether Embree runs 16-wide packets with 16-wide kernels on this CPU.
bool embree_has_16_wide() {
    return simd::cpu_has_avx512f();
}

/// How many floats lie between a and b (0: the same value).
int64_t ulps(float a, float b) {
    auto key = [](float x) {
        const int32_t i = std::bit_cast<int32_t>(x);
        return i < 0 ? int64_t(INT32_MIN) - i : int64_t(i);
    };
    return std::abs(key(a) - key(b));
}

} // namespace

TEST(PathBatch, BatchedQueriesMatchSingleRays) {
    for (const auto &path : feature_scenes()) {
        SCOPED_TRACE(path.string());
        auto scene = load_scene_file(path);
        std::vector<Ray> rays;
        std::vector<Sampler> samplers;
        camera_rays(*scene, 12, 2, rays, samplers);
        // Secondary rays in all directions from the camera rays' hits, and shadow rays to the origin.
        size_t n_camera = rays.size();
        for (size_t i = 0; i < n_camera; ++i) {
            SurfaceInteraction si;
            if (!scene->intersect(rays[i], si)) continue;
            Vec3f d = warp::square_to_uniform_sphere(samplers[i].next_2d());
            rays.push_back(si.spawn_ray(d));
            rays.push_back(si.spawn_ray_to(Point3f(0.f, 0.f, 0.f)));
        }
        // Rays Embree must not trace (a NaN, a coordinate beyond its range) among the others,
        // at packet positions that vary: misses and unblocked, as the single queries say.
        const float nan = std::nanf("");
        for (size_t i = 0, n = rays.size(); i < n; i += 7) {
            Ray bad = rays[i];
            switch (i / 7 % 5) {
            case 0: bad.o.x = nan; break;
            case 1: bad.d.y = 1e19f; break;
            case 2: bad.tmax = nan; break;
            case 3: bad.tmin = nan; break;
            default: bad.o.z = -2e18f; break;
            }
            rays[i] = bad;
        }
        // Embree's 16-wide kernels (AVX-512) find the same bits as its single-ray ones. Without
        // them it traces a 16-wide packet as a stream of 8-wide ones, whose distances may differ
        // in the last bit (one ray of one scene here).
        const int64_t max_ulps = embree_has_16_wide() ? 0 : 2;
        for (bool coherent : {false, true}) {
            size_t ties = 0;
            std::vector<SurfaceInteraction> si(rays.size());
            std::vector<uint8_t> hit(rays.size()), blocked(rays.size());
            scene->intersect(rays.data(), rays.size(), si.data(), hit.data(), coherent);
            scene->occluded(rays.data(), rays.size(), blocked.data());
            for (size_t i = 0; i < rays.size(); ++i) {
                SurfaceInteraction ref;
                bool h = scene->intersect(rays[i], ref);
                ASSERT_EQ(bool(hit[i]), h) << "ray " << i;
                ASSERT_EQ(bool(blocked[i]), scene->occluded(rays[i])) << "ray " << i;
                if (!h) continue;
                EXPECT_LE(ulps(si[i].t, ref.t), max_ulps) << "ray " << i << ": " << si[i].t << " " << ref.t;
                if (si[i].shape != ref.shape || si[i].prim != ref.prim) {
                    // Two primitives at exactly the same distance (a box standing on the floor,
                    // a ray along the contact): the packet's traversal order may pick the other.
                    ++ties;
                    continue;
                }
                EXPECT_LE(ulps(si[i].p.x, ref.p.x), max_ulps) << "ray " << i;
                EXPECT_LE(ulps(si[i].p.y, ref.p.y), max_ulps) << "ray " << i;
                EXPECT_LE(ulps(si[i].sh_frame.n.z, ref.sh_frame.n.z), max_ulps) << "ray " << i;
                EXPECT_LE(ulps(si[i].uv.x, ref.uv.x), max_ulps) << "ray " << i;
            }
            EXPECT_LE(ties, rays.size() / 100);
        }
    }
}

TEST(PathBatch, RadianceBitIdenticalToLi) {
    for (const auto &path : feature_scenes()) {
        SCOPED_TRACE(path.string());
        auto scene = load_scene_file(path);
        for (int variant = 0; variant < 4; ++variant) {
            // The scene's own integrator, then short paths with emitters hidden, then long ones,
            // then the scene's integrator with Sobol samplers (li_batch draws the independent
            // sampler's numbers in a batched loop, the others through the sampler).
            PathConfig cfg;
            if (auto *p = dynamic_cast<const PathIntegrator *>(&scene->integrator())) cfg = p->config();
            if (variant == 1) { cfg.max_depth = 2; cfg.hide_emitters = true; }
            if (variant == 2) { cfg.max_depth = -1; cfg.rr_depth = 2; }
            PathIntegrator integrator(cfg);
            std::vector<Ray> rays;
            std::vector<Sampler> samplers;
            camera_rays(*scene, 16, 2, rays, samplers, variant == 3);
            SCOPED_TRACE("variant " + std::to_string(variant));
            const size_t nonzero = test::expect_li_batch_equals_li(*scene, integrator, rays, samplers);
            if (HasFailure()) return;
            EXPECT_GT(nonzero, rays.size() / 10) << "variant " << variant; // the comparison saw light
        }
    }
}

// trace_batch continues paths from given states (multi-view path tracing's suffixes) exactly
// as trace does, result and valid flag, for states of every kind: deeper vertices, delta and
// smooth previous lobes, paths not yet valid.
TEST(PathBatch, TraceBatchContinuesLikeTrace) {
    for (const auto &path : feature_scenes()) {
        SCOPED_TRACE(path.string());
        auto scene = load_scene_file(path);
        PathConfig cfg;
        if (auto *p = dynamic_cast<const PathIntegrator *>(&scene->integrator())) cfg = p->config();
        cfg.rr_depth = 2;
        PathIntegrator integrator(cfg);
        std::vector<Ray> camera, rays;
        std::vector<Sampler> samplers, batch_samplers;
        std::vector<PathState> states;
        camera_rays(*scene, 16, 2, camera, samplers);
        for (size_t i = 0; i < camera.size(); ++i) {
            SurfaceInteraction si;
            if (!scene->intersect(camera[i], si)) continue;
            Sampler &s = samplers[i];
            PathState st;
            st.depth = 1 + uint32_t(s.next_1d() * 3.f);
            st.throughput = Spectrum(0.2f + s.next_1d(), 0.5f, 0.2f + s.next_1d());
            st.eta = s.next_1d() < 0.5f ? 1.f : 1.5f;
            st.prev_p = si.p;
            st.prev_bsdf_pdf = 0.05f + 2.f * s.next_1d();
            st.prev_bsdf_delta = s.next_1d() < 0.2f;
            st.valid = s.next_1d() < 0.7f;
            Vec3f d = warp::square_to_uniform_sphere(s.next_2d());
            if (dot(d, si.n) * dot(camera[i].d, si.n) > 0.f) d = -d; // back to the camera's side, as a bounce
            rays.push_back(si.spawn_ray(d));
            states.push_back(st);
            batch_samplers.push_back(s);
        }
        const size_t nonzero = test::expect_trace_batch_equals_trace(*scene, integrator, rays, states, batch_samplers);
        EXPECT_GT(nonzero, rays.size() / 10); // the comparison saw light
        EXPECT_GT(rays.size(), 100u);
    }
}
