// Our rays as Embree's 16-wide packets: which rays Embree may trace, and the packing of up
// to 16 consecutive rays into a packet's fields with its valid mask.
#pragma once

#include "../core/math.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <cstdint>

namespace mvpt {

/// Embree's RayK::valid() on a ray's fields: |origin|, |direction| <= FLT_LARGE (1.844e18)
/// and no NaN in the range. Its release builds may misbehave and its debug builds abort on
/// other rays, so a NaN or absurdly distant ray is treated as a miss (its sample is then
/// usually non-finite and counted as such).
inline bool embree_can_trace(float ox, float oy, float oz, float dx, float dy, float dz, float tnear, float tfar) {
    constexpr float large = 1.844e18f;
    // Branch-free: a NaN fails its comparison and so the conjunction.
    bool finite = (std::abs(ox) <= large) & (std::abs(oy) <= large) & (std::abs(oz) <= large) &
                  (std::abs(dx) <= large) & (std::abs(dy) <= large) & (std::abs(dz) <= large);
    return finite & (tnear == tnear) & (tfar == tfar);
}

inline bool embree_can_trace(const Ray &ray) {
    return embree_can_trace(ray.o.x, ray.o.y, ray.o.z, ray.d.x, ray.d.y, ray.d.z, ray.tmin, ray.tmax);
}

/// Makes the lanes that `valid` leaves out inactive as Embree's ray streams see them (tnear >
/// tfar). Where Embree has no 16-wide kernels for the CPU (no AVX-512), rtcIntersect16 and
/// rtcOccluded16 trace the packet as a stream, which ignores the valid mask: those lanes would
/// be traced (a NaN ray then trips Embree's checks).
template <class RayK>
void deactivate_invalid(RayK &r, const int *valid) {
    for (uint32_t i = 0; i < 16; ++i)
        if (!valid[i]) r.tnear[i] = 1.f, r.tfar[i] = 0.f;
}

/// `embree_can_trace` of a 16-wide packet's lanes (SoA, after packing) as Embree's valid
/// mask, lanes from `m` on inactive (and deactivate_invalid): one vector loop instead of a
/// test per Ray.
template <class RayK>
void packet_valid(RayK &r, uint32_t m, int *valid) {
    for (uint32_t i = 0; i < 16; ++i) {
        bool ok = (i < m) & embree_can_trace(r.org_x[i], r.org_y[i], r.org_z[i], r.dir_x[i], r.dir_y[i], r.dir_z[i],
                                             r.tnear[i], r.tfar[i]);
        valid[i] = ok ? -1 : 0;
    }
    deactivate_invalid(r, valid);
}

/// Origin, direction, tnear and tfar of packet `p` from rays[0 .. m), 1 <= m <= 16 (lanes
/// from m on repeat ray m - 1), and its valid mask (embree_can_trace; lanes from m
/// inactive), the lanes it leaves out deactivated (deactivate_invalid). Where the CPU has
/// AVX-512, one gather per field: the packet is then written with whole-vector stores, which Embree's vector loads forward from (after 16 narrow
/// stores per field they wait for them). `vector` = false takes the lane loop on any CPU.
void pack_ray16(const Ray *rays, uint32_t m, RTCRay16 &p, int *valid, bool vector = true);

} // namespace mvpt
