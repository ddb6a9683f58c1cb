// Our rays as Embree's 16-wide packets: which rays Embree may trace, and the packing of up
// to 16 consecutive rays into a packet's fields with its valid mask.
#pragma once

#include "../core/math.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstdint>

namespace mvpt {

/// Embree's RayK::valid(): |origin|, |direction| <= FLT_LARGE (1.844e18) and no NaN in the
/// range. Its release builds may misbehave and its debug builds abort on other rays, so a
/// NaN or absurdly distant ray is treated as a miss (its sample is then usually non-finite
/// and counted as such).
inline bool embree_can_trace(const Ray &ray) {
    constexpr float large = 1.844e18f;
    // Branch-free: a NaN fails its comparison and so the conjunction.
    bool finite = (std::abs(ray.o.x) <= large) & (std::abs(ray.o.y) <= large) & (std::abs(ray.o.z) <= large) &
                  (std::abs(ray.d.x) <= large) & (std::abs(ray.d.y) <= large) & (std::abs(ray.d.z) <= large);
    return finite & (ray.tmin == ray.tmin) & (ray.tmax == ray.tmax);
}

/// `embree_can_trace` of a 16-wide packet's lanes (SoA, after packing) as Embree's valid
/// mask, lanes from `m` on inactive: one vector loop instead of a test per Ray.
template <class RayK>
void packet_valid(const RayK &r, uint32_t m, int *valid) {
    constexpr float large = 1.844e18f;
    for (uint32_t i = 0; i < 16; ++i) {
        bool finite = (std::abs(r.org_x[i]) <= large) & (std::abs(r.org_y[i]) <= large) &
                      (std::abs(r.org_z[i]) <= large) & (std::abs(r.dir_x[i]) <= large) &
                      (std::abs(r.dir_y[i]) <= large) & (std::abs(r.dir_z[i]) <= large);
        bool ok = (i < m) & finite & (r.tnear[i] == r.tnear[i]) & (r.tfar[i] == r.tfar[i]);
        valid[i] = ok ? -1 : 0;
    }
}

/// Origin, direction, tnear and tfar of packet `p` from rays[0 .. m), 1 <= m <= 16 (lanes
/// from m on repeat ray m - 1), and its valid mask (embree_can_trace; lanes from m
/// inactive). Where the CPU has AVX-512, one gather per field: the packet is then written
/// with whole-vector stores, which Embree's vector loads forward from (after 16 narrow
/// stores per field they wait for them). `vector` = false takes the lane loop on any CPU.
void pack_ray16(const Ray *rays, uint32_t m, RTCRay16 &p, int *valid, bool vector = true);

} // namespace mvpt
