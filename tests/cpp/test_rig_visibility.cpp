// Cells that see a static camera rig (accel/rig_visibility.*): a cell is declared unblocked
// only if Embree finds every segment from a vertex in it to any lens point of the rig (on the
// vertex's camera side) unblocked, and the cache answers the way a fresh evaluation does.
#include "mvpt/render/interaction.h"
#include "mvpt/accel/rig_visibility.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <random>

using namespace mvpt;

namespace {

// A floor (two big triangles), a sphere, a cube, a small tilted rectangle, a disk (a
// bounding-box occluder) and a fine sphere mesh of small triangles (not usable as keys).
const char *SceneXml = R"(<scene version="3.0.0">
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform></shape>
  <shape type="sphere"><point name="center" x="0.1" y="0.35" z="0"/><float name="radius" value="0.3"/></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.2"/><rotate y="1" angle="30"/>
    <translate x="-0.6" y="0.2" z="0.3"/></transform></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.3"/><rotate x="1" angle="50"/>
    <translate x="0.5" y="0.4" z="0.5"/></transform></shape>
  <shape type="disk"><transform name="to_world"><scale value="0.25"/><translate x="0.7" y="0.5" z="-0.4"/></transform></shape>
  <sensor type="perspective"><transform name="to_world"><lookat origin="0, 1, 3" target="0, 0.3, 0" up="0, 1, 0"/>
    </transform></sensor>
</scene>)";

/// A rig: a row or grid of lens squares (half-size `lens`, 0 for pinholes) around `centre`.
struct Rig {
    Point3f centre;
    std::vector<Point3f> corners; ///< what RigVisibility is given
    Vec3f right, up;
    float spacing, lens;
    int rows, cols;
    /// A random lens point of the rig (inside the hull of the corners).
    Point3f sample(std::mt19937 &rng) const {
        std::uniform_real_distribution<float> u(0.f, 1.f);
        const int r = int(rng() % uint32_t(rows)), c = int(rng() % uint32_t(cols));
        return centre + right * (spacing * float(c) + lens * (2.f * u(rng) - 1.f)) +
               up * (spacing * float(r) + lens * (2.f * u(rng) - 1.f));
    }
};

Rig make_rig(std::mt19937 &rng) {
    std::uniform_real_distribution<float> u(0.f, 1.f);
    Rig rig;
    rig.centre = Point3f(u(rng) * 4.f - 2.f, u(rng) * 2.f + 0.3f, u(rng) * 2.f + 1.5f);
    const Vec3f to = Point3f(0.f, 0.3f, 0.f) - rig.centre;
    rig.right = normalize(cross(to, Vec3f(0.f, 1.f, 0.f)));
    rig.up = normalize(cross(rig.right, to));
    rig.spacing = std::exp(-4.f * u(rng));
    rig.lens = rng() % 2 ? 0.f : 0.02f * u(rng);
    rig.cols = 2 + int(rng() % 6), rig.rows = rng() % 2 ? 1 : 1 + int(rng() % 4);
    for (int r = 0; r < rig.rows; ++r)
        for (int c = 0; c < rig.cols; ++c)
            for (float sx : {-1.f, 1.f})
                for (float sy : {-1.f, 1.f})
                    rig.corners.push_back(rig.centre + rig.right * (rig.spacing * float(c) + sx * rig.lens) +
                                          rig.up * (rig.spacing * float(r) + sy * rig.lens));
    return rig;
}

} // namespace

// Every vertex whose cell is declared unblocked sees every lens point on its camera side,
// for Embree segment by segment; the check covers both outcomes on keyed primitives.
TEST(RigVisibility, UnblockedCellsSeeTheWholeRig) {
    auto scene = load_scene_string(SceneXml, ".");
    scene->prepare_segment_culling();
    const OccluderBvh &bvh = *scene->occluder_bvh();
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int free = 0, kept = 0, blocked = 0, segments = 0;
    for (int trial = 0; trial < 150; ++trial) {
        const Rig rig = make_rig(rng);
        const RigVisibility vis(bvh, rig.corners, rig.right, 16 + int(rng() % 3) * 24);
        for (int s = 0; s < 400; ++s) {
            // A vertex seen from a lens point of the rig, as a camera ray finds it.
            const Point3f from = rig.sample(rng);
            const Vec3f d = normalize(Point3f(u(rng) * 2.4f - 1.2f, u(rng) * 0.8f, u(rng) * 2.4f - 1.2f) - from);
            SurfaceInteraction si;
            if (!scene->intersect(Ray{from, d, 0.f, Infinity, 0.f}, si)) continue;
            const Point3f o = si.offset_p(from - si.p);
            const bool unblocked = vis.unblocked(o, si.shape, si.prim);
            const size_t evaluated = vis.evaluated();
            ASSERT_EQ(unblocked, vis.unblocked(o, si.shape, si.prim)) << "the cache answers differently";
            ASSERT_EQ(vis.evaluated(), evaluated) << "a second lookup of the same cell is not served by the cache";
            bool any = false;
            for (int k = 0; k < 24; ++k) {
                const Point3f lens = rig.sample(rng);
                if (dot(si.n, lens - si.p) * dot(si.n, from - si.p) <= 0.f) continue; // §3 test 1 fails
                const Vec3f to = lens - o;
                const float dist = norm(to);
                const bool hit = scene->occluded(Ray{o, to / dist, 0.f, dist * (1.f - ShadowEpsilon), 0.f});
                ++segments;
                ASSERT_FALSE(unblocked && hit) << "trial " << trial << ", vertex " << s << ", lens point " << k;
                any |= hit;
            }
            (unblocked ? free : kept) += 1;
            blocked += any;
        }
    }
    EXPECT_GT(segments, 500000);
    EXPECT_GT(free, 15000);
    EXPECT_GT(blocked, 2500);
    EXPECT_GT(kept, blocked);
}

// Primitives map to occluders: a mesh's triangles in order, a sphere once, other shapes not.
TEST(RigVisibility, OccluderOfShapes) {
    auto scene = load_scene_string(SceneXml, ".");
    scene->prepare_segment_culling();
    const OccluderBvh &bvh = *scene->occluder_bvh();
    const auto &shapes = scene->shapes();
    ASSERT_EQ(shapes.size(), 5u);
    EXPECT_EQ(bvh.occluder_of(shapes[0].get(), 0), 0);
    EXPECT_EQ(bvh.occluder_of(shapes[0].get(), 1), 1);
    EXPECT_EQ(bvh.occluder_of(shapes[0].get(), 2), -1);
    EXPECT_EQ(bvh.occluder_of(shapes[2].get(), 11), 13); // the cube's 12 triangles follow the floor's 2
    EXPECT_EQ(bvh.occluder_of(shapes[3].get(), 0), 14);
    EXPECT_TRUE(bvh.is_sphere(bvh.occluder_of(shapes[1].get(), 0)));
    EXPECT_EQ(bvh.occluder_of(shapes[4].get(), 0), -1); // a disk is a bounding box
    double p[3][3], n[3], n_len;
    ASSERT_TRUE(bvh.triangle(0, p, n, &n_len));
    EXPECT_NEAR(std::abs(n[1]) / n_len, 1.0, 1e-12); // the floor is horizontal
}
