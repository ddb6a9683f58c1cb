// The vector loops over views of multi-view path tracing (integrators/multiview/mv_candidates.*):
// they run in the clone for this CPU's instruction set and must give exactly what the
// scalar per-camera code gives (the build has no FMA contraction), and the visibility
// packets must agree with one-ray queries.
#include "mvpt/core/warp.h"
#include "mvpt/integrators/multiview/mv_candidates.h"
#include "mvpt/integrators/multiview/mv_sample.h"
#include "mvpt/render/interaction.h"
#include "mvpt/loader/load_scene.h"
#include "mvpt/accel/segment_cull.h"

#include <gtest/gtest.h>

#include <random>

using namespace mvpt;

namespace {

// Box filters: a view's sample window is its crop window (no filter margin).
const char *SceneXml = R"(<scene version="3.0.0">
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"/></shape>
  <shape type="sphere"><point name="center" x="0.1" y="0.35" z="0"/><float name="radius" value="0.3"/>
    <bsdf type="diffuse"/></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.2"/><translate x="-0.6" y="0.2" z="0.3"/></transform>
    <bsdf type="diffuse"/></shape>
  <sensor type="perspective" id="a"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 1.2, 3" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/><rfilter type="box"/></film></sensor>
  <sensor type="perspective" id="b"><float name="fov" value="30"/><float name="near_clip" value="2.5"/>
    <transform name="to_world"><lookat origin="0.4, 1.0, 3.2" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
      <integer name="crop_offset_x" value="4"/><integer name="crop_offset_y" value="6"/>
      <integer name="crop_width" value="12"/><integer name="crop_height" value="10"/><rfilter type="box"/></film></sensor>
  <sensor type="thinlens" id="c"><float name="fov" value="50"/><float name="aperture_radius" value="0.08"/>
    <float name="focus_distance" value="3"/>
    <transform name="to_world"><lookat origin="-0.5, 1.1, 2.8" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film></sensor>
  <sensor type="perspective" id="below"><float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, -1, 1" target="0, 0.3, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/><rfilter type="box"/></film></sensor>
</scene>)";

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

} // namespace

// shift_static_views (one vector loop over the padded view tables) gives, view by view, the
// status bits, pixel and geometry of the camera's own shift_geometry and shift_status; with
// the scene's 4 cameras (one vector) and with 5 copies of them (20 views: two vectors, padding).
class StaticShiftLoop : public testing::TestWithParam<int> {};

TEST_P(StaticShiftLoop, EqualsEachCamera) {
    auto scene = load_scene_string(SceneXml, ".");
    MvContext ctx;
    ctx.scene = scene.get();
    const auto &scene_cams = scene->cameras();
    std::vector<const Camera *> cams;
    for (int copy = 0; copy < GetParam(); ++copy)
        for (size_t i = 0; i < scene_cams.size(); ++i) {
            cams.push_back(scene_cams[i].get());
            ctx.views.push_back({cams.back(), uint32_t(i), cams.back()->shutter_open, 0.f});
        }
    ctx.prepare();
    ASSERT_TRUE(ctx.static_shift);
    ASSERT_EQ(ctx.projections.size() % ViewLanes, 0u);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    ViewShifts vs;
    int accepted = 0, rejected[3] = {};
    for (int trial = 0; trial < 2000; ++trial) {
        const Camera &cam = *cams[0];
        Vec2f xi = warp::square_to_uniform_disk_concentric({u(rng), u(rng)});
        Ray ray = cam.generate_ray({u(rng) * cam.film.width, u(rng) * cam.film.height}, xi, 0.f);
        SurfaceInteraction si;
        if (!scene->intersect(ray, si)) continue;
        MvVertex y{si.p, si.n, 0.f, xi, dot(si.n, ray.o - si.p)};
        shift_static_views(ctx.projections, ctx.films, y, vs);
        for (size_t k = 0; k < cams.size(); ++k) {
            ShiftGeometry g;
            bool ok = cams[k]->shift_geometry(y.p, y.n, 0.f, y.lens, &g);
            uint32_t pixel = 0;
            uint32_t status = shift_status(y, ok, g, SampleWindow(cams[k]->film), &pixel);
            ASSERT_EQ(vs.status[k], status) << "view " << k << ", trial " << trial;
            if (status & ShiftDepth) continue;
            EXPECT_TRUE(same_bits(vs.geo.density[k], g.density));
            EXPECT_TRUE(same_bits(vs.geo.visible_length[k], g.visible_length));
            EXPECT_TRUE(same_bits(vs.geo.lens_x[k], g.lens_point.x) && same_bits(vs.geo.lens_y[k], g.lens_point.y) &&
                        same_bits(vs.geo.lens_z[k], g.lens_point.z));
            EXPECT_TRUE(same_bits(vs.geo.film_x[k], g.film.x) && same_bits(vs.geo.film_y[k], g.film.y));
            if (status == 0) {
                ASSERT_EQ(vs.pixel[k], pixel);
                ASSERT_LT(pixel, uint32_t(cams[k]->film.crop_width * cams[k]->film.crop_height));
                ++accepted;
            } else {
                ++rejected[status & ShiftFacing ? 0 : status & ShiftOutside ? 1 : 2];
            }
        }
        for (size_t k = cams.size(); k < ctx.projections.size(); ++k)
            ASSERT_TRUE(vs.status[k] & ShiftOutside) << "padding view " << k << " must never be a candidate";
    }
    // Every kind of outcome occurred: shifts accepted, facing away (the camera below the
    // floor), outside the crop window.
    EXPECT_GT(accepted, 1000);
    EXPECT_GT(rejected[0], 100);
    EXPECT_GT(rejected[1], 100);
}

