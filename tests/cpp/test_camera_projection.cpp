// The camera projection API of multi-view path tracing (docs/multiview-path-tracing.md
// §2–§4) and animated sensors: project() inverts generate_ray(), the Jacobian of the
// shift x_l -> y -> x_k equals G_k(y) / G_l(y) (finite differences), and G integrates
// to the film area of a surface patch. Cameras differ in fov, fov_axis, resolution and
// lens radius; two of them move during the shutter.
#include "mvpt/core/warp.h"
#include "mvpt/integrators/multiview/mv_candidates.h"
#include "mvpt/render/camera.h"
#include "mvpt/render/camera_projection.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

using namespace mvpt;

namespace {

const char *CameraXml = R"(
  <sensor type="perspective" id="pin_a"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0.3,1,6" target="0,0.2,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film></sensor>
  <sensor type="perspective" id="pin_b"><float name="fov" value="65"/><string name="fov_axis" value="y"/>
    <transform name="to_world"><lookat origin="3,2,5" target="0.2,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="80"/><integer name="height" value="96"/></film></sensor>
  <sensor type="thinlens" id="lens_c"><float name="fov" value="35"/>
    <float name="aperture_radius" value="0.2"/><float name="focus_distance" value="5"/>
    <transform name="to_world"><lookat origin="-2,1.5,5.5" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="50"/><integer name="height" value="40"/></film></sensor>
  <sensor type="thinlens" id="lens_d"><float name="fov" value="50"/><string name="fov_axis" value="diagonal"/>
    <float name="aperture_radius" value="0.05"/><float name="focus_distance" value="9"/>
    <transform name="to_world"><lookat origin="1,-1,7" target="0,0.3,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="96"/><integer name="height" value="64"/></film></sensor>
  <sensor type="perspective" id="moving_e"><float name="fov" value="45"/>
    <float name="shutter_open" value="0"/><float name="shutter_close" value="1"/>
    <animation name="to_world">
      <transform time="0"><lookat origin="-3,1,5" target="0,0,0" up="0,1,0"/></transform>
      <transform time="1"><lookat origin="2,2,6" target="0.5,0.2,0" up="0,1,0"/></transform>
    </animation>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film></sensor>
  <sensor type="thinlens" id="moving_f"><float name="fov" value="40"/>
    <float name="aperture_radius" value="0.15"/><float name="focus_distance" value="6"/>
    <float name="shutter_open" value="0.2"/><float name="shutter_close" value="0.8"/>
    <animation name="to_world">
      <transform time="0"><rotate y="1" angle="170"/><translate x="-1" y="0.5" z="6"/></transform>
      <transform time="0.5"><rotate x="1" angle="8"/><rotate y="1" angle="185"/><translate x="0" y="1" z="6.5"/></transform>
      <transform time="1"><rotate y="1" angle="195"/><translate x="1.5" y="0.8" z="6"/></transform>
    </animation>
    <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="64"/></film></sensor>
  <sensor type="perspective" id="offaxis_g"><float name="fov" value="42"/>
    <float name="principal_point_offset_x" value="0.17"/><float name="principal_point_offset_y" value="-0.11"/>
    <transform name="to_world"><lookat origin="0.8,0.6,6" target="0.3,0.1,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="72"/><integer name="height" value="40"/></film></sensor>
  <sensor type="thinlens" id="offaxis_lens_h"><float name="fov" value="38"/><string name="fov_axis" value="y"/>
    <float name="principal_point_offset_x" value="-0.09"/><float name="principal_point_offset_y" value="0.13"/>
    <float name="aperture_radius" value="0.12"/><float name="focus_distance" value="6"/>
    <transform name="to_world"><lookat origin="-1.2,0.4,6.2" target="-0.2,0.2,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="56"/><integer name="height" value="64"/></film></sensor>)";

std::unique_ptr<Scene> load(const std::string &body) {
    return load_scene_string("<scene version=\"3.0.0\">" + body + "</scene>", ".");
}

struct Rng {
    std::mt19937 gen;
    std::uniform_real_distribution<float> u{0.f, 1.f};
    explicit Rng(uint32_t seed) : gen(seed) {}
    float next() { return u(gen); }
    Vec2f next_2d() { return {next(), next()}; }
};

/// A test surface: its hit along a ray and its normal there.
struct Surface {
    bool sphere;
    Point3f c;   ///< plane point / sphere centre
    Vec3f n;     ///< plane normal
    float r = 0; ///< sphere radius

