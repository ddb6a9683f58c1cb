// walk_segments (the batched walk of multi-view path tracing's camera segments through media)
// against walk_segment, one segment at a time: the same walk, bit for bit, for both null rules,
// through nested media, a mask, a null-BSDF emitter and an opaque floor.
#include "mvpt/core/warp.h"
#include "mvpt/integrators/path/transmittance.h"
#include "mvpt/render/camera.h"
#include "mvpt/loader/load_scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <vector>

using namespace mvpt;

namespace {

const char *MediaScene = R"(
<scene version="3.0.0">
    <integrator type="volpath"/>
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
    <shape type="sphere"><float name="radius" value="1.5"/><bsdf type="null"/>
        <medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.4, 0.6, 0.2"/><rgb name="albedo" value="0.8"/></medium>
    </shape>
    <shape type="sphere"><float name="radius" value="0.5"/><point name="center" x="0.3" y="0.2" z="0"/><bsdf type="null"/>
        <medium type="homogeneous" name="interior"><rgb name="sigma_t" value="2, 1, 3"/></medium>
        <medium type="homogeneous" name="exterior"><rgb name="sigma_t" value="0.4, 0.6, 0.2"/><rgb name="albedo" value="0.8"/></medium>
    </shape>
    <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="30"/><translate x="-0.5"/></transform>
        <bsdf type="mask"><float name="opacity" value="0.4"/><bsdf type="diffuse"/></bsdf></shape>
    <shape type="disk"><transform name="to_world"><translate z="1"/></transform><bsdf type="null"/>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-1"/></transform>
        <bsdf type="diffuse"/></shape>
</scene>)";

bool same(const SegmentWalk &a, const SegmentWalk &b) {
    auto bits = [](const auto &x, const auto &y) { return std::memcmp(&x, &y, sizeof(x)) == 0; };
    return a.stopped == b.stopped && bits(a.tr, b.tr) && a.medium == b.medium && a.medium_pieces == b.medium_pieces &&
           a.piece_medium == b.piece_medium && bits(a.piece_t0, b.piece_t0) && bits(a.piece_t1, b.piece_t1) &&
           a.crossed_emitter == b.crossed_emitter && (!a.stopped || (bits(a.si.t, b.si.t) && a.si.shape == b.si.shape));
}

} // namespace

TEST(WalkSegments, BitIdenticalToOneAtATime) {
    auto scene = load_scene_string(MediaScene, std::filesystem::current_path());
    const Medium *outer = scene->shapes()[0]->interior.get();
    ASSERT_NE(outer, nullptr);
    Sampler sampler(SamplerKind::Independent, 3);
    sampler.start(0, 0, 0, 0);
    // Segments from points inside and outside the fog, finite and infinite, in all directions.
    std::vector<Ray> rays;
    std::vector<const Medium *> media;
    for (int i = 0; i < 400; ++i) {
        const Vec3f o = warp::square_to_uniform_sphere(sampler.next_2d()) * (i % 2 ? 0.9f : 3.f);
        const Vec3f d = warp::square_to_uniform_sphere(sampler.next_2d());
        const float t = i % 5 == 0 ? Infinity : 0.5f + 4.f * sampler.next_1d();
        rays.push_back(Ray{Point3f(o.x, o.y, o.z), d, 0.f, t, 0.f});
        media.push_back(i % 2 ? outer : nullptr);
    }
    for (NullRule rule : {NullRule::PureNull, NullRule::Transmission}) {
        std::vector<RandomStream> streams, streams_one;
        for (size_t i = 0; i < rays.size(); ++i) streams.emplace_back(i), streams_one.emplace_back(i);
        std::vector<SegmentWalk> walks(rays.size());
        WalkBuffers buffers;
        RayCounters batched, single;
        walk_segments(*scene, rays.data(), media.data(), rays.size(), rule, streams.data(), batched, walks.data(),
                      buffers);
        size_t stopped = 0, crossed = 0;
        for (size_t i = 0; i < rays.size(); ++i) {
            const SegmentWalk one = walk_segment(*scene, rays[i], media[i], rule, streams_one[i], single);
            EXPECT_TRUE(same(walks[i], one)) << "segment " << i;
            stopped += one.stopped;
            crossed += one.medium_pieces > 1;
        }
        EXPECT_EQ(batched.shadow_rays, single.shadow_rays);
        // The segments do meet surfaces and cross media.
        EXPECT_GT(stopped, 20u);
        EXPECT_GT(crossed, 20u);
    }
}