INSTANTIATE_TEST_SUITE_P(MvCandidates, StaticShiftLoop, testing::Values(1, 5));

// Segments from one origin traced as 8-wide packets block exactly when the one-ray query does;
// segments of length <= 0 and the padding are not traced.
TEST(MvCandidates, OccludedSegmentsEqualsOccluded) {
    auto scene = load_scene_string(SceneXml, ".");
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int blocked_count = 0, free_count = 0;
    for (int trial = 0; trial < 200; ++trial) {
        const Point3f o(u(rng) * 2.f - 1.f, u(rng) * 1.2f + 0.01f, u(rng) * 2.f - 1.f);
        const size_t n = 1 + rng() % 40, padded = whole_lanes(n);
        std::vector<float> dx(padded, 0.f), dy(padded, 0.f), dz(padded, 1.f), t_max(padded, -1.f);
        for (size_t i = 0; i < n; ++i) {
            Vec3f d = warp::square_to_uniform_sphere({u(rng), u(rng)});
            dx[i] = d.x, dy[i] = d.y, dz[i] = d.z;
            t_max[i] = i % 7 == 3 ? -0.5f : u(rng) * 3.f;
        }
        std::vector<uint8_t> blocked(n, 7);
        scene->occluded_segments(o, dx.data(), dy.data(), dz.data(), t_max.data(), n, 0.f, blocked.data());
        for (size_t i = 0; i < n; ++i) {
            bool expect = t_max[i] > 0.f && scene->occluded(Ray{o, Vec3f(dx[i], dy[i], dz[i]), 0.f, t_max[i], 0.f});
            ASSERT_EQ(bool(blocked[i]), expect) << "trial " << trial << ", segment " << i;
            (expect ? blocked_count : free_count) += 1;
        }
    }
    EXPECT_GT(blocked_count, 200);
    EXPECT_GT(free_count, 200);
}

// The same with culling: bundles of 24 segments from points around the sphere's and the
// cube's silhouettes to a small grid of lens points, so that most bundles meet one to four
// occluders and only the packets with a segment that may meet one are traced. Every segment
// must still get Embree's answer for its own ray.
TEST(MvCandidates, CulledSegmentsEqualOccluded) {
    auto scene = load_scene_string(SceneXml, ".");
    scene->prepare_segment_culling();
    ASSERT_NE(scene->occluder_bvh(), nullptr);
    std::mt19937 rng(6);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const Vec3f across(1.f, 0.f, 0.f);
    int blocked_count = 0, free_count = 0, few_blockers = 0;
    for (int trial = 0; trial < 400; ++trial) {
        // Behind the sphere or the cube as seen from the grid (z ~ 3), near the floor or above it.
        const bool sphere = trial % 2 == 0;
        const Point3f o = sphere ? Point3f(0.1f + 0.8f * (u(rng) - 0.5f), 0.01f + 0.7f * u(rng), -0.35f - 0.5f * u(rng))
                                 : Point3f(-0.6f + 0.5f * (u(rng) - 0.5f), 0.01f + 0.4f * u(rng), 0.05f - 0.4f * u(rng));
        const size_t n = 24, padded = whole_lanes(n);
        std::vector<float> dx(padded, 0.f), dy(padded, 0.f), dz(padded, 1.f), t_max(padded, -1.f);
        for (size_t i = 0; i < n; ++i) {
            const Point3f lens(0.06f * float(i % 5) - 0.12f, 1.0f + 0.06f * float(i / 5), 3.f);
            const Vec3f d = lens - o;
            const float len = norm(d);
            dx[i] = d.x / len, dy[i] = d.y / len, dz[i] = d.z / len;
            t_max[i] = i % 11 == 5 ? -1.f : len * 0.999f;
        }
        SegmentBundle bundle;
        int64_t list[4];
        if (bundle.build(o, across, dx.data(), dy.data(), dz.data(), t_max.data(), n)) {
            const int k = scene->occluder_bvh()->blockers(bundle, list, 4);
            few_blockers += k > 0;
        }
        std::vector<uint8_t> blocked(n, 7);
        scene->occluded_segments(o, dx.data(), dy.data(), dz.data(), t_max.data(), n, 0.f, blocked.data(), across);
        for (size_t i = 0; i < n; ++i) {
            bool expect = t_max[i] > 0.f && scene->occluded(Ray{o, Vec3f(dx[i], dy[i], dz[i]), 0.f, t_max[i], 0.f});
            ASSERT_EQ(bool(blocked[i]), expect) << "trial " << trial << ", segment " << i;
            (expect ? blocked_count : free_count) += 1;
        }
    }
    EXPECT_GT(few_blockers, 100); // the culled path is taken
    EXPECT_GT(blocked_count, 500);
    EXPECT_GT(free_count, 500);
}

