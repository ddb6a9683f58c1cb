// Camera rigs and shots (loader/rig.h, loader/camera_path.h): the poses and frusta of every
// rig type, the shared focal plane of off-axis grids, per-frame shutters of path rigs, the
// --rig option, one clear error for each kind of bad input, and the control of a load
// (loader/load_control.h): a cancel flag stops it between elements and between the views a rig
// makes; a rig whose views' images cannot fit is refused before its views are made when every
// view is to be rendered, and loads otherwise.
#include "mvpt/render/camera.h"
#include "mvpt/loader/camera_path.h"
#include "mvpt/loader/load_control.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>

using namespace mvpt;
namespace fs = std::filesystem;

namespace {

const char *BaseSensor = R"(<sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="1,2,6" target="0,0.5,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film></sensor>)";

std::unique_ptr<Scene> load_rig(const std::string &attrs, const std::string &sensor = BaseSensor, const std::string &rig = "") {
    std::string xml = "<scene version=\"3.0.0\" xmlns:mvpt=\"urn:mvpt\"><mvpt:rig " + attrs + ">" + sensor + "</mvpt:rig></scene>";
    return load_scene_string(xml, fs::temp_directory_path(), {}, rig);
}

/// The base camera alone (to compare the views against).
std::unique_ptr<Scene> load_base() { return load_scene_string("<scene version=\"3.0.0\">" + std::string(BaseSensor) + "</scene>", "."); }

/// The lens centre (camera position) at time t.
Point3f origin(const Camera &c, float t = 0.f) { return c.lens_point(t, {0.f, 0.f}); }

std::string error_of(const std::function<void()> &f) {
    try {
        f();
    } catch (const SceneError &e) {
        return e.what();
    }
    return "(no error)";
}

fs::path write_file(const std::string &name, const std::string &text) {
    fs::path p = fs::temp_directory_path() / name;
    std::ofstream(p) << text;
    return p;
}

/// World-space camera axes of the base (lookat origin=(1,2,6), target=(0,0.5,0), up=+y).
struct Axes {
    Vec3f x, y, z;
};
Axes base_axes() {
    Transform t = Transform::look_at({1, 2, 6}, {0, 0.5f, 0}, {0, 1, 0});
    return {t.vector({1, 0, 0}), t.vector({0, 1, 0}), t.vector({0, 0, 1})};
}

} // namespace

TEST(Rigs, GridPosesIdsAndSharedFocalPlane) {
    const float D = 4.f, spacing = 0.1f;
    auto s = load_rig(R"(type="grid" size="3x2" spacing="0.1" focus_distance="4")");
    auto base = load_base();
    const Camera &b = *base->cameras()[0];
    const auto &cams = s->cameras();
    ASSERT_EQ(cams.size(), 6u);
    Axes ax = base_axes();
    const char *ids[] = {"r0c0", "r0c1", "r0c2", "r1c0", "r1c1", "r1c2"};
    for (int i = 0; i < 6; ++i) {
        int r = i / 3, c = i % 3;
        EXPECT_EQ(cams[i]->id, ids[i]);
        // Row 0 on top (+y), column 0 leftmost (+x): offsets (1 - c, 0.5 - r) * spacing.
        Point3f want = origin(b) + ax.x * (spacing * (1.f - c)) + ax.y * (spacing * (0.5f - r));
        EXPECT_LT(norm(origin(*cams[i]) - want), 1e-5f) << ids[i];
    }
    // A point on the focal plane (depth D in front of the base) lands on the same pixel in every
    // view; a point off it shows parallax along the offset (x: disparity f dx (1/z - 1/D)).
    std::mt19937 gen(5);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    Transform to_world = Transform::look_at({1, 2, 6}, {0, 0.5f, 0}, {0, 1, 0});
    float f = 0.5f * 64.f / std::tan(20.f * Pi / 180.f);
    for (int k = 0; k < 50; ++k) {
        float qx = 0.3f * u(gen), qy = 0.2f * u(gen);
        Point3f on = to_world.point({qx * D, qy * D, D});
        Vec2f x0;
        ASSERT_TRUE(b.project(on, 0.f, {0.f, 0.f}, &x0));
        for (auto &c : cams) {
            Vec2f x;
            ASSERT_TRUE(c->project(on, 0.f, {0.f, 0.f}, &x));
            EXPECT_NEAR(x.x, x0.x, 2e-3f) << c->id;
            EXPECT_NEAR(x.y, x0.y, 2e-3f) << c->id;
        }
        float z = 2.5f;
        Point3f off = to_world.point({qx * z, qy * z, z});
        Vec2f a, c;
        ASSERT_TRUE(cams[0]->project(off, 0.f, {0.f, 0.f}, &a)); // r0c0: dx = +spacing (left)
        ASSERT_TRUE(cams[2]->project(off, 0.f, {0.f, 0.f}, &c)); // r0c2: dx = -spacing
        // Film x grows to the camera's right (-x): moving the camera left moves a near point right.
        EXPECT_NEAR(a.x - c.x, f * 2.f * spacing * (1.f / z - 1.f / D), 1e-2f);
        EXPECT_NEAR(a.y, c.y, 2e-3f);
    }
}