    std::optional<std::pair<Point3f, Normal3f>> hit(const Ray &ray) const {
        if (!sphere) {
            float dn = dot(ray.d, n);
            if (std::abs(dn) < 1e-6f) return {};
            float t = dot(c - ray.o, n) / dn;
            if (!(t > 0.f)) return {};
            return std::pair{ray.at(t), n};
        }
        // Nearest positive root of |o + t d - c|^2 = r^2 (d unit), in double.
        double ox = ray.o.x - c.x, oy = ray.o.y - c.y, oz = ray.o.z - c.z;
        double b = ox * ray.d.x + oy * ray.d.y + oz * ray.d.z, cc = ox * ox + oy * oy + oz * oz - double(r) * r;
        double disc = b * b - cc;
        if (disc < 0) return {};
        double t = -b - std::sqrt(disc);
        if (t <= 0) return {};
        Point3f p(float(ray.o.x + t * ray.d.x), float(ray.o.y + t * ray.d.y), float(ray.o.z + t * ray.d.z));
        return std::pair{p, normalize(p - c)};
    }
};

const Surface Plane{false, {0.f, 0.f, 0.f}, normalize(Vec3f(0.2f, 0.3f, 1.f))};
const Surface Ball{true, {0.f, 0.f, -1.5f}, {}, 2.5f};

float shoelace(const Vec2f *p, int n) {
    double a = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2f &q = p[i], &r = p[(i + 1) % n];
        a += double(q.x) * r.y - double(r.x) * q.y;
    }
    return float(std::abs(a) * 0.5);
}

} // namespace

TEST(CameraProjection, FilmContainsUsesTheCropWindow) {
    auto s = load(R"(<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="64"/>
        <integer name="height" value="48"/><integer name="crop_offset_x" value="8"/><integer name="crop_offset_y" value="4"/>
        <integer name="crop_width" value="16"/><integer name="crop_height" value="20"/></film></sensor>)");
    const FilmDesc &f = s->cameras()[0]->film;
    EXPECT_TRUE(f.contains({8.f, 4.f}));
    EXPECT_TRUE(f.contains({23.99f, 23.99f}));
    EXPECT_FALSE(f.contains({24.f, 10.f}));
    EXPECT_FALSE(f.contains({7.99f, 10.f}));
    EXPECT_FALSE(f.contains({10.f, 24.f}));
    EXPECT_FALSE(f.contains({10.f, 3.99f}));
}

TEST(CameraProjection, ProjectInvertsGenerateRay) {
    // (a) film position -> ray -> point at a random distance -> project back (design doc §3).
    auto s = load(CameraXml);
    Rng rng(1);
    for (const auto &cam : s->cameras()) {
        float worst = 0.f;
        for (int i = 0; i < 4000; ++i) {
            Vec2f x(rng.next() * cam->film.width, rng.next() * cam->film.height);
            Vec2f xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
            float t = -0.2f + 1.4f * rng.next(); // also outside the keyframe range (end poses hold)
            Ray r = cam->generate_ray(x, xi, t);
            Point3f y = r.at(1.f + 39.f * rng.next());
            Vec2f back;
            ASSERT_TRUE(cam->project(y, t, xi, &back)) << cam->id;
            worst = std::max({worst, std::abs(back.x - x.x), std::abs(back.y - x.y)});
            // The ray starts at the lens point.
            Point3f u = cam->lens_point(t, xi);
            ASSERT_LT(norm(u - r.o), 1e-5f) << cam->id;
        }
        EXPECT_LT(worst, 1e-4f) << cam->id;
    }
}