// balance_sums (eight targets in vector lanes) against a direct double-precision sum.
TEST(MvCandidates, BalanceSumsMatchDirectSums) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int trial = 0; trial < 200; ++trial) {
        const size_t nv = 1 + rng() % 70, nt = 1 + rng() % nv, padded = (nt + 7) / 8 * 8;
        std::vector<float> g(nv), n(nv), gt(padded, 1.f), d(padded);
        for (size_t j = 0; j < nv; ++j) {
            g[j] = std::exp(4.f * u(rng) - 2.f);
            n[j] = float(1 + rng() % 16);
        }
        for (size_t t = 0; t < nt; ++t) gt[t] = g[rng() % nv];
        for (bool jacobian : {false, true}) {
            balance_sums(g.data(), n.data(), nv, gt.data(), padded, jacobian, d.data());
            for (size_t t = 0; t < nt; ++t) {
                double sum = 0.0;
                for (size_t j = 0; j < nv; ++j) {
                    double r = double(g[j]) / gt[t];
                    sum += n[j] * (jacobian ? r * std::min(1.0, r) : r);
                }
                ASSERT_NEAR(d[t], sum, 2e-6 * sum * double(nv)) << "trial " << trial << ", target " << t;
            }
        }
    }
}

// select_by_jacobian (one vector loop) makes, candidate by candidate, the draw the sampler
// makes at the view's selection dimension and the choice of the scalar rule: s = s_J(G_0 ->
// G_i) (1 without the Jacobian term), selected when s >= 1 or u < s; with zero, negative and
// non-finite densities among the candidates.
TEST(MvCandidates, SelectionLoopEqualsSamplerDraws) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const size_t views = 70;
    std::vector<uint32_t> scene_index(views);
    std::vector<uint64_t> keys(views);
    for (size_t v = 0; v < views; ++v) {
        scene_index[v] = uint32_t(rng() % 1000);
        keys[v] = Sampler::dimension_key(DimSelectBase + scene_index[v]);
    }
    size_t drawn = 0, rejected = 0;
    for (int trial = 0; trial < 300; ++trial) {
        MvCandidates c;
        c.reserve(views);
        c.size = 1 + rng() % views;
        for (size_t i = 0; i < c.size; ++i) {
            c.slot[i] = int32_t(rng() % views);
            const float r = u(rng);
            c.g[i] = r < 0.05f ? 0.f : r < 0.08f ? -1.f : r < 0.1f ? INFINITY : std::exp(2.f * u(rng) - 1.f);
        }
        Sampler sampler(SamplerKind::Independent, 7);
        sampler.start(rng() % 4, rng() % 64, rng() % 64, uint32_t(trial));
        for (bool jacobian : {false, true}) {
            std::vector<float> s(c.size, -1.f);
            std::vector<uint32_t> selected(c.size, 7u);
            select_by_jacobian(c, keys.data(), sampler.sample_hash(), jacobian, s.data(), selected.data());
            for (size_t i = 1; i < c.size; ++i) {
                const float s_ref = jacobian ? jacobian_similarity(c.g[0], c.g[i]) : 1.f;
                bool sel_ref = true;
                if (!(s_ref >= 1.f)) {
                    Sampler draw = sampler;
                    draw.set_dimension(DimSelectBase + scene_index[size_t(c.slot[i])]);
                    sel_ref = draw.next_1d() < s_ref;
                    ++drawn;
                    rejected += !sel_ref;
                }
                ASSERT_TRUE(same_bits(s[i], s_ref)) << "trial " << trial << ", candidate " << i;
                ASSERT_EQ(selected[i], uint32_t(sel_ref)) << "trial " << trial << ", candidate " << i;
            }
            EXPECT_EQ(selected[0], 7u) << "the native view is not drawn";
        }
    }
    EXPECT_GT(drawn, 1000u);
    EXPECT_GT(rejected, 100u); // both outcomes of the draws occur
}