TEST(Rigs, StereoAndLinearShareTheFocalPlaneToo) {
    const float D = 3.f;
    Transform to_world = Transform::look_at({1, 2, 6}, {0, 0.5f, 0}, {0, 1, 0});
    for (const char *attrs : {R"(type="stereo" ipd="0.2" focus_distance="3")", R"(type="linear" n="7" baseline="0.9" focus_distance="3")"}) {
        auto s = load_rig(attrs);
        for (float qx : {-0.25f, 0.f, 0.3f}) {
            Point3f on = to_world.point({qx * D, 0.1f * D, D}), near = to_world.point({qx * 2.f, 0.2f, 2.f});
            Vec2f x0, x, n0, n;
            ASSERT_TRUE(s->cameras()[0]->project(on, 0.f, {0.f, 0.f}, &x0));
            ASSERT_TRUE(s->cameras()[0]->project(near, 0.f, {0.f, 0.f}, &n0));
            for (auto &c : s->cameras()) {
                ASSERT_TRUE(c->project(on, 0.f, {0.f, 0.f}, &x));
                EXPECT_NEAR(x.x, x0.x, 2e-3f) << attrs << " " << c->id;
                EXPECT_NEAR(x.y, x0.y, 2e-3f) << attrs << " " << c->id;
                ASSERT_TRUE(c->project(near, 0.f, {0.f, 0.f}, &n));
                if (c != s->cameras()[0]) EXPECT_GT(std::abs(n.x - n0.x), 0.5f) << attrs << " " << c->id; // parallax off the plane
            }
        }
    }
}

TEST(Rigs, GridWithoutFocusDistanceIsParallel) {
    auto s = load_rig(R"(type="grid" cols="2" rows="2" spacing="0.2")");
    auto base = load_base();
    // Parallel views: every ray through the same film position has the base's direction.
    for (auto &c : s->cameras()) {
        Ray r = c->generate_ray({10.f, 30.f}, {0.f, 0.f}, 0.f), r0 = base->cameras()[0]->generate_ray({10.f, 30.f}, {0.f, 0.f}, 0.f);
        EXPECT_LT(norm(r.d - r0.d), 1e-6f) << c->id;
    }
}

