// pack_ray16 (accel/ray_packet.cpp): 16-wide Embree packets from consecutive rays, by the
// AVX-512 gathers and by the lane loop, against the rays and embree_can_trace.
#include "mvpt/accel/ray_packet.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <vector>

using namespace mvpt;

TEST(RayPacket, PacksRaysAndTheirValidity) {
    // 32 rays: ordinary ones and ones Embree must not trace (a NaN, a coordinate beyond its range).
    std::vector<Ray> rays(32);
    const float nan = std::nanf("");
    for (size_t i = 0; i < rays.size(); ++i) {
        const float x = float(i);
        rays[i] = Ray{{x, -x, 0.5f * x}, {0.1f * x, 1.f, -0.2f}, 0.01f * x, 10.f + x, 0.f};
        switch (i % 6) {
        case 1: rays[i].o.y = nan; break;
        case 2: rays[i].d.z = -1e19f; break;
        case 3: rays[i].tmax = nan; break;
        case 4: rays[i].tmin = nan; break;
        case 5: rays[i].d.x = -1.844e18f; break; // Embree's bound itself: traceable
        default: break;
        }
    }
    for (uint32_t m : {16u, 11u, 1u}) {
        for (uint32_t start : {0u, 5u, 16u}) {
            alignas(64) RTCRay16 pv, ps;
            alignas(64) int valid_v[16], valid_s[16];
            pack_ray16(rays.data() + start, m, pv, valid_v, true);
            pack_ray16(rays.data() + start, m, ps, valid_s, false);
            for (uint32_t i = 0; i < 16; ++i) {
                const Ray &r = rays[start + std::min(i, m - 1)]; // lanes from m on repeat the last ray
                const bool active = i < m && embree_can_trace(rays[start + i]);
                for (const RTCRay16 *p : {&pv, &ps}) {
                    // Lanes left out are also inactive as a ray stream's (tnear 1 > tfar 0).
                    const float expect[8] = {r.o.x, r.o.y, r.o.z, r.d.x, r.d.y, r.d.z, active ? r.tmin : 1.f,
                                             active ? r.tmax : 0.f};
                    const float got[8] = {p->org_x[i], p->org_y[i], p->org_z[i], p->dir_x[i],
                                          p->dir_y[i], p->dir_z[i], p->tnear[i], p->tfar[i]};
                    for (int f = 0; f < 8; ++f)
                        ASSERT_EQ(std::bit_cast<uint32_t>(got[f]), std::bit_cast<uint32_t>(expect[f]))
                            << "m " << m << " lane " << i << " field " << f;
                }
                const int expect_valid = active ? -1 : 0;
                EXPECT_EQ(valid_v[i], expect_valid) << "m " << m << " start " << start << " lane " << i;
                EXPECT_EQ(valid_s[i], expect_valid) << "m " << m << " start " << start << " lane " << i;
            }
        }
    }
    // The cases above each make a ray untraceable.
    EXPECT_FALSE(embree_can_trace(rays[1]));
    EXPECT_FALSE(embree_can_trace(rays[2]));
    EXPECT_FALSE(embree_can_trace(rays[3]));
    EXPECT_FALSE(embree_can_trace(rays[4]));
    EXPECT_TRUE(embree_can_trace(rays[5]));
    EXPECT_TRUE(embree_can_trace(rays[6]));
}