TEST(CameraProjection, PrincipalPointOffsetShiftsTheImage) {
    // Mitsuba's principal_point_offset_x/_y (fractions of the film size) are added to the film
    // position before the near-plane map: the ray through film position x of the off-axis camera
    // equals the ray through x + (ppo_x W, ppo_y H) of the same camera without offset, and the
    // optical axis lands at ((0.5 - ppo_x) W, (0.5 - ppo_y) H).
    for (const char *type : {"perspective", "thinlens"}) {
        std::string lens = std::string(type) == "thinlens"
                               ? "<float name=\"aperture_radius\" value=\"0.1\"/><float name=\"focus_distance\" value=\"4\"/>"
                               : "";
        std::string pose = "<transform name=\"to_world\"><lookat origin=\"1,2,3\" target=\"0,0,0\" up=\"0,1,0\"/></transform>"
                           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"30\"/></film>";
        auto s = load("<sensor type=\"" + std::string(type) + "\">" + lens + pose +
                      "<float name=\"principal_point_offset_x\" value=\"0.25\"/><float name=\"principal_point_offset_y\" value=\"-0.1\"/></sensor>"
                      "<sensor type=\"" + std::string(type) + "\">" + lens + pose + "</sensor>");
        const Camera &off = *s->cameras()[0], &on = *s->cameras()[1];
        Rng rng(9);
        for (int i = 0; i < 100; ++i) {
            Vec2f x(rng.next() * 40.f, rng.next() * 30.f), xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
            Ray a = off.generate_ray(x, xi, 0.f), b = on.generate_ray(x + Vec2f(0.25f * 40.f, -0.1f * 30.f), xi, 0.f);
            EXPECT_LT(norm(a.o - b.o), 1e-6f) << type;
            EXPECT_LT(norm(a.d - b.d), 1e-6f) << type;
        }
        Ray axis = on.generate_ray({20.f, 15.f}, {0.f, 0.f}, 0.f);
        Vec2f x;
        ASSERT_TRUE(off.project(axis.at(2.f), 0.f, {0.f, 0.f}, &x));
        EXPECT_NEAR(x.x, (0.5f - 0.25f) * 40.f, 1e-4f) << type;
        EXPECT_NEAR(x.y, (0.5f + 0.1f) * 30.f, 1e-4f) << type;
    }
}

TEST(CameraProjection, ProjectRejectsPointsOutsideTheDepthRange) {
    auto s = load(R"(<sensor type="thinlens"><float name="near_clip" value="0.5"/><float name="far_clip" value="20"/>
        <float name="aperture_radius" value="0.1"/><float name="focus_distance" value="4"/>
        <transform name="to_world"><lookat origin="1,2,3" target="0,0,0" up="0,1,0"/></transform></sensor>)");
    const Camera &cam = *s->cameras()[0];
    Vec2f centre(cam.film.width * 0.5f, cam.film.height * 0.5f), x;
    Ray r = cam.generate_ray(centre, {0.f, 0.f}, 0.f); // along the optical axis: distance = depth
    EXPECT_TRUE(cam.project(r.at(0.6f), 0.f, {0.3f, -0.4f}, &x));
    EXPECT_TRUE(cam.project(r.at(19.9f), 0.f, {0.3f, -0.4f}, &x));
    EXPECT_FALSE(cam.project(r.at(0.4f), 0.f, {0.3f, -0.4f}, &x));
    EXPECT_FALSE(cam.project(r.at(20.1f), 0.f, {0.3f, -0.4f}, &x));
    EXPECT_FALSE(cam.project(r.at(-3.f), 0.f, {0.3f, -0.4f}, &x));
    EXPECT_EQ(cam.film_density(r.at(-3.f), r.d, 0.f, {0.f, 0.f}), 0.f);
}