TEST(Rigs, StereoLinearAndOrbitPoses) {
    auto base = load_base();
    Point3f o = origin(*base->cameras()[0]);
    Axes ax = base_axes();
    auto st = load_rig(R"(type="stereo" ipd="0.07")");
    ASSERT_EQ(st->cameras().size(), 2u);
    EXPECT_EQ(st->cameras()[0]->id, "left");
    EXPECT_EQ(st->cameras()[1]->id, "right");
    EXPECT_LT(norm(origin(*st->cameras()[0]) - (o + ax.x * 0.035f)), 1e-5f);
    EXPECT_LT(norm(origin(*st->cameras()[1]) - (o - ax.x * 0.035f)), 1e-5f);
    auto def = load_rig(R"(type="stereo")");
    EXPECT_NEAR(norm(origin(*def->cameras()[0]) - origin(*def->cameras()[1])), 0.064f, 1e-5f);

    auto lin = load_rig(R"(type="linear" n="5" baseline="1" id="row")");
    ASSERT_EQ(lin->cameras().size(), 5u);
    for (int i = 0; i < 5; ++i) {
        EXPECT_EQ(lin->cameras()[i]->id, "row_view00" + std::to_string(i));
        EXPECT_LT(norm(origin(*lin->cameras()[i]) - (o + ax.x * (0.5f - 0.25f * i))), 1e-5f);
    }

    // Orbit about the base's up axis through the point `radius` ahead: every view keeps that
    // point on its optical axis (film centre) and its distance; view i is turned by 360 i / n.
    auto orb = load_rig(R"(type="orbit" n="4" radius="3")");
    ASSERT_EQ(orb->cameras().size(), 4u);
    Point3f centre = o + ax.z * 3.f;
    for (int i = 0; i < 4; ++i) {
        const Camera &c = *orb->cameras()[i];
        Vec2f x;
        ASSERT_TRUE(c.project(centre, 0.f, {0.f, 0.f}, &x));
        EXPECT_NEAR(x.x, 32.f, 1e-3f);
        EXPECT_NEAR(x.y, 24.f, 1e-3f);
        EXPECT_NEAR(norm(origin(c) - centre), 3.f, 1e-4f);
        float cos_angle = dot(normalize(origin(c) - centre), -ax.z);
        EXPECT_NEAR(cos_angle, std::cos(i * Pi / 2), 1e-4f) << i;
    }
    auto arc = load_rig(R"(type="orbit" n="3" radius="3" arc="90")");
    EXPECT_NEAR(dot(normalize(origin(*arc->cameras()[0]) - centre), -ax.z), std::cos(Pi / 4), 1e-4f);
    EXPECT_LT(norm(origin(*arc->cameras()[1]) - o), 1e-4f);
}

TEST(Rigs, PathFramesShuttersAndInterpolation) {
    // Three collinear keys at uniform speed: the smooth (Catmull-Rom) path equals the linear one.
    write_file("rig_keys_line.json", R"({"interpolation": "smooth", "keys": [
        {"time": 0, "position": [0, 1, 5], "target": [0, 1, 0]},
        {"time": 1, "position": [1, 1, 5], "target": [1, 1, 0]},
        {"time": 2, "position": [2, 1, 5], "target": [2, 1, 0]}]})");
    auto s = load_rig(R"(type="path" file="rig_keys_line.json" frames="10" fps="4" shutter="1.5")");
    const auto &cams = s->cameras();
    ASSERT_EQ(cams.size(), 10u);
    for (int i = 0; i < 10; ++i) {
        const Camera &c = *cams[i];
        char id[16];
        std::snprintf(id, sizeof(id), "frame%04d", i);
        EXPECT_EQ(c.id, id);
        EXPECT_NEAR(c.shutter_open, i / 4.f, 1e-6f);
        EXPECT_NEAR(c.shutter_close, i / 4.f + 1.5f / 4.f, 1e-6f);
        if (i > 0) EXPECT_GT(cams[i - 1]->shutter_close, c.shutter_open); // shutter > 1: frames overlap
        EXPECT_TRUE(c.is_animated());
        // Position along the path within the shutter (held at the last key after t = 2).
        for (float t : {c.shutter_open, 0.5f * (c.shutter_open + c.shutter_close), c.shutter_close})
            EXPECT_LT(norm(origin(c, t) - Point3f(std::min(t, 2.f), 1.f, 5.f)), 1e-4f) << c.id << " t=" << t;
    }
    // A curved path: smooth passes through every key, differs from linear between keys, and
    // moves with continuous velocity across a key (finite differences on either side).
    std::string keys = R"({"keys": [
        {"time": 0, "position": [0, 1, 5], "target": [0, 0, 0]},
        {"time": 1, "position": [2, 1, 4], "target": [0, 0, 0]},
        {"time": 3, "position": [3, 2, 1], "target": [0, 0, 0]}]})";
    CameraPath smooth = CameraPath::from_json(parse_json(keys, "k.json")), lin = smooth;
    lin.interpolation = PathInterpolation::Linear;
    EXPECT_EQ(smooth.interpolation, PathInterpolation::Smooth); // the default
    Vec3f p, t, up, q;
    for (auto &k : smooth.keys()) {
        smooth.eval(k.time, &p, &t, &up);
        EXPECT_LT(norm(p - k.position), 1e-5f);
    }
    smooth.eval(0.5f, &p, &t, &up);
    lin.eval(0.5f, &q, &t, &up);
    EXPECT_GT(norm(p - q), 0.05f);
    EXPECT_LT(norm(q - Vec3f(1.f, 1.f, 4.5f)), 1e-5f);
    const float h = 1e-3f;
    Vec3f a, b, c;
    smooth.eval(1.f - h, &a, &t, &up);
    smooth.eval(1.f, &b, &t, &up);
    smooth.eval(1.f + h, &c, &t, &up);
    EXPECT_LT(norm((b - a) / h - (c - b) / h), 2e-2f);
    // Catmull-Rom tangent at key 1: (p2 - p0) / (t2 - t0).
    EXPECT_LT(norm((c - a) / (2 * h) - Vec3f(3.f, 1.f, -4.f) / 3.f), 1e-2f);
}

