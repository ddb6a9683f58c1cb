// Culling of visibility-segment bundles (accel/segment_cull.*): a bundle is declared free of
// occluders only if Embree finds every one of its segments unblocked, the pyramid holds
// its segments, and the culling actually fires on the bundles multi-view sampling makes.
#include "mvpt/core/warp.h"
#include "mvpt/render/interaction.h"
#include "mvpt/loader/load_scene.h"
#include "mvpt/accel/segment_cull.h"

#include <gtest/gtest.h>

#include <random>

using namespace mvpt;

namespace {

// A floor at y = 0 (box sides at 0), a sphere, a cube, a disk and a cylinder (bounding-box
// occluders), and a tilted triangle mesh.
const char *CullSceneXml = R"(<scene version="3.0.0">
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"/></shape>
  <shape type="sphere"><point name="center" x="0.1" y="0.35" z="0"/><float name="radius" value="0.3"/></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.2"/><rotate y="1" angle="30"/>
    <translate x="-0.6" y="0.2" z="0.3"/></transform></shape>
  <shape type="disk"><transform name="to_world"><scale value="0.25"/><translate x="0.7" y="0.5" z="-0.4"/></transform></shape>
  <shape type="cylinder"><float name="radius" value="0.1"/><point name="p0" x="-0.3" y="0" z="-0.6"/>
    <point name="p1" x="-0.3" y="0.7" z="-0.6"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.3"/><rotate x="1" angle="50"/>
    <translate x="0.5" y="0.4" z="0.5"/></transform></shape>
  <sensor type="perspective"><transform name="to_world"><lookat origin="0, 1, 3" target="0, 0.3, 0" up="0, 1, 0"/>
    </transform></sensor>
</scene>)";

/// Segments as multi-view sampling traces them: from a hit y (offset origin) to a row or grid
/// of lens points around `centre`, each on the side of y's surface the first one is on; or,
/// with `in_space`, from a point anywhere among the shapes to lens points among them too.
struct Bundle {
    Point3f o;
    std::vector<float> dx, dy, dz, t_max;
    size_t n = 0;
};

bool make_bundle(const Scene &scene, std::mt19937 &rng, bool in_space, Bundle &b) {
    std::uniform_real_distribution<float> u(0.f, 1.f);
    Point3f centre(u(rng) * 4.f - 2.f, u(rng) * 2.f + 0.2f, u(rng) * 2.f + 1.5f);
    if (in_space) centre = Point3f(u(rng) * 2.4f - 1.2f, u(rng) * 1.2f, u(rng) * 2.4f - 1.2f);
    Vec3f to = Point3f(u(rng) - 0.5f, u(rng) * 0.6f, u(rng) - 0.5f) - centre;
    SurfaceInteraction si;
    if (in_space) { // a free point: no surface, every lens point is traced
        si.p = Point3f(u(rng) * 2.4f - 1.2f, u(rng) * 1.2f, u(rng) * 2.4f - 1.2f);
        to = si.p - centre;
        si.n = normalize(-to);
    } else if (!scene.intersect(Ray{centre, normalize(to), 0.f, Infinity, 0.f}, si)) {
        return false;
    }
    const float spacing = std::exp(-5.f * u(rng)); // from a tight light field to a wide rig
    const int cols = 1 + int(rng() % 7), rows = rng() % 2 ? 1 : 1 + int(rng() % 5);
    const Vec3f right = normalize(cross(to, Vec3f(0.f, 1.f, 0.f))), up = normalize(cross(right, to));
    std::vector<Point3f> lens;
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) lens.push_back(centre + right * (spacing * float(c)) + up * (spacing * float(r)));
    const float side = in_space ? 1.f : dot(si.n, lens[0] - si.p);
    b.o = in_space ? si.p : si.offset_p(lens[0] - si.p);
    b.n = 0;
    const size_t padded = (lens.size() + 7) / 8 * 8;
    b.dx.assign(padded, 0.f), b.dy.assign(padded, 0.f), b.dz.assign(padded, 1.f), b.t_max.assign(padded, -1.f);
    for (const Point3f &p : lens) {
        const Vec3f d = p - b.o;
        const float dist = norm(d);
        const size_t i = b.n++;
        b.dx[i] = d.x / dist, b.dy[i] = d.y / dist, b.dz[i] = d.z / dist;
        const bool facing = in_space || dot(si.n, p - si.p) * side > 0.f;
        b.t_max[i] = facing ? dist * (1.f - ShadowEpsilon) : -1.f;
    }
    return true;
}

} // namespace