TEST(CameraProjection, ShiftJacobianEqualsFilmDensityRatio) {
    // (b) |dx_k/dx_l| of x_l -> y (plane or sphere hit) -> x_k by central differences, with
    // t and xi fixed, against G_k(y) / G_l(y) (design doc §4).
    auto s = load(CameraXml);
    const auto &cams = s->cameras();
    auto cam = [&](const char *id) {
        for (auto &c : cams)
            if (c->id == id) return c.get();
        throw std::runtime_error("no camera");
    };
    std::vector<std::pair<const Camera *, const Camera *>> pairs = {
        {cam("pin_a"), cam("pin_b")},    {cam("pin_b"), cam("pin_a")},   {cam("lens_c"), cam("lens_d")},
        {cam("lens_d"), cam("lens_c")},  {cam("pin_a"), cam("lens_c")},  {cam("lens_d"), cam("pin_b")},
        {cam("moving_e"), cam("moving_f")}, {cam("moving_f"), cam("lens_c")}, {cam("pin_a"), cam("moving_e")},
        {cam("offaxis_g"), cam("pin_a")}, {cam("lens_c"), cam("offaxis_lens_h")}, {cam("offaxis_lens_h"), cam("offaxis_g")}};
    Rng rng(2);
    // Step (pixels): smaller steps let float rounding of the hit point dominate, larger ones
    // the O(h^4) remainder; at 0.4 both stay below 1e-3 relative (worst seen: 3e-4).
    const float h = 0.4f;
    for (auto [l, k] : pairs)
        for (const Surface *surf : {&Plane, &Ball}) {
            int valid = 0;
            float worst = 0.f;
            for (int i = 0; i < 800; ++i) {
                Vec2f x(1.f + rng.next() * (l->film.width - 2.f), 1.f + rng.next() * (l->film.height - 2.f));
                Vec2f xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
                float t = rng.next();
                auto shift = [&](Vec2f xl, Point3f *y, Normal3f *n) -> std::optional<Vec2f> {
                    auto hit = surf->hit(l->generate_ray(xl, xi, t));
                    if (!hit) return {};
                    Vec2f xk;
                    if (!k->project(hit->first, t, xi, &xk)) return {};
                    if (y) { *y = hit->first; *n = hit->second; }
                    return xk;
                };
                Point3f y;
                Normal3f n;
                if (!shift(x, &y, &n)) continue;
                // Grazing views amplify float rounding (of the hit along the ray) by 1 / cos;
                // near grazing the finite differences would measure rounding, not G.
                Vec3f to_l = normalize(l->lens_point(t, xi) - y), to_k = normalize(k->lens_point(t, xi) - y);
                if (absdot(n, to_l) < 0.3f || absdot(n, to_k) < 0.3f) continue;
                // Central differences with Richardson extrapolation (error O(h^4)): the sphere's
                // curvature makes the O(h^2) term visible near its silhouette.
                auto derivative = [&](Vec2f dir, float step) -> std::optional<Vec2f> {
                    auto p = shift(x + dir * step, nullptr, nullptr), m = shift(x - dir * step, nullptr, nullptr);
                    if (!p || !m) return {};
                    return (*p - *m) * (0.5f / step);
                };
                auto dx1 = derivative({1.f, 0.f}, h), dx2 = derivative({1.f, 0.f}, 0.5f * h);
                auto dy1 = derivative({0.f, 1.f}, h), dy2 = derivative({0.f, 1.f}, 0.5f * h);
                if (!dx1 || !dx2 || !dy1 || !dy2) continue;
                Vec2f dx = (*dx2 * 4.f - *dx1) * (1.f / 3.f), dy = (*dy2 * 4.f - *dy1) * (1.f / 3.f);
                float jac = std::abs(dx.x * dy.y - dx.y * dy.x);
                float ratio = k->film_density(y, n, t, xi) / l->film_density(y, n, t, xi);
                ASSERT_GT(ratio, 0.f);
                worst = std::max(worst, std::abs(jac / ratio - 1.f));
                ++valid;
            }
            EXPECT_GT(valid, 50) << l->id << " -> " << k->id << (surf->sphere ? " sphere" : " plane");
            EXPECT_LT(worst, 1e-3f) << l->id << " -> " << k->id << (surf->sphere ? " sphere" : " plane");
        }
}

