// The closed forms that the wavefront's vector kernels run (render/bsdfs/bsdf_form.h,
// render/lights/area.h, render/shapes/sphere.h) are found for exactly the BSDFs and emitters that amount to them:
// a form found where it does not hold would give wrong images, one missed would only be slow,
// so both directions are checked here.
#include "mvpt/render/bsdf.h"
#include "mvpt/render/bsdfs/bsdf_form.h"
#include "mvpt/render/light.h"
#include "mvpt/render/lights/area.h"
#include "mvpt/render/shape.h"
#include "mvpt/render/shapes/sphere.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

using namespace mvpt;

namespace {

/// One rectangle per BSDF, each its own emitter when `emitters` is given.
std::unique_ptr<Scene> scene_of(const std::vector<std::string> &bsdfs, const std::string &emitters = "") {
    std::string xml = R"(<scene version="3.0.0"><integrator type="path"/>
        <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
        <texture type="checkerboard" id="checks"/>)";
    for (const std::string &b : bsdfs) xml += "<shape type=\"rectangle\">" + b + "</shape>";
    xml += emitters + "</scene>";
    return load_scene_string(xml, std::filesystem::current_path());
}

BsdfForm::Kind kind_of(const std::string &bsdf) { return bsdf_form(*scene_of({bsdf})->shapes()[0]->bsdf).kind; }

} // namespace

TEST(ClosedForms, BsdfFormsOfTheirTypesOnly) {
    const std::string diffuse = R"(<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf>)";
    const std::string other_diffuse = R"(<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>)";
    const std::string ggx = R"(<bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>)";
    EXPECT_EQ(kind_of(diffuse), BsdfForm::Lambert);
    EXPECT_EQ(kind_of(R"(<bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf>)"), BsdfForm::Lambert);
    EXPECT_EQ(kind_of("<bsdf type=\"twosided\">" + diffuse + "</bsdf>"), BsdfForm::Lambert);
    EXPECT_EQ(kind_of("<bsdf type=\"twosided\">" + diffuse + other_diffuse + "</bsdf>"), BsdfForm::General);
    EXPECT_EQ(kind_of("<bsdf type=\"twosided\">" + diffuse + diffuse + "</bsdf>"), BsdfForm::Lambert);
    EXPECT_EQ(kind_of(ggx), BsdfForm::RoughConductor);
    EXPECT_EQ(kind_of("<bsdf type=\"twosided\">" + ggx + "</bsdf>"), BsdfForm::RoughConductor);
    EXPECT_EQ(kind_of("<bsdf type=\"twosided\">" + ggx + diffuse + "</bsdf>"), BsdfForm::General);
    // Varying or anisotropic roughness, no visible-normal sampling: not constant.
    EXPECT_EQ(kind_of(R"(<bsdf type="roughconductor"><ref name="alpha" id="checks"/></bsdf>)"), BsdfForm::General);
    EXPECT_EQ(kind_of(R"(<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>)"),
              BsdfForm::General);
    EXPECT_EQ(kind_of(R"(<bsdf type="roughconductor"><boolean name="sample_visible" value="false"/></bsdf>)"),
              BsdfForm::General);
    EXPECT_EQ(kind_of(R"(<bsdf type="roughplastic"/>)"), BsdfForm::General);
    EXPECT_EQ(kind_of(R"(<bsdf type="conductor"/>)"), BsdfForm::General);

    const BsdfForm two = bsdf_form(*scene_of({"<bsdf type=\"twosided\">" + ggx + "</bsdf>"})->shapes()[0]->bsdf);
    EXPECT_TRUE(two.conductor.two_sided);
    EXPECT_FALSE(two.conductor.beckmann);
    EXPECT_FLOAT_EQ(two.conductor.alpha, 0.2f);
    const BsdfForm lam = bsdf_form(*scene_of({diffuse})->shapes()[0]->bsdf);
    EXPECT_FALSE(lam.lambert.two_sided);
    EXPECT_EQ(lam.lambert.texture, nullptr);
    EXPECT_FLOAT_EQ(lam.lambert.reflectance.g, 0.4f);
}

TEST(ClosedForms, EmitterFormsOfConstantAreaLightsOnly) {
    const std::string emitters = R"(
        <shape type="rectangle"><emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>
        <shape type="rectangle"><emitter type="area"><ref name="radiance" id="checks"/></emitter></shape>
        <shape type="sphere"><float name="radius" value="0.5"/><emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
        <shape type="disk"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
        <emitter type="point"><point name="position" value="0, 2, 0"/></emitter>
        <emitter type="constant"/>)";
    auto scene = scene_of({}, emitters);
    int quads = 0, spheres = 0;
    for (const auto &light : scene->lights()) {
        const auto quad = quad_emitter(*light);
        const auto sphere = sphere_emitter(*light);
        EXPECT_FALSE(quad && sphere);
        if (quad) {
            ++quads;
            EXPECT_EQ(light->shape(), scene->shapes()[0].get()); // the first rectangle, of constant radiance
            EXPECT_FLOAT_EQ(quad->radiance.b, 3.f);
            EXPECT_FLOAT_EQ(quad->inv_area, 0.25f); // Mitsuba's rectangle spans [-1, 1]^2
        }
        if (sphere) {
            ++spheres;
            EXPECT_FLOAT_EQ(sphere->radius, 0.5f);
            EXPECT_FLOAT_EQ(sphere->radiance.r, 4.f);
        }
    }
    EXPECT_EQ(quads, 1);
    EXPECT_EQ(spheres, 1);
    int sphere_shapes = 0;
    for (const auto &shape : scene->shapes())
        if (const auto g = sphere_geometry(*shape)) {
            ++sphere_shapes;
            EXPECT_EQ(g->radius, 0.5);
        }
    EXPECT_EQ(sphere_shapes, 1);
}