// Every bundle the tree declares free is free for Embree, segment by segment, and
// occluded_segments (which uses the tree) equals one-ray queries.
TEST(SegmentCull, CulledBundlesAreUnblocked) {
    auto scene = load_scene_string(CullSceneXml, ".");
    scene->prepare_segment_culling();
    OccluderBvh bvh(scene->device(), scene->shapes());
    std::mt19937 rng(17);
    int culled = 0, kept = 0, blocked_bundles = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        Bundle b;
        if (!make_bundle(*scene, rng, trial % 2 == 1, b)) continue;
        SegmentBundle bundle;
        const Vec3f across(1.f, 0.f, 0.f);
        const bool built = bundle.build(b.o, across, b.dx.data(), b.dy.data(), b.dz.data(), b.t_max.data(), b.n);
        const bool free = built && !bvh.may_block(bundle);
        std::vector<uint8_t> blocked(b.n, 7);
        scene->occluded_segments(b.o, b.dx.data(), b.dy.data(), b.dz.data(), b.t_max.data(), b.n, 0.f, blocked.data(),
                                 across);
        bool any = false;
        for (size_t i = 0; i < b.n; ++i) {
            const bool expect =
                b.t_max[i] > 0.f && scene->occluded(Ray{b.o, Vec3f(b.dx[i], b.dy[i], b.dz[i]), 0.f, b.t_max[i], 0.f});
            ASSERT_EQ(bool(blocked[i]), expect) << "trial " << trial << ", segment " << i;
            ASSERT_FALSE(free && expect) << "a culled bundle has a blocked segment: trial " << trial << ", segment " << i;
            any |= expect;
        }
        (free ? culled : kept) += 1;
        blocked_bundles += any;
    }
    // The test covers both outcomes: most bundles are culled, and blocked ones exist.
    EXPECT_GT(culled, 7000);
    EXPECT_GT(blocked_bundles, 3000);
    EXPECT_GT(kept, blocked_bundles);
}

// The pyramid's half-spaces hold every point of every traced segment.
TEST(SegmentCull, BundleHoldsItsSegments) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    int built = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const Point3f o(u(rng) * 20.f - 10.f, u(rng) * 20.f - 10.f, u(rng) * 20.f - 10.f);
        const Vec3f axis = warp::square_to_uniform_sphere({u(rng), u(rng)});
        const float spread = std::exp(-6.f * u(rng));
        const size_t n = 1 + rng() % 30, padded = (n + 7) / 8 * 8;
        std::vector<float> dx(padded, 0.f), dy(padded, 0.f), dz(padded, 1.f), t_max(padded, -1.f);
        for (size_t i = 0; i < n; ++i) {
            const Vec3f d = normalize(axis + warp::square_to_uniform_sphere({u(rng), u(rng)}) * spread);
            dx[i] = d.x, dy[i] = d.y, dz[i] = d.z;
            t_max[i] = i % 5 == 2 ? -1.f : std::exp(6.f * u(rng) - 3.f);
        }
        SegmentBundle b;
        if (!b.build(o, warp::square_to_uniform_sphere({u(rng), u(rng)}), dx.data(), dy.data(), dz.data(),
                     t_max.data(), n))
            continue;
        ++built;
        for (size_t i = 0; i < n; ++i) {
            if (!(t_max[i] > 0.f)) continue;
            for (double s : {0.0, 1e-6, 0.5, 1.0}) {
                const double q[3] = {s * dx[i] * t_max[i], s * dy[i] * t_max[i], s * dz[i] * t_max[i]};
                for (int k = 0; k < 6; ++k) {
                    const double v = b.normal[k][0] * q[0] + b.normal[k][1] * q[1] + b.normal[k][2] * q[2];
                    ASSERT_LE(v, b.offset[k]) << "trial " << trial << ", segment " << i << ", plane " << k;
                }
                for (int c = 0; c < 3; ++c) {
                    ASSERT_GE(double(o[c]) + q[c], b.lo[c]);
                    ASSERT_LE(double(o[c]) + q[c], b.hi[c]);
                }
            }
        }
    }
    EXPECT_GT(built, 1200);
}
