// Analytic shapes through the Embree scene: hit distances, normals, uv,
// robustness for large/far spheres, instance transforms, and the sphere's
// visible-cone sampling (chi^2 and analytic irradiance); meshes' flat-normal test.
#include "mvpt/render/shapes/instance.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

using namespace mvpt;

namespace {

std::unique_ptr<Scene> load(const std::string &shapes) {
    std::string xml = R"(<scene version="3.0.0"><sensor type="perspective"/>)" + shapes + "</scene>";
    return load_scene_string(xml, ".");
}

SurfaceInteraction hit(const Scene &s, Point3f o, Vec3f d, bool expect = true) {
    SurfaceInteraction si;
    bool h = s.intersect(Ray{o, normalize(d)}, si);
    EXPECT_EQ(h, expect) << o.x << "," << o.y << "," << o.z;
    return si;
}

} // namespace

TEST(AnalyticShapes, SphereHitNormalUv) {
    auto s = load(R"(<shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="2"/></shape>)");
    SurfaceInteraction si = hit(*s, {1, 2, 10}, {0, 0, -1});
    EXPECT_NEAR(si.t, 5.f, 1e-5f);
    EXPECT_NEAR(si.n.z, 1.f, 1e-6f);
    // Mitsuba's parameterisation: u = phi / 2pi, v = theta / pi with theta from +z.
    EXPECT_NEAR(si.uv.y, 0.f, 1e-5f);
    si = hit(*s, {10, 2, 3}, {-1, 0, 0});
    EXPECT_NEAR(si.uv.x, 0.f, 1e-5f);
    EXPECT_NEAR(si.uv.y, 0.5f, 1e-5f);
    si = hit(*s, {1, 10, 3}, {0, -1, 0});
    EXPECT_NEAR(si.uv.x, 0.25f, 1e-5f);
    // From inside: the far side, normal still outward.
    si = hit(*s, {1, 2, 3}, {0, 0, 1});
    EXPECT_NEAR(si.t, 2.f, 1e-5f);
    EXPECT_NEAR(si.n.z, 1.f, 1e-6f);
    hit(*s, {5, 5, 10}, {0, 0, -1}, false);
}

TEST(AnalyticShapes, FarAndLargeSpheresHaveNoSelfIntersection) {
    // A small sphere far away and a huge sphere: re-spawned rays must not hit
    // the surface they leave, and rays crossing the inside must reach the far side.
    for (auto [c, r] : {std::pair{Vec3f(1e4f, 0, 0), 0.5f}, std::pair{Vec3f(0, 0, 3e4f), 2e4f},
                        std::pair{Vec3f(-3e3f, 2e3f, 1e3f), 1e3f}}) {
        auto s = load("<shape type=\"sphere\"><point name=\"center\" x=\"" + std::to_string(c.x) + "\" y=\"" +
                      std::to_string(c.y) + "\" z=\"" + std::to_string(c.z) + "\"/><float name=\"radius\" value=\"" +
                      std::to_string(r) + "\"/></shape>");
        std::mt19937 rng(1);
        std::uniform_real_distribution<float> u(-1.f, 1.f);
        int crossings = 0;
        for (int i = 0; i < 200; ++i) {
            Vec3f target = c + normalize(Vec3f(u(rng), u(rng), u(rng))) * (0.9f * r);
            SurfaceInteraction si;
            ASSERT_TRUE(s->intersect(Ray{Point3f(0.f), normalize(target)}, si));
            EXPECT_NEAR(norm(si.p - c), r, 2e-6f * (norm(c) + r));
            // Leaving outwards (reflection): no hit at all.
            Vec3f out = normalize(si.n + Vec3f(u(rng), u(rng), u(rng)) * 0.5f);
            if (dot(out, si.n) > 0.05f) {
                SurfaceInteraction si2;
                EXPECT_FALSE(s->intersect(si.spawn_ray(out), si2)) << "self-intersection at sphere " << i;
            }
            // Entering (refraction): the exit point lies on the far side.
            Vec3f in = normalize(target - si.p);
            SurfaceInteraction si3;
            ASSERT_TRUE(s->intersect(si.spawn_ray(in), si3));
            EXPECT_GT(si3.t, 1e-3f * r);
            ++crossings;
        }
        EXPECT_EQ(crossings, 200);
    }
}