TEST(Rigs, ZeroShutterGivesStaticFrames) {
    write_file("rig_keys_two.json", R"([{"time": 0, "position": [0, 1, 5], "target": [0, 0, 0]},
        {"time": 1, "matrix": [[1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 5], [0, 0, 0, 1]]}])");
    auto s = load_rig(R"(type="path" file="rig_keys_two.json" frames="3" fps="2" shutter="0" interpolation="linear")");
    ASSERT_EQ(s->cameras().size(), 3u);
    for (auto &c : s->cameras()) {
        EXPECT_FALSE(c->is_animated());
        EXPECT_EQ(c->shutter_open, c->shutter_close);
    }
    // Frame 2 (t = 1) sits at the matrix key, looking along its +z axis.
    Ray r = s->cameras()[2]->generate_ray({32.f, 24.f}, {0.f, 0.f}, 1.f);
    EXPECT_LT(norm(r.o - Point3f(1, 1, 5)), 1e-5f);
    EXPECT_LT(norm(r.d - Vec3f(0, 0, 1)), 1e-5f);
}

TEST(Rigs, RigOptionReplacesTheSensors) {
    std::string xml = std::string("<scene version=\"3.0.0\">") + BaseSensor +
                      R"(<sensor type="perspective" id="other"/></scene>)";
    auto s = load_scene_string(xml, ".", {}, "grid:3x2,spacing=0.1,focus_distance=4");
    ASSERT_EQ(s->cameras().size(), 6u);
    EXPECT_EQ(s->cameras()[5]->id, "r1c2");
    auto xml_rig = load_rig(R"(type="grid" size="3x2" spacing="0.1" focus_distance="4")");
    for (int i = 0; i < 6; ++i) {
        Ray a = s->cameras()[i]->generate_ray({5.f, 7.f}, {0.f, 0.f}, 0.f), b = xml_rig->cameras()[i]->generate_ray({5.f, 7.f}, {0.f, 0.f}, 0.f);
        EXPECT_LT(norm(a.o - b.o) + norm(a.d - b.d), 1e-6f);
    }
    EXPECT_EQ(load_scene_string(xml, ".", {}, "stereo")->cameras().size(), 2u);
    EXPECT_EQ(load_scene_string(xml, ".", {}, "linear:n=45,baseline=0.5")->cameras().size(), 45u);
    EXPECT_EQ(load_scene_string(xml, ".", {}, "orbit:n=60,radius=4")->cameras().size(), 60u);
}

TEST(Rigs, ReferencedFilmSetsTheShear) {
    // The shear needs the film's aspect: a <ref>'d film (as in scenes/cornell-glossy-9.xml) is
    // looked up, so a point on the focal plane stays on one pixel vertically too.
    std::string film = R"(<film type="hdrfilm" id="f"><integer name="width" value="32"/><integer name="height" value="32"/></film>)";
    std::string sensor = R"(<sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform><ref id="f"/></sensor>)";
    auto xml_rig = load_scene_string("<scene version=\"3.0.0\">" + film + "<mvpt:rig type=\"grid\" size=\"3x3\" spacing=\"0.2\" focus_distance=\"5\">" +
                                         sensor + "</mvpt:rig></scene>", ".");
    auto opt_rig = load_scene_string("<scene version=\"3.0.0\">" + film + sensor + "</scene>", ".", {}, "grid:3x3,spacing=0.2,focus_distance=5");
    for (auto *s : {xml_rig.get(), opt_rig.get()}) {
        ASSERT_EQ(s->cameras().size(), 9u);
        for (auto &c : s->cameras()) {
            Vec2f x;
            ASSERT_TRUE(c->project({0.3f, -0.4f, 0.f}, 0.f, {0.f, 0.f}, &x));
            Vec2f want(16.f + 0.3f * 16.f / std::tan(20.f * Pi / 180.f) / 5.f, 16.f + 0.4f * 16.f / std::tan(20.f * Pi / 180.f) / 5.f);
            EXPECT_NEAR(x.x, want.x, 2e-3f) << c->id;
            EXPECT_NEAR(x.y, want.y, 2e-3f) << c->id;
        }
    }
}