TEST(CameraProjection, FilmDensityIntegratesToProjectedArea) {
    // (c) The film area covered by a planar patch, seen from a fixed lens point, equals the
    // integral of G over the patch. With the lens point fixed the map is a perspective
    // projection (straight lines stay straight), so the image of a square is the
    // quadrilateral of its projected corners; the integral uses a midpoint rule.
    auto s = load(CameraXml);
    Rng rng(3);
    const Frame fr(Plane.n);
    for (const auto &cam : s->cameras())
        for (int trial = 0; trial < 4; ++trial) {
            float t = rng.next();
            Vec2f xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
            Vec2f x(cam->film.width * (0.3f + 0.4f * rng.next()), cam->film.height * (0.3f + 0.4f * rng.next()));
            auto hit = Plane.hit(cam->generate_ray(x, xi, t));
            ASSERT_TRUE(hit) << cam->id;
            Point3f c = hit->first;
            const float a = 0.2f; // half side of the square patch (world units)
            Vec2f corners[4];
            const float sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
            for (int j = 0; j < 4; ++j)
                ASSERT_TRUE(cam->project(c + fr.s * (a * sx[j]) + fr.t * (a * sy[j]), t, xi, &corners[j])) << cam->id;
            double area_film = shoelace(corners, 4);
            const int N = 200;
            double integral = 0;
            float cell = 2.f * a / N;
            for (int i = 0; i < N; ++i)
                for (int j = 0; j < N; ++j) {
                    Point3f y = c + fr.s * (-a + (i + 0.5f) * cell) + fr.t * (-a + (j + 0.5f) * cell);
                    integral += double(cam->film_density(y, Plane.n, t, xi)) * cell * cell;
                }
            EXPECT_NEAR(integral / area_film, 1.0, 1e-4) << cam->id << " area " << area_film;
            // A pinhole's G does not depend on xi; a thin lens's does.
            if (cam->lens_radius() == 0.f)
                EXPECT_EQ(cam->film_density(c, Plane.n, t, xi), cam->film_density(c, Plane.n, t, {0.f, 0.f}));
        }
}

TEST(AnimatedSensor, PoseInterpolatesAndHoldsAtTheEnds) {
    // Keys: rotation 0 -> 90 degrees about y and a translation; at t = 0.25 the pose equals the
    // static camera rotated by 22.5 degrees (slerp of a single-axis rotation is linear in angle)
    // and translated by the interpolated offset. Outside [0, 1] the end poses hold.
    auto static_cam = [](float angle, float tx) {
        return "<sensor type=\"thinlens\"><float name=\"aperture_radius\" value=\"0.1\"/><float name=\"focus_distance\" value=\"3\"/>"
               "<transform name=\"to_world\"><rotate y=\"1\" angle=\"" + std::to_string(angle) + "\"/><translate x=\"" +
               std::to_string(tx) + "\" z=\"-4\"/></transform></sensor>";
    };
    auto s = load(R"(<sensor type="thinlens"><float name="aperture_radius" value="0.1"/><float name="focus_distance" value="3"/>
        <animation name="to_world">
          <transform time="0"><rotate y="1" angle="0"/><translate x="-2" z="-4"/></transform>
          <transform time="1"><rotate y="1" angle="90"/><translate x="2" z="-4"/></transform>
        </animation></sensor>)" + static_cam(22.5f, -1.f) + static_cam(0.f, -2.f) + static_cam(90.f, 2.f));
    const auto &c = s->cameras();
    ASSERT_TRUE(c[0]->is_animated());
    ASSERT_FALSE(c[1]->is_animated());
    Rng rng(4);
    for (auto [t, ref] : {std::pair{0.25f, 1}, std::pair{-0.5f, 2}, std::pair{0.f, 2}, std::pair{1.f, 3}, std::pair{7.f, 3}})
        for (int i = 0; i < 50; ++i) {
            Vec2f x(rng.next() * c[0]->film.width, rng.next() * c[0]->film.height);
            Vec2f xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
            Ray a = c[0]->generate_ray(x, xi, t), b = c[ref]->generate_ray(x, xi, 0.f);
            EXPECT_LT(norm(a.o - b.o), 1e-5f) << t;
            EXPECT_LT(norm(a.d - b.d), 1e-5f) << t;
            EXPECT_EQ(a.time, t);
        }
}

TEST(AnimatedSensor, ScaledKeyframeIsAnError) {
    try {
        load(R"(<sensor type="perspective"><animation name="to_world">
            <transform time="0"><translate x="1"/></transform>
            <transform time="1"><scale value="2"/><translate x="2"/></transform></animation></sensor>)");
        FAIL() << "expected a SceneError";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("keyframe at time 1"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("rigid"), std::string::npos) << e.what();
    }
}

