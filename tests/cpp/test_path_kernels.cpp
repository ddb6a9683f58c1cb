// The wavefront's vector kernels for Lambertian vertices (integrators/path/path_kernels.cpp) against
// PathIntegrator::li, bit for bit, in the cases that pick their branches: both sides of a
// twosided diffuse, one-sided diffuse seen from behind, quad and sphere emitters (flipped
// normals, a reference point inside a sphere, a back-facing quad), several emitters of each kind.
#include "batch_checks.h"
#include "mvpt/core/warp.h"
#include "mvpt/integrators/path/path.h"
#include "mvpt/integrators/path/path_kernels.h"
#include "mvpt/render/camera.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <string>

using namespace mvpt;

namespace {

const char *KernelScene = R"(<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="6"/><integer name="rr_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="70"/>
        <transform name="to_world"><lookat origin="0.3, 0.4, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
    </sensor>
    <!-- floor: twosided diffuse, tilted so that both sides are seen and lit -->
    <shape type="rectangle">
        <transform name="to_world"><scale value="2"/><rotate x="1" angle="-70"/><translate y="-0.8"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf></bsdf>
    </shape>
    <!-- one-sided diffuse wall whose back faces the camera -->
    <shape type="rectangle">
        <transform name="to_world"><rotate y="1" angle="150"/><translate x="-1" z="-0.5"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.4, 0.8, 0.2"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.4, -0.2, 0"/><float name="radius" value="0.4"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.9, 0.9, 0.9"/></bsdf>
    </shape>
    <!-- emitters: two quads (one facing away), a sphere, a small sphere with flipped normals
         (dark from outside), a sphere with flipped normals around the scene (sampled from inside) -->
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate y="1.2"/></transform>
        <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.4"/><rotate x="1" angle="-90"/><translate x="1" y="0.9"/></transform>
        <emitter type="area"><rgb name="radiance" value="3, 3, 3"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.7, 0.6, 0.5"/><float name="radius" value="0.15"/>
        <emitter type="area"><rgb name="radiance" value="20, 10, 5"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.8, 0.5, -0.6"/><float name="radius" value="0.2"/><boolean name="flip_normals" value="true"/>
        <emitter type="area"><rgb name="radiance" value="9, 9, 9"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="0, 0, 0"/><float name="radius" value="5"/><boolean name="flip_normals" value="true"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.2, 0.2"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="0.3, 0.4, 0.5"/></emitter>
    </shape>
</scene>)";

} // namespace

/// li_batch against li on every pixel of `xml` (24 x 24, 4 spp), bit for bit.
static void expect_batch_equals_li(const char *xml) {
    auto scene = load_scene_string(xml, ".");
    auto *path = dynamic_cast<const PathIntegrator *>(&scene->integrator());
    ASSERT_NE(path, nullptr);
    std::vector<Ray> rays;
    std::vector<Sampler> samplers;
    test::camera_rays(*scene, 24, 4, rays, samplers, false, 3); // the scenes' films are 24 px
    const size_t nonzero = test::expect_li_batch_equals_li(*scene, *path, rays, samplers);
    EXPECT_GT(nonzero, rays.size() / 2);
}

TEST(PathKernels, LambertKernelsBitIdenticalToLi) { expect_batch_equals_li(KernelScene); }

namespace {

/// Rough conductors: twosided Beckmann (both sides lit), one-sided GGX whose back faces the
/// camera, GGX with a specular reflectance, a nearly smooth Beckmann sphere, an anisotropic one
/// (scalar path), lit by a quad, a sphere, a sphere with flipped normals (dark from outside; both
/// sampled by rough_conductor_sphere_nee_kernel) and an environment-like enclosing sphere.
std::string conductor_scene(const char *floor_distr, const char *wall_distr, const char *ball_distr) {
    std::string xml = R"(<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="6"/><integer name="rr_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="70"/>
        <transform name="to_world"><lookat origin="0.3, 0.4, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><scale value="2"/><rotate x="1" angle="-70"/><translate y="-0.8"/></transform>
        <bsdf type="twosided"><bsdf type="roughconductor"><string name="distribution" value="FLOOR"/>
            <float name="alpha" value="0.3"/><rgb name="eta" value="0.2, 0.92, 1.1"/><rgb name="k" value="3.9, 2.45, 2.14"/>
        </bsdf></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate y="1" angle="150"/><translate x="-1" z="-0.5"/></transform>
        <bsdf type="roughconductor"><string name="distribution" value="WALL"/><float name="alpha" value="0.15"/>
            <rgb name="specular_reflectance" value="0.3, 0.6, 0.9"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.4, -0.2, 0"/><float name="radius" value="0.4"/>
        <bsdf type="twosided"><bsdf type="roughconductor"><string name="distribution" value="BALL"/>
            <float name="alpha" value="0.01"/><string name="material" value="Au"/></bsdf></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.4, -0.3, 0.3"/><float name="radius" value="0.25"/>
        <bsdf type="roughconductor"><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate y="1.2"/></transform>
        <emitter type="area"><rgb name="radiance" value="6, 5, 4"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="-0.7, 0.6, 0.5"/><float name="radius" value="0.15"/>
        <emitter type="area"><rgb name="radiance" value="20, 10, 5"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="0.6, 0.7, 0.2"/><float name="radius" value="0.1"/><boolean name="flip_normals" value="true"/>
        <emitter type="area"><rgb name="radiance" value="9, 9, 9"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" value="0, 0, 0"/><float name="radius" value="5"/><boolean name="flip_normals" value="true"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.2, 0.2"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="0.3, 0.4, 0.5"/></emitter>
    </shape>
</scene>)";
    auto put = [&](const std::string &key, const char *value) { xml.replace(xml.find(key), key.size(), value); };
    put("FLOOR", floor_distr);
    put("WALL", wall_distr);
    put("BALL", ball_distr);
    return xml;
}

} // namespace