TEST(Rigs, ThinLensBaseKeepsItsLens) {
    auto s = load_rig(R"(type="stereo" focus_distance="5")", R"(<sensor type="thinlens"><float name="aperture_radius" value="0.1"/>
        <float name="focus_distance" value="5"/></sensor>)");
    ASSERT_EQ(s->cameras().size(), 2u);
    EXPECT_EQ(s->cameras()[0]->lens_radius(), 0.1f);
}

TEST(RigErrors, ZeroViews) {
    for (const char *attrs : {R"(type="grid" size="0x3" spacing="0.1")", R"(type="grid" cols="2" rows="0" spacing="0.1")",
                              R"(type="linear" n="0" baseline="1")", R"(type="orbit" n="0" radius="1")"}) {
        std::string e = error_of([&] { load_rig(attrs); });
        EXPECT_NE(e.find("at least one view"), std::string::npos) << e;
        EXPECT_NE(e.find("<string>:1:"), std::string::npos) << e; // at the attribute
    }
    std::string e = error_of([&] { load_scene_string(std::string("<scene version=\"3.0.0\">") + BaseSensor + "</scene>", ".", {}, "linear:n=0,baseline=1"); });
    EXPECT_NE(e.find("--rig linear:n=0,baseline=1: linear rig 'n'"), std::string::npos) << e;
    EXPECT_NE(e.find("at least one view"), std::string::npos) << e;
}

TEST(RigErrors, NanSpacing) {
    std::string e = error_of([&] { load_rig("type=\"grid\" size=\"5x5\"\n  spacing=\"nan\""); });
    EXPECT_NE(e.find("<string>:2:3: <mvpt:rig>: grid rig 'spacing'"), std::string::npos) << e;
    EXPECT_NE(e.find("finite"), std::string::npos) << e;
    e = error_of([&] { load_scene_string(std::string("<scene version=\"3.0.0\">") + BaseSensor + "</scene>", ".", {}, "grid:5x5,spacing=NaN"); });
    EXPECT_NE(e.find("--rig grid:5x5,spacing=NaN: grid rig 'spacing'"), std::string::npos) << e;
    e = error_of([&] { load_rig(R"(type="grid" size="5x5" spacing="-0.1")"); });
    EXPECT_NE(e.find("must be a length > 0"), std::string::npos) << e;
}

TEST(RigErrors, KeyFileThatDoesNotParse) {
    fs::path p = write_file("rig_keys_bad.json", "{\"keys\": [\n  {\"time\": 0, \"position\": [0, 1, 5] \"target\": [0, 0, 0]}\n]}");
    std::string e = error_of([&] { load_rig(R"(type="path" file="rig_keys_bad.json" frames="3")"); });
    EXPECT_NE(e.find(p.string() + ":2:37: expected '}' or ',' in the object"), std::string::npos) << e;
    write_file("rig_keys_order.json", R"([{"time": 1, "position": [0, 1, 5], "target": [0, 0, 0]},
        {"time": 0.5, "position": [0, 1, 5], "target": [0, 0, 0]}])");
    e = error_of([&] { load_rig(R"(type="path" file="rig_keys_order.json" frames="3")"); });
    EXPECT_NE(e.find("rig_keys_order.json:2:9: key times must increase"), std::string::npos) << e;
    e = error_of([&] { load_rig(R"(type="path" file="no_such_keys.json" frames="3")"); });
    EXPECT_NE(e.find("'no_such_keys.json' not found"), std::string::npos) << e;
    write_file("rig_keys_scaled.json", R"([{"time": 0, "matrix": [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}])");
    e = error_of([&] { load_rig(R"(type="path" file="rig_keys_scaled.json" frames="3")"); });
    EXPECT_NE(e.find("rigid"), std::string::npos) << e;
}

