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

TEST(BitmapTexture, GradientIsTheDerivativeOfTheBilinearLuminance) {
    // 3x2 pixels of different luminances, read through a rotating and scaling to_uv: eval_1_grad
    // must be the derivative of eval_1 (central differences inside the bilinear patches), by the
    // chain rule through the uv map and the non-square resolution.
    fs::path dir = fs::temp_directory_path() / "mvpt_texture_tests";
    fs::create_directories(dir);
    fs::path img = dir / "grad.exr";
    write_exr(img, 3, 2, {{"R", {0.1f, 0.9f, 0.3f, 0.5f, 0.2f, 0.8f}}, {"G", {0.4f, 0.1f, 0.7f, 0.2f, 0.9f, 0.3f}},
                          {"B", {0.6f, 0.5f, 0.2f, 0.9f, 0.1f, 0.4f}}});
    Properties p("texture", "bitmap");
    p.set("filename", img.string(), {}, "string");
    p.set("to_uv", Transform::scale({1.3f, 0.7f, 1.f}) * Transform::rotate({0, 0, 1}, 25.f), {}, "transform");
    auto t = make(p);
    const float h = 1e-3f;
    for (Vec2f uv : {Vec2f(0.31f, 0.47f), Vec2f(0.62f, 0.13f), Vec2f(0.83f, 0.71f), Vec2f(-0.4f, 1.37f)}) {
        const Vec2f g = t->eval_1_grad(uv);
        const float du = (t->eval_1({uv.x + h, uv.y}) - t->eval_1({uv.x - h, uv.y})) / (2.f * h);
        const float dv = (t->eval_1({uv.x, uv.y + h}) - t->eval_1({uv.x, uv.y - h})) / (2.f * h);
        EXPECT_NEAR(g.x, du, 2e-3f * (1.f + std::abs(du))) << uv.x << ", " << uv.y;
        EXPECT_NEAR(g.y, dv, 2e-3f * (1.f + std::abs(dv))) << uv.x << ", " << uv.y;
        EXPECT_GT(std::abs(g.x) + std::abs(g.y), 0.1f); // not vacuous
    }
    // The nearest lookup is piecewise constant: no gradient.
    Properties q("texture", "bitmap");
    q.set("filename", img.string(), {}, "string");
    q.set("filter_type", std::string("nearest"), {}, "string");
    const Vec2f g = make(q)->eval_1_grad({0.31f, 0.47f});
    EXPECT_EQ(g.x, 0.f);
    EXPECT_EQ(g.y, 0.f);
}
