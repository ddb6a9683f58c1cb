// Balance weights of multi-view path tracing (docs/multiview-path-tracing.md §5): every
// strategy that can produce a shifted sample must compute the same density D_k for it —
// then the weights n_j rho_{j->k} / D_k of all strategies sum to one. For random first hits
// in a scene with an occluder, pinholes and thin lenses of different fov, resolution and
// aperture, a moving camera, random native-sample maps, with and without each selection
// term: the native sample of every view that sees y yields the same set of sharing views
// and the same D_k for each of them.
#include "mvpt/core/warp.h"
#include "mvpt/integrators/multiview/mv_sample.h"
#include "mvpt/render/interaction.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

using namespace mvpt;

namespace {

// Box filters: a view's sample window is its crop window (no filter margin).
const char *SceneXml = R"(<scene version="3.0.0">
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="phong"><float name="exponent" value="12"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><translate z="-1.5" y="1"/></transform>
    <bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="0.1" y="0.35" z="0"/><float name="radius" value="0.3"/>
    <bsdf type="diffuse"/></shape>
  <sensor type="perspective" id="a"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 1.2, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/><rfilter type="box"/></film></sensor>
  <sensor type="perspective" id="b"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0.4, 1.0, 3.2" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film></sensor>
  <sensor type="thinlens" id="c"><float name="fov" value="50"/><float name="aperture_radius" value="0.08"/>
    <float name="focus_distance" value="3"/>
    <transform name="to_world"><lookat origin="-0.5, 1.1, 2.8" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film></sensor>
  <sensor type="thinlens" id="d"><float name="fov" value="40"/><float name="aperture_radius" value="0.2"/>
    <float name="focus_distance" value="2.5"/>
    <transform name="to_world"><lookat origin="0.8, 1.5, 2.6" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="36"/><integer name="height" value="20"/><rfilter type="box"/></film></sensor>
  <sensor type="perspective" id="moving"><float name="fov" value="45"/>
    <float name="shutter_open" value="0"/><float name="shutter_close" value="1"/>
    <animation name="to_world">
      <transform time="0"><lookat origin="-0.2, 1.2, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
      <transform time="1"><lookat origin="0.3, 1.3, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    </animation>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film></sensor>
  <sensor type="perspective" id="moving2"><float name="fov" value="35"/>
    <float name="shutter_open" value="0.5"/><float name="shutter_close" value="1.5"/>
    <animation name="to_world">
      <transform time="0.5"><lookat origin="0.6, 1.2, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
      <transform time="1.5"><lookat origin="0.2, 1.0, 3.3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    </animation>
    <film type="hdrfilm"><integer name="width" value="28"/><integer name="height" value="28"/><rfilter type="box"/></film></sensor>
</scene>)";

struct Fixture {
    std::unique_ptr<Scene> scene = load_scene_string(SceneXml, ".");
    std::vector<std::vector<uint16_t>> maps;
    MvContext ctx;

    /// `static_only`: the four static cameras only (then shifts and D take the vector loops).
    Fixture(bool jacobian, bool material, bool static_only, uint32_t seed) {
        std::mt19937 rng(seed);
        ctx.scene = scene.get();
        ctx.cfg.select_jacobian = jacobian;
        ctx.cfg.select_material = material;
        const auto &cams = scene->cameras();
        for (size_t i = 0; i < cams.size(); ++i) {
            const Camera &c = *cams[i];
            if (static_only && c.is_animated()) continue;
            ctx.views.push_back({&c, uint32_t(i), c.shutter_open, c.shutter_close - c.shutter_open});
            maps.emplace_back(size_t(c.film.crop_width) * c.film.crop_height);
            for (uint16_t &n : maps.back()) n = uint16_t(1 + rng() % 4); // uneven native counts
        }
        for (auto &m : maps) ctx.native_map.push_back(m.data());
        ctx.prepare();
    }
};

void check_weights(bool jacobian, bool material, bool static_only = false) {
    Fixture f(jacobian, material, static_only, 7);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    MvScratch sc;
    int checked = 0, shared = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        int l = int(rng() % f.ctx.views.size());
        const Camera &cam = *f.ctx.views[l].camera;
        Vec2f x(u(rng) * cam.film.width, u(rng) * cam.film.height);
        Vec2f xi = warp::square_to_uniform_disk_concentric({u(rng), u(rng)});
        float t = cam.sample_time(u(rng));
        Ray ray = cam.generate_ray(x, xi, t);
        SurfaceInteraction si;
        if (!f.scene->intersect(ray, si)) continue;
        auto from_l = mv_balance_densities(f.ctx, l, si, ray.o, t, xi, sc);
        if (from_l.empty()) continue;
        std::map<int, float> d_l(from_l.begin(), from_l.end());
        // Every other strategy j that can produce this sample: its own native sample of y at
        // its time (t mapped between shutters: the scene is static) and the same lens point xi.
        for (auto [j, d_unused] : from_l) {
            if (j == l) continue;
            const MvView &vl = f.ctx.views[l], &vj = f.ctx.views[j];
            float t_j = 0.f;
            ASSERT_TRUE(shift_time(vl, vj, t, false, &t_j));
            Point3f u_j = vj.camera->lens_point(t_j, xi);
            auto from_j = mv_balance_densities(f.ctx, j, si, u_j, t_j, xi, sc);
            std::map<int, float> d_j(from_j.begin(), from_j.end());
            ASSERT_EQ(d_l.size(), d_j.size()) << "views " << l << " and " << j << " disagree on who shares y";
            for (auto [k, d] : d_l) {
                ASSERT_TRUE(d_j.count(k)) << "view " << k << " shares from " << l << " but not from " << j;
                EXPECT_NEAR(d_j[k], d, 2e-4f * d) << "D of view " << k << " from " << l << " vs " << j;
            }
            ++checked;
        }
        shared += from_l.size() > 1;
    }
    EXPECT_GT(checked, 1000);
    EXPECT_GT(shared, 500);
    EXPECT_EQ(f.ctx.all_time_compatible, static_only);
}

} // namespace

TEST(MultiViewWeights, EveryStrategyComputesTheSameDensity) { check_weights(true, false); }
TEST(MultiViewWeights, EveryStrategyComputesTheSameDensityWithMaterialSimilarity) { check_weights(true, true); }
TEST(MultiViewWeights, EveryStrategyComputesTheSameDensityWithoutSelection) { check_weights(false, false); }
TEST(MultiViewWeights, EveryStrategyComputesTheSameDensityStaticCameras) { check_weights(true, false, true); }
