// The sphere's packet intersection (AnalyticShape::intersect_t_n, a vector loop over the lanes
// that Embree hands to the user-geometry callbacks) against its one-ray intersect_t, bit for
// bit, on rays that hit, miss, start inside, stop just short of the surface (shadow rays
// towards a sampled point) or graze it; and the packets' valid masks.
#include "mvpt/core/sampler.h"
#include "mvpt/core/warp.h"
#include "mvpt/render/shapes/analytic.h"
#include "mvpt/loader/load_scene.h"

#include <embree3/rtcore_ray.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

using namespace mvpt;

namespace {

const char *SphereScene = R"(<scene version="3.0.0">
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
    <shape type="sphere"><point name="center" value="0.3, -0.2, 0.7"/><float name="radius" value="0.8"/></shape>
</scene>)";

/// One packet of `n` lanes in RTCRayN's layout (org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, time, tfar).
struct Packet {
    unsigned n;
    std::vector<float> soa;
    std::vector<int> valid;
    explicit Packet(unsigned lanes) : n(lanes), soa(9 * lanes, 0.f), valid(lanes, -1) {}
    float &at(int field, unsigned i) { return soa[field * n + i]; }
};

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

} // namespace

TEST(SpherePackets, PacketIntersectionBitIdenticalToOneRay) {
    auto scene = load_scene_string(SphereScene, ".");
    const auto *sphere = dynamic_cast<const AnalyticShape *>(scene->shapes().at(0).get());
    ASSERT_NE(sphere, nullptr);
    const Point3f center(0.3f, -0.2f, 0.7f);
    const float radius = 0.8f;
    Sampler sampler(SamplerKind::Independent, 7);
    size_t hits = 0, misses = 0;
    for (unsigned lanes : {1u, 4u, 8u, 16u}) {
        for (int round = 0; round < 400; ++round) {
            Packet p(lanes);
            sampler.start(0, lanes, uint32_t(round), 0);
            for (unsigned i = 0; i < lanes; ++i) {
                // Origins outside, inside or on the sphere; directions at it or random; segments
                // ending short of a point on the surface, at infinity, or with tmin > 0.
                Vec3f on = warp::square_to_uniform_sphere(sampler.next_2d());
                Point3f target = center + on * radius;
                float shell = 0.5f + 3.f * sampler.next_1d();
                Point3f o = center + warp::square_to_uniform_sphere(sampler.next_2d()) * (radius * shell);
                if (i % 5 == 4) o = target; // on the surface (a spawned ray, before its offset)
                Vec3f d = sampler.next_1d() < 0.7f ? target - o : warp::square_to_uniform_sphere(sampler.next_2d());
                float len = norm(d);
                if (len > 0.f) d = d / len;
                float u = sampler.next_1d();
                float tmax = u < 0.4f ? len * (1.f - 1e-4f) : u < 0.7f ? Infinity : len * (1.f + 1e-6f);
                float tmin = sampler.next_1d() < 0.2f ? 0.3f * len : 0.f;
                const float f[9] = {o.x, o.y, o.z, tmin, d.x, d.y, d.z, 0.f, tmax};
                for (int k = 0; k < 9; ++k) p.at(k, i) = f[k];
                p.valid[i] = sampler.next_1d() < 0.15f ? 0 : -1;
            }
            std::vector<double> t(lanes);
            sphere->intersect_t_n(reinterpret_cast<const RTCRayN *>(p.soa.data()), lanes, p.valid.data(), t.data());
            for (unsigned i = 0; i < lanes; ++i) {
                if (p.valid[i] != -1) {
                    EXPECT_TRUE(std::isnan(t[i])) << "an invalid lane was intersected";
                    continue;
                }
                const double o[3] = {p.at(0, i), p.at(1, i), p.at(2, i)}, d[3] = {p.at(4, i), p.at(5, i), p.at(6, i)};
                double ref = sphere->intersect_t(o, d, p.at(3, i), p.at(8, i));
                ASSERT_TRUE(same_bits(t[i], ref) || (std::isnan(t[i]) && std::isnan(ref)))
                    << lanes << " lanes, lane " << i << ": packet " << t[i] << ", one ray " << ref;
                (std::isnan(ref) ? misses : hits) += 1;
                if (!std::isnan(ref)) { // a hit lies on the sphere
                    double q2 = 0;
                    for (int k = 0; k < 3; ++k) q2 += std::pow(o[k] + ref * d[k] - double(center[k]), 2);
                    EXPECT_NEAR(std::sqrt(q2), radius, 1e-5);
                }
            }
        }
    }
    // Both outcomes are well represented.
    EXPECT_GT(hits, 1000u);
    EXPECT_GT(misses, 1000u);
}
