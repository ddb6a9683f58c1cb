// A textured area emitter looks its radiance up at the surface uv, both when
// sampled (sample_li) and when hit (eval): checked with a texture that returns
// its own coordinates, on a rectangle whose uv is ((x+1)/2, (y+1)/2) locally.
#include "mvpt/render/texture.h"
#include "mvpt/core/plugin.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

using namespace mvpt;

namespace {
class UvTexture final : public Texture {
public:
    Color3f eval(Vec2f uv) const override { return {uv.x, uv.y, 1.f}; }
    Color3f mean() const override { return {0.5f, 0.5f, 1.f}; }
};
MVPT_REGISTER_PLUGIN("texture", "test_uv", [](const Properties &, const LoadContext &) {
    return std::make_shared<UvTexture>();
});

const char *kScene = R"(<scene version="3.0.0">
  <shape type="rectangle">
    <transform name="to_world"><scale x="2" y="1"/><rotate x="1" angle="180"/><translate z="3"/></transform>
    <emitter type="area"><texture type="test_uv" name="radiance"/></emitter>
  </shape>
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
</scene>)";

/// Local rectangle coordinates of a world point on the light: x = px / 2, y = -py (rotated by 180 degrees about x).
Vec2f expected_uv(Point3f p) { return {(p.x / 2.f + 1.f) * 0.5f, (-p.y + 1.f) * 0.5f}; }
} // namespace

TEST(AreaLightTexture, SampleAndEvalUseSurfaceUv) {
    auto scene = load_scene_string(kScene, ".");
    ASSERT_EQ(scene->lights().size(), 1u);
    const Light &light = *scene->lights()[0];
    Point3f ref(0.3f, -0.2f, 0.f);
    for (int i = 0; i < 64; ++i) {
        Vec2f u((i % 8 + 0.5f) / 8.f, (i / 8 + 0.5f) / 8.f);
        auto [ls, weight] = light.sample_li(ref, u, 0.f);
        ASSERT_GT(ls.pdf, 0.f);
        Color3f L = weight * ls.pdf;
        Vec2f uv = expected_uv(ls.p);
        EXPECT_NEAR(L.r, uv.x, 1e-4f);
        EXPECT_NEAR(L.g, uv.y, 1e-4f);
        EXPECT_NEAR(L.b, 1.f, 1e-4f);

        // The same point reached by a ray: eval returns the same radiance.
        SurfaceInteraction si;
        ASSERT_TRUE(scene->intersect(Ray{ref, ls.d, 0.f, Infinity, 0.f}, si));
        Color3f Le = light.eval(si, -ls.d);
        EXPECT_NEAR(Le.r, L.r, 1e-4f);
        EXPECT_NEAR(Le.g, L.g, 1e-4f);
        EXPECT_NEAR(light.pdf_li(ref, si, ls.d), ls.pdf, 1e-4f * ls.pdf);
    }
    // Seen from behind, the one-sided emitter is dark.
    SurfaceInteraction si;
    Point3f above(0.f, 0.f, 6.f);
    ASSERT_TRUE(scene->intersect(Ray{above, Vec3f(0, 0, -1), 0.f, Infinity, 0.f}, si));
    EXPECT_TRUE(light.eval(si, Vec3f(0, 0, 1)).is_black());
}

TEST(SpotLightTexture, ProjectsTheCutoffConeOntoUnitSquare) {
    // Spot at the origin looking down +z (identity to_world); a receiver at
    // local direction (x, y, 1) sees uv = 1/2 + (x, y) / (2 tan(cutoff)).
    auto scene = load_scene_string(R"(<scene version="3.0.0">
      <emitter type="spot"><float name="cutoff_angle" value="40"/><float name="beam_width" value="40"/>
        <texture type="test_uv" name="texture"/></emitter>
      <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
    </scene>)", ".");
    const Light &light = *scene->lights()[0];
    const float t = std::tan(deg_to_rad(40.f));
    for (Vec2f xy : {Vec2f(0.f, 0.f), Vec2f(0.3f, -0.2f), Vec2f(-0.5f, 0.4f)}) {
        Point3f ref(xy.x * 2.f, xy.y * 2.f, 2.f);
        auto [ls, weight] = light.sample_li(ref, {0.5f, 0.5f}, 0.f);
        Color3f L = weight * squared_norm(ref);
        EXPECT_NEAR(L.r, 0.5f + 0.5f * xy.x / t, 1e-4f);
        EXPECT_NEAR(L.g, 0.5f + 0.5f * xy.y / t, 1e-4f);
        EXPECT_NEAR(L.b, 1.f, 1e-4f);
    }
}

TEST(SpotLightTexture, ConstantTextureIsAnError) {
    try {
        load_scene_string(R"(<scene version="3.0.0">
          <emitter type="spot"><rgb name="texture" value="0.5"/></emitter>
          <sensor type="perspective"/></scene>)", ".");
        FAIL() << "a constant spot texture was accepted";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("spatially varying"), std::string::npos) << e.what();
    }
}