TEST(PathKernels, RoughConductorKernelsBitIdenticalToLi) {
    expect_batch_equals_li(conductor_scene("beckmann", "ggx", "beckmann").c_str()); // mixed chunks
    expect_batch_equals_li(conductor_scene("beckmann", "beckmann", "beckmann").c_str());
    expect_batch_equals_li(conductor_scene("ggx", "ggx", "ggx").c_str());
}

TEST(PathKernels, SincosTurnMatchesLibm) {
    // sin/cos of 2 pi u on a fine grid and at the quadrant boundaries.
    float worst = 0.f;
    for (uint32_t k = 0; k < (1u << 16); ++k) {
        float u = float(k) * 0x1p-16f;
        Vec2f sc = warp::sincos_turn(u);
        double a = 2.0 * 3.14159265358979323846 * double(u);
        worst = std::max({worst, float(std::abs(sc.x - std::sin(a))), float(std::abs(sc.y - std::cos(a)))});
    }
    EXPECT_LT(worst, 4e-7f);
    EXPECT_EQ(warp::sincos_turn(0.f).x, 0.f);
    EXPECT_EQ(warp::sincos_turn(0.f).y, 1.f);
    EXPECT_EQ(warp::sincos_turn(0.25f).y, 0.f);
    EXPECT_EQ(warp::sincos_turn(0.5f).x, 0.f);
}

TEST(PathKernels, OneQuadChunkMatchesMixedChunk) {
    // A chunk whose lanes all chose one quad takes the loop-invariant form of
    // lambert_quad_nee_kernel; its lanes must come out bit for bit as in the per-lane form
    // (a chunk that mixes quads). The lanes use quad 1, so a wrong table row shows too.
    QuadTable quads;
    const float rows[2][QuadTable::Params] = {
        {-0.5f, 2.f, -0.5f, 1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, -1.f, 0.f, 1.f, 5.f, 5.f, 5.f},
        {1.f, -0.2f, -0.3f, 0.f, 0.f, 0.6f, 0.f, 0.4f, 0.f, -1.f, 0.f, 0.f, 1.f / 0.24f, 2.f, 3.f, 4.f}};
    for (size_t q = 0; q < 2; ++q)
        for (size_t r = 0; r < QuadTable::Params; ++r) quads.at(r, q) = rows[q][r];
    constexpr size_t n = 40;
    SoaColumns one, mixed;
    one.resize(lam_col::Count, n);
    mixed.resize(lam_col::Count, n + 1);
    uint32_t state = 12345u;
    auto rnd = [&state] { // in [0, 1)
        state = state * 1664525u + 1013904223u;
        return float(state >> 8) * 0x1p-24f;
    };
    for (size_t i = 0; i <= n; ++i) {
        using namespace lam_col;
        const float v[] = {0.2f + 0.8f * rnd(), 1.f, 1.f, 0.f, 0.f, 0.f, 0.f, -1.f, 0.f, 1.f, 0.f,
                           -1.f + 1.8f * rnd(), -1.f + rnd(), -1.f + 2.f * rnd(), 0.f, 1.f, 0.f,
                           rnd(), rnd(), rnd(), rnd(), rnd(), rnd()};
        static_assert(Bb + 1 == std::size(v));
        for (size_t c = 0; c < std::size(v); ++c) {
            mixed[c][i] = v[c];
            if (i < n) one[c][i] = v[c];
        }
        const float u[] = {rnd(), rnd(), i < n ? 1.f : 0.f}; // the last lane of `mixed` on quad 0
        for (size_t c = 0; c < 3; ++c) {
            mixed[LightUx + c][i] = u[c];
            if (i < n) one[LightUx + c][i] = u[c];
        }
    }
    lambert_quad_nee_kernel(one, n, quads, 2.f, 1);
    lambert_quad_nee_kernel(mixed, n + 1, quads, 2.f);
    size_t lit = 0;
    for (size_t i = 0; i < n; ++i) {
        for (size_t c = lam_col::SOx; c <= lam_col::Ok; ++c)
            EXPECT_EQ(std::bit_cast<uint32_t>(one[c][i]), std::bit_cast<uint32_t>(mixed[c][i])) << "lane " << i << " column " << c;
        lit += one[lam_col::Ok][i] > 0.f && one[lam_col::Cr][i] > 0.f;
    }
    EXPECT_GT(lit, n / 2); // most lanes see quad 1's front and get a contribution
}