TEST(CameraProjection, ShiftGeometryAgreesWithProjectLensPointAndFilmDensity) {
    // The one-pose-evaluation hot path of multi-view path tracing must equal the three
    // separate calls, and a shifted film point's own camera ray must hit y (design doc §3).
    auto s = load(CameraXml);
    Rng rng(5);
    for (const auto &cam : s->cameras()) {
        int checked = 0;
        for (int i = 0; i < 2000; ++i) {
            Vec2f x(rng.next() * cam->film.width, rng.next() * cam->film.height);
            Vec2f xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
            float t = rng.next();
            Ray r = cam->generate_ray(x, xi, t);
            auto h = Ball.hit(r);
            if (!h) continue;
            auto [y, n] = *h;
            ShiftGeometry geo;
            Vec2f film;
            bool ok = cam->shift_geometry(y, n, t, xi, &geo);
            ASSERT_EQ(ok, cam->project(y, t, xi, &film)) << cam->id;
            if (!ok) continue;
            EXPECT_NEAR(geo.film.x, film.x, 1e-3f) << cam->id;
            EXPECT_NEAR(geo.film.y, film.y, 1e-3f) << cam->id;
            EXPECT_LT(norm(geo.lens_point - cam->lens_point(t, xi)), 1e-5f) << cam->id;
            float g = cam->film_density(y, n, t, xi);
            EXPECT_NEAR(geo.density, g, 1e-4f * g) << cam->id;
            // The ray through the shifted film point with the same lens point hits y.
            Ray back = cam->generate_ray(geo.film, xi, t);
            auto h2 = Ball.hit(back);
            ASSERT_TRUE(h2.has_value()) << cam->id;
            EXPECT_LT(norm(h2->first - y), 1e-3f * (1.f + norm(y - back.o))) << cam->id;
            // visible_length reaches from y to the near clip plane of the ray.
            EXPECT_NEAR(geo.visible_length, norm(y - back.o) - back.tmin, 1e-3f * norm(y - back.o)) << cam->id;
            ++checked;
        }
        EXPECT_GT(checked, 100) << cam->id;
    }
}

TEST(CameraProjection, BatchOverStaticCamerasEqualsEachCamera) {
    // Multi-view path tracing shifts a sample to all static views at once from a structure of
    // arrays (shift_static_views, a vector loop); it must give each camera's own
    // shift_geometry, including the depth test, for pinholes and thin lenses alike.
    auto s = load(CameraXml);
    std::vector<const Camera *> cams;
    std::vector<CameraProjection> proj;
    std::vector<SampleWindow> films;
    for (const auto &cam : s->cameras())
        if (const CameraProjection *p = cam->static_projection()) {
            cams.push_back(cam.get());
            proj.push_back(*p);
            films.emplace_back(cam->film);
        }
    ASSERT_GE(cams.size(), 3u);
    ProjectionTable table(proj);
    FilmTable film_table(films, table.size());
    ViewShifts shifts;
    const ShiftBatch &batch = shifts.geo;
    Rng rng(9);
    int in_range = 0, out_of_range = 0;
    for (int i = 0; i < 2000; ++i) {
        // Points in front of, beside and behind the cameras.
        Point3f y(8.f * rng.next() - 4.f, 8.f * rng.next() - 4.f, 20.f * rng.next() - 8.f);
        Normal3f n = normalize(Vec3f(rng.next() - 0.5f, rng.next() - 0.5f, rng.next() - 0.5f));
        Vec2f xi = warp::square_to_uniform_disk_concentric(rng.next_2d());
        shift_static_views(table, film_table, MvVertex{y, n, 0.f, xi, 1.f}, shifts);
        for (size_t k = 0; k < cams.size(); ++k) {
            ShiftGeometry geo;
            bool ok = cams[k]->shift_geometry(y, n, 0.f, xi, &geo);
            ok = ok && geo.density > 0.f;
            ASSERT_EQ(!(shifts.status[k] & ShiftDepth), ok);
            (ok ? in_range : out_of_range)++;
            if (!ok) continue;
            EXPECT_FLOAT_EQ(batch.film_x[k], geo.film.x);
            EXPECT_FLOAT_EQ(batch.film_y[k], geo.film.y);
            EXPECT_FLOAT_EQ(batch.lens_x[k], geo.lens_point.x);
            EXPECT_FLOAT_EQ(batch.lens_y[k], geo.lens_point.y);
            EXPECT_FLOAT_EQ(batch.lens_z[k], geo.lens_point.z);
            EXPECT_FLOAT_EQ(batch.density[k], geo.density);
            EXPECT_FLOAT_EQ(batch.visible_length[k], geo.visible_length);
        }
    }
    EXPECT_GT(in_range, 1000);
    EXPECT_GT(out_of_range, 1000);
}
