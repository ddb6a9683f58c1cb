// Textured diffuse surfaces (a checkerboard reflectance, bare and inside twosided) take the
// wavefront's Lambertian vector kernels, with the texture evaluated when the lanes are
// gathered: li_batch must stay bit-identical to li there, for every kernel that reads the
// reflectance (quad and sphere emitters, other emitters, BSDF sampling).
#include "batch_checks.h"
#include "mvpt/core/warp.h"
#include "mvpt/integrators/path/path.h"
#include "mvpt/render/bsdf.h"
#include "mvpt/render/bsdfs/bsdf_form.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <vector>

using namespace mvpt;

namespace {

/// A checkerboard floor and wall, a twosided checkerboard panel and a constant diffuse ball,
/// lit by a quad emitter, a sphere emitter and a constant environment (escaping paths).
const char *TexturedScene = R"(
<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="6"/><integer name="rr_depth" value="3"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, 0.8, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/></film>
    </sensor>
    <texture type="checkerboard" id="checks">
        <rgb name="color0" value="0.8, 0.2, 0.1"/>
        <rgb name="color1" value="0.1, 0.3, 0.7"/>
        <transform name="to_uv"><scale x="6" y="6"/></transform>
    </texture>
    <shape type="rectangle">
        <transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-1"/></transform>
        <bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="4" y="3"/><translate y="1.5" z="-3"/></transform>
        <bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate y="1" angle="35"/><rotate x="1" angle="-20"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-1.5, -0.4, 0.5"/>
        <float name="radius" value="0.5"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.6, 0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.8"/><rotate x="1" angle="90"/><translate x="0.5" y="3" z="1"/></transform>
        <emitter type="area"><rgb name="radiance" value="9, 8, 6.5"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="1.8, 1.2, 0"/>
        <float name="radius" value="0.3"/>
        <emitter type="area"><rgb name="radiance" value="6, 6, 8"/></emitter>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="0.3, 0.35, 0.4"/></emitter>
</scene>)";

} // namespace

TEST(PathBatchTextured, TexturedDiffuseTakesTheLambertKernels) {
    auto scene = load_scene_string(TexturedScene, std::filesystem::current_path());
    size_t textured = 0, twosided_textured = 0;
    for (const auto &shape : scene->shapes())
        if (shape->bsdf)
            if (const BsdfForm form = bsdf_form(*shape->bsdf); form.kind == BsdfForm::Lambert && form.lambert.texture) {
                ++textured;
                twosided_textured += form.lambert.two_sided;
            }
    EXPECT_EQ(textured, 3u);
    EXPECT_EQ(twosided_textured, 1u);
}

TEST(PathBatchTextured, RadianceBitIdenticalToLi) {
    auto scene = load_scene_string(TexturedScene, std::filesystem::current_path());
    PathConfig cfg;
    if (auto *p = dynamic_cast<const PathIntegrator *>(&scene->integrator())) cfg = p->config();
    PathIntegrator integrator(cfg);
    std::vector<Ray> rays;
    std::vector<Sampler> samplers;
    test::camera_rays(*scene, 24, 3, rays, samplers, false, 11);
    std::vector<Spectrum> li;
    test::expect_li_batch_equals_li(*scene, integrator, rays, samplers, &li);
    size_t reddish = 0, bluish = 0;
    for (const Spectrum &ref : li) {
        reddish += ref.r > 2.f * ref.b;
        bluish += ref.b > 2.f * ref.r;
    }
    // Both checker colours were seen: the comparison covered the varying reflectance.
    EXPECT_GT(reddish, rays.size() / 20);
    EXPECT_GT(bluish, rays.size() / 20);
}