TEST(AnalyticShapes, DiskAndCylinder) {
    auto s = load(R"(<shape type="disk"><transform name="to_world"><scale value="2"/><translate z="-1"/></transform></shape>
                     <shape type="cylinder"><point name="p0" x="5" y="0" z="0"/><point name="p1" x="5" y="0" z="4"/>
                       <float name="radius" value="0.5"/></shape>)");
    SurfaceInteraction si = hit(*s, {1, 1, 5}, {0, 0, -1});
    EXPECT_NEAR(si.t, 6.f, 1e-5f);
    EXPECT_NEAR(si.n.z, 1.f, 1e-6f);
    EXPECT_NEAR(si.uv.x, std::sqrt(2.f) / 2.f, 1e-5f); // (r, phi / 2pi)
    EXPECT_NEAR(si.uv.y, 0.125f, 1e-5f);
    hit(*s, {1.5f, 1.5f, 5}, {0, 0, -1}, false);         // outside the radius
    si = hit(*s, {5, -10, 1}, {0, 1, 0});                 // cylinder side, a quarter up
    EXPECT_NEAR(si.t, 9.5f, 1e-5f);
    EXPECT_NEAR(si.n.y, -1.f, 1e-5f);
    EXPECT_NEAR(si.uv.y, 0.25f, 1e-5f);
    si = hit(*s, {5, 0, -3}, {0, 0.1f, 1});               // open tube: enters through the end, hits inside
    EXPECT_GT(dot(si.n, Vec3f(0, 1, 0)), 0.9f);
    hit(*s, {5, -10, 4.5f}, {0, 1, 0}, false);            // above the end
}

TEST(Instances, AnimatedTransformMatchesEmbreeInterpolation) {
    auto s = load(R"(<shape type="sphere"><float name="radius" value="0.5"/>
      <animation name="to_world">
        <transform time="1"><translate x="-2"/></transform>
        <transform time="2"><scale value="2"/><rotate y="1" angle="120"/><translate x="2" y="1"/></transform>
        <transform time="3"><rotate z="1" angle="30"/><translate x="0" y="3"/></transform>
      </animation></shape>)");
    auto *inst = dynamic_cast<const Instance *>(s->shapes().at(0).get());
    ASSERT_NE(inst, nullptr);
    for (float t : {0.f, 1.f, 1.3f, 1.5f, 2.f, 2.7f, 3.f, 4.f}) {
        Point3f c = inst->transform_at(t).point(Point3f(0.f));
        SurfaceInteraction si;
        // Ray through the predicted centre from +z must hit the sphere at the predicted time.
        Ray r{c + Vec3f(0, 0, 10), {0, 0, -1}};
        r.time = t;
        ASSERT_TRUE(s->intersect(r, si)) << t;
        EXPECT_NEAR(norm(si.p - c), 0.5f * norm(inst->transform_at(t).vector({1, 0, 0})), 1e-4f) << t;
    }
    // Hold semantics and key poses.
    EXPECT_NEAR(inst->transform_at(0.f).point(Point3f(0.f)).x, -2.f, 1e-5f);
    EXPECT_NEAR(inst->transform_at(2.f).point(Point3f(0.f)).x, 2.f, 1e-5f);
    EXPECT_NEAR(inst->transform_at(9.f).point(Point3f(0.f)).y, 3.f, 1e-5f);
    // Rotation interpolated by slerp: halfway between 0 and 120 degrees about y is 60 degrees.
    Transform half = inst->transform_at(1.5f);
    Vec3f x = normalize(half.vector({1, 0, 0}));
    EXPECT_NEAR(x.x, std::cos(deg_to_rad(60.f)), 1e-4f);
    EXPECT_NEAR(x.z, -std::sin(deg_to_rad(60.f)), 1e-4f);
    // Scale and translation interpolated linearly: 1.5 and (0, 0.5, 0).
    EXPECT_NEAR(norm(half.vector({0, 1, 0})), 1.5f, 1e-4f);
    Point3f o = half.point(Point3f(0.f));
    EXPECT_NEAR(o.x, 0.f, 1e-4f);
    EXPECT_NEAR(o.y, 0.5f, 1e-4f);
}

