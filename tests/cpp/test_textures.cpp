// bitmap and checkerboard textures: Mitsuba's uv orientation, filtering,
// wrap modes, to_uv, and the checkerboard's scalar lookup.
#include "mvpt/io/image_io.h"
#include "mvpt/render/texture.h"
#include "mvpt/core/plugin.h"

#include <gtest/gtest.h>

#include <filesystem>

using namespace mvpt;
namespace fs = std::filesystem;

namespace {

std::shared_ptr<Texture> make(Properties &p, const LoadContext &ctx = {}) {
    auto t = std::static_pointer_cast<Texture>((*PluginRegistry::find("texture", p.type()))(p, ctx));
    p.check_all_queried();
    return t;
}

/// 2x2 EXR: row 0 (top) red, green; row 1 blue, white.
fs::path quad_image() {
    fs::path dir = fs::temp_directory_path() / "mvpt_texture_tests";
    fs::create_directories(dir);
    fs::path p = dir / "quad.exr";
    std::vector<ExrChannel> ch = {{"R", {1, 0, 0, 1}}, {"G", {0, 1, 0, 1}}, {"B", {0, 0, 1, 1}}};
    write_exr(p, 2, 2, ch);
    return p;
}

void expect_color(Color3f c, Color3f e, const char *what) {
    EXPECT_NEAR(c.r, e.r, 1e-5f) << what;
    EXPECT_NEAR(c.g, e.g, 1e-5f) << what;
    EXPECT_NEAR(c.b, e.b, 1e-5f) << what;
}

} // namespace

TEST(BitmapTexture, OrientationFilteringAndWrapping) {
    fs::path img = quad_image();
    LoadContext ctx;
    ctx.search_dirs = {img.parent_path()};
    Properties p("texture", "bitmap");
    p.set("filename", std::string("quad.exr"), {}, "string");
    p.set("filter_type", std::string("nearest"), {}, "string");
    auto t = make(p, ctx);
    // uv (0, 0) is the top-left pixel (Mitsuba's convention, checked against Mitsuba 3.9).
    expect_color(t->eval({0.25f, 0.25f}), {1, 0, 0}, "top left");
    expect_color(t->eval({0.75f, 0.25f}), {0, 1, 0}, "top right");
    expect_color(t->eval({0.25f, 0.75f}), {0, 0, 1}, "bottom left");
    EXPECT_NEAR(t->eval_1({0.25f, 0.25f}), 0.212671f, 1e-5f); // luminance
    expect_color(t->mean(), {0.5f, 0.5f, 0.5f}, "mean");

    // Bilinear with the three wrap modes (values from Mitsuba 3.9's bitmap).
    struct Case { const char *wrap; float u; Color3f expected; };
    for (Case c : {Case{"repeat", 0.0f, {0.5f, 0.5f, 0}}, Case{"repeat", 1.2f, {0.9f, 0.1f, 0}},
                   Case{"mirror", -0.1f, {1, 0, 0}}, Case{"mirror", 1.6f, {0.7f, 0.3f, 0}},
                   Case{"mirror", 2.3f, {0.9f, 0.1f, 0}}, Case{"clamp", 1.6f, {0, 1, 0}},
                   Case{"clamp", -0.1f, {1, 0, 0}}}) {
        Properties q("texture", "bitmap");
        q.set("filename", img.string(), {}, "string");
        q.set("wrap_mode", std::string(c.wrap), {}, "string");
        expect_color(make(q)->eval({c.u, 0.25f}), c.expected, c.wrap);
    }
    // to_uv with a translation.
    Properties q("texture", "bitmap");
    q.set("filename", img.string(), {}, "string");
    q.set("filter_type", std::string("nearest"), {}, "string");
    q.set("to_uv", Transform::translate({0.5f, 0, 0}), {}, "transform");
    expect_color(make(q)->eval({0.25f, 0.25f}), {0, 1, 0}, "to_uv");
    // Bad parameters name themselves.
    Properties bad("texture", "bitmap");
    bad.set("filename", img.string(), {}, "string");
    bad.set("wrap_mode", std::string("wrap"), {}, "string");
    EXPECT_THROW(make(bad), SceneError);
    // Non-finite uvs do not crash.
    EXPECT_NO_THROW(make(q)->eval({std::nanf(""), 1e30f}));
}

TEST(Checkerboard, PatternAndMitsubaScalarQuirk) {
    Properties p("texture", "checkerboard");
    auto t = make(p);
    expect_color(t->eval({0.1f, 0.1f}), Color3f(0.4f), "c0");
    expect_color(t->eval({0.6f, 0.1f}), Color3f(0.2f), "c1");
    expect_color(t->eval({0.6f, 0.6f}), Color3f(0.4f), "c0");
    // Mitsuba 3.9's eval_1 returns the other patch's value (reproduced).
    EXPECT_NEAR(t->eval_1({0.1f, 0.1f}), 0.2f, 1e-6f);
    expect_color(t->mean(), Color3f(0.3f), "mean");
    Properties q("texture", "checkerboard");
    q.set("to_uv", Transform::translate({0.5f, 0, 0}), {}, "transform");
    expect_color(make(q)->eval({0.1f, 0.1f}), Color3f(0.2f), "to_uv");
}