TEST(RigErrors, BadTypeParameterOrStructure) {
    std::string e = error_of([&] { load_rig(R"(type="gird" size="5x5" spacing="0.1")"); });
    EXPECT_NE(e.find("unknown rig type 'gird' (did you mean 'grid'?)"), std::string::npos) << e;
    e = error_of([&] { load_rig(R"(type="grid" size="5x5" spacnig="0.1")"); });
    EXPECT_NE(e.find("has no parameter 'spacnig' (did you mean 'spacing'?)"), std::string::npos) << e;
    e = error_of([&] { load_rig(R"(type="grid" size="5x5")"); });
    EXPECT_NE(e.find("needs 'spacing'"), std::string::npos) << e;
    e = error_of([&] { load_rig(R"(type="stereo")", ""); });
    EXPECT_NE(e.find("needs a <sensor> inside it"), std::string::npos) << e;
    e = error_of([&] { load_rig(R"(type="stereo")", R"(<sensor type="perspective"><animation name="to_world">
        <transform time="0"><translate x="1"/></transform><transform time="1"><translate x="2"/></transform></animation></sensor>)"); });
    EXPECT_NE(e.find("static 'to_world'"), std::string::npos) << e;
    e = error_of([&] {
        load_scene_string(std::string("<scene version=\"3.0.0\"><shape type=\"sphere\"><mvpt:rig type=\"stereo\">") + BaseSensor +
                              "</mvpt:rig></shape></scene>", ".");
    });
    EXPECT_NE(e.find("<mvpt:rig> must be placed directly inside <scene>"), std::string::npos) << e;
    e = error_of([&] { load_scene_string("<scene version=\"3.0.0\"><shape type=\"sphere\"/></scene>", ".", {}, "stereo"); });
    EXPECT_NE(e.find("has no <sensor>"), std::string::npos) << e;
    e = error_of([&] { load_scene_string(std::string("<scene version=\"3.0.0\">") + BaseSensor + "</scene>", ".", {}, "stereo:0.1"); });
    EXPECT_NE(e.find("expected name=value"), std::string::npos) << e;
    // Two rigs whose views share ids collide like any duplicate id.
    e = error_of([&] {
        load_scene_string(std::string("<scene version=\"3.0.0\"><mvpt:rig type=\"stereo\">") + BaseSensor +
                              "</mvpt:rig><mvpt:rig type=\"stereo\">" + BaseSensor + "</mvpt:rig></scene>", ".");
    });
    EXPECT_NE(e.find("duplicate id 'left'"), std::string::npos) << e;
}

namespace {

std::string scene_with_film(int width, int height) {
    return "<scene version=\"3.0.0\" xmlns:mvpt=\"urn:mvpt\"><sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(width) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(height) + "\"/></film></sensor></scene>";
}

} // namespace

TEST(LoadControl, ACancelledLoadStops) {
    std::atomic<bool> cancel{true};
    LoadControlScope scope({&cancel, false});
    EXPECT_THROW(load_scene_string(scene_with_film(8, 8), "."), LoadCancelled);
    EXPECT_THROW(load_scene_string(scene_with_film(8, 8), ".", {}, "grid:3x3,spacing=0.1"), LoadCancelled);
}

TEST(LoadControl, TheScopeEnds) {
    std::atomic<bool> cancel{true};
    { LoadControlScope scope({&cancel, true}); }
    EXPECT_EQ(load_control().cancel, nullptr);
    EXPECT_FALSE(load_control().every_view_rendered);
    EXPECT_EQ(load_scene_string(scene_with_film(8, 8), ".")->cameras().size(), 1u);
}

TEST(LoadControl, ARigThatCannotFitIsRefusedWhenEveryViewIsRendered) {
    // 4 views of 2^32 pixels: 550 GB of images at the least (nothing is allocated by the load).
    const std::string xml = scene_with_film(65536, 65536);
    EXPECT_EQ(load_scene_string(xml, ".", {}, "grid:2x2,spacing=0.1")->cameras().size(), 4u);
    LoadControlScope scope({nullptr, true});
    try {
        load_scene_string(xml, ".", {}, "grid:2x2,spacing=0.1");
        FAIL() << "not refused";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("the rig's 4 views need at least"), std::string::npos) << e.what();
    }
    // A crop window counts as the view's pixels: 4 views of 8 x 8 fit.
    const std::string cropped = scene_with_film(65536, 65536).replace(
        xml.find("</film>"), 7, "<integer name=\"crop_width\" value=\"8\"/><integer name=\"crop_height\" value=\"8\"/></film>");
    EXPECT_EQ(load_scene_string(cropped, ".", {}, "grid:2x2,spacing=0.1")->cameras().size(), 4u);
}