TEST(Instances, ShapeGroupHitsResolveTheInnerShape) {
    auto s = load(R"(<shape type="shapegroup" id="g">
        <shape type="sphere" id="ball"><float name="radius" value="1"/></shape>
        <shape type="rectangle" id="plane"><transform name="to_world"><translate z="-3"/></transform></shape></shape>
      <shape type="instance"><ref id="g"/><transform name="to_world"><scale value="2"/><translate x="10"/></transform></shape>
      <shape type="instance"><ref id="g"/><transform name="to_world"><rotate x="1" angle="90"/></transform></shape>)");
    SurfaceInteraction si = hit(*s, {10, 0, 10}, {0, 0, -1});
    EXPECT_EQ(si.shape->id, "ball");
    EXPECT_NEAR(si.t, 8.f, 1e-4f);
    EXPECT_NEAR(si.n.z, 1.f, 1e-5f);
    si = hit(*s, {11, 1, 10}, {0, 0, -1}); // within the scaled ball's radius 2
    EXPECT_EQ(si.shape->id, "ball");
    si = hit(*s, {11.9f, 1.9f, 10}, {0, 0, -1}); // outside the ball, inside the scaled plane [8, 12]^2
    EXPECT_EQ(si.shape->id, "plane");
    EXPECT_EQ(si.shape->id, "plane");
    EXPECT_NEAR(si.p.z, -6.f, 1e-4f);
    // Instance rotated 90 degrees about x: the plane z = -3 moves to y = 3.
    si = hit(*s, {0.5f, 10, 0.5f}, {0, -1, 0});
    EXPECT_EQ(si.shape->id, "plane");
    si = hit(*s, {0.5f, -10, 0.5f}, {0, 1, 0});
    EXPECT_EQ(si.shape->id, "ball");
    EXPECT_NEAR(norm(si.p), 1.f, 1e-5f);
    si = hit(*s, {0.5f, -10, 0.9f}, {0, 1, 0});
    EXPECT_EQ(si.shape->id, "plane");
    EXPECT_NEAR(si.p.y, 3.f, 1e-4f);
    EXPECT_NEAR(std::abs(si.n.y), 1.f, 1e-5f);
}

// ---------------------------------------------------------------- sphere light sampling

namespace {
const Shape &emitting_sphere(const Scene &s) { return *s.lights().at(0)->shape(); }
} // namespace

TEST(SphereSampling, VisibleConeIsUniformChi2) {
    auto s = load(R"(<shape type="sphere"><point name="center" x="0.3" y="-0.2" z="4"/><float name="radius" value="1.5"/>
                       <emitter type="area"/></shape>)");
    const Shape &sphere = emitting_sphere(*s);
    Point3f ref(0.f), c(0.3f, -0.2f, 4.f);
    float cos_max = std::sqrt(1.f - sqr(1.5f / norm(c)));
    Frame f(normalize(c));
    // Equal-probability cells for a uniform cone: 12 bins in (1 - cos) / (1 - cos_max), 12 in phi.
    const int nb = 12, n = 144000;
    std::vector<double> counts(nb * nb, 0.0);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    for (int i = 0; i < n; ++i) {
        auto [ss, pdf] = sphere.sample_solid_angle(ref, {u01(rng), u01(rng)});
        Vec3f d = f.to_local(normalize(ss.p - ref));
        // pdf_solid_angle agrees with the density returned by sampling.
        SurfaceInteraction si;
        si.p = ss.p;
        si.n = ss.n;
        ASSERT_NEAR(sphere.pdf_solid_angle(ref, si), pdf, 1e-3f * pdf);
        ASSERT_NEAR(pdf, 1.f / (2.f * Pi * (1.f - cos_max)), 1e-3f * pdf);
        // The point is on the sphere and faces the reference point.
        ASSERT_NEAR(norm(ss.p - c), 1.5f, 1e-4f);
        ASSERT_LT(dot(ss.n, ss.p - ref), 0.f);
        float a = std::clamp((1.f - d.z) / (1.f - cos_max), 0.f, 0.99999f);
        float phi = std::atan2(d.y, d.x);
        if (phi < 0) phi += 2 * Pi;
        counts[size_t(a * nb) * nb + std::min(nb - 1, int(phi / (2 * Pi) * nb))] += 1;
    }
    double expected = double(n) / (nb * nb), chi2 = 0;
    for (double c_ : counts) chi2 += sqr(float(c_ - expected)) / expected;
    // chi^2 with 143 dof: p = 1e-4 critical value is about 215.
    EXPECT_LT(chi2, 215.0);
}

TEST(SphereSampling, IrradianceMatchesAnalyticValue) {
    // A sphere of radius R at distance D, fully above the horizon of a surface
    // whose normal makes angle beta with the sphere's direction: E = pi sin^2(alpha) cos(beta) for L = 1.
    auto s = load(R"(<shape type="sphere"><point name="center" x="0" y="1.5" z="2"/><float name="radius" value="0.8"/>
                       <emitter type="area"/></shape>)");
    const Shape &sphere = emitting_sphere(*s);
    Vec3f c(0, 1.5f, 2), n(0, 0, 1);
    float sin2 = sqr(0.8f) / squared_norm(c), cos_beta = dot(normalize(c), n);
    double exact = Pi * sin2 * cos_beta, sum = 0, sum2 = 0;
    const int N = 200000;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u01(0.f, 1.f);
    for (int i = 0; i < N; ++i) {
        auto [ss, pdf] = sphere.sample_solid_angle(Point3f(0.f), {u01(rng), u01(rng)});
        double v = std::max(0.f, dot(normalize(ss.p), n)) / pdf;
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / N, se = std::sqrt((sum2 / N - mean * mean) / N);
    EXPECT_LT(std::abs(mean - exact), 4.5 * se + 1e-6) << mean << " vs " << exact;

    // From inside: area sampling; the solid angle of the whole sphere is 4 pi.
    double omega = 0;
    for (int i = 0; i < N; ++i) {
        auto [ss, pdf] = sphere.sample_solid_angle(Point3f(0.1f, 1.4f, 2.2f), {u01(rng), u01(rng)});
        omega += 1.0 / pdf;
    }
    EXPECT_NEAR(omega / N, 4 * Pi, 0.02 * 4 * Pi);
}

// A triangle whose vertex normals agree to within 1e-6 is shaded with its first vertex
// normal (a constant frame); one whose normals differ more is interpolated.
TEST(MeshShading, NearlyEqualVertexNormalsCountAsFlat) {
    namespace fs = std::filesystem;
    auto shading_normal_at_centroid = [](const std::string &name, float nx) {
        fs::path dir = fs::temp_directory_path() / "mvpt_shape_tests";
        fs::create_directories(dir);
        fs::path ply = dir / name;
        std::ofstream(ply) << "ply\nformat ascii 1.0\nelement vertex 3\n"
                              "property float x\nproperty float y\nproperty float z\n"
                              "property float nx\nproperty float ny\nproperty float nz\n"
                              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                              "0 0 0 0 0 1\n1 0 0 " << nx << " 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
        auto s = load(R"(<shape type="ply"><string name="filename" value=")" + ply.string() + R"("/></shape>)");
        return hit(*s, {1.f / 3.f, 1.f / 3.f, 1.f}, {0, 0, -1}).sh_frame.n;
    };
    // 4e-7 apart: the first vertex's normal exactly (interpolation would give x = 4e-7 / 3).
    Normal3f flat = shading_normal_at_centroid("near_flat.ply", 4e-7f);
    EXPECT_EQ(flat.x, 0.f);
    EXPECT_EQ(flat.z, 1.f);
    // 3e-3 apart (a warped quad, as cbox's red wall): interpolated.
    Normal3f smooth = shading_normal_at_centroid("smooth.ply", 3e-3f);
    EXPECT_NEAR(smooth.x, 1e-3f, 1e-5f);
}
