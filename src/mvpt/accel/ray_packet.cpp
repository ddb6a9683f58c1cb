#include "ray_packet.h"

#include "../core/simd_gather.h"

#include <algorithm>
#include <cstddef>

namespace mvpt {

namespace {

/// RTCRay16's fields are arrays of 16 words one after another: the columns of simd::gather.
constexpr uint32_t column(size_t field_offset) { return uint32_t(field_offset / (16 * sizeof(float))); }

/// A ray's origin, direction, tmin and tmax to the packet's fields.
constexpr simd::FieldList RayFields = simd::FieldList()
                                          .add(column(offsetof(RTCRay16, org_x)), offsetof(Ray, o) + 0 * sizeof(float))
                                          .add(column(offsetof(RTCRay16, org_y)), offsetof(Ray, o) + 1 * sizeof(float))
                                          .add(column(offsetof(RTCRay16, org_z)), offsetof(Ray, o) + 2 * sizeof(float))
                                          .add(column(offsetof(RTCRay16, dir_x)), offsetof(Ray, d) + 0 * sizeof(float))
                                          .add(column(offsetof(RTCRay16, dir_y)), offsetof(Ray, d) + 1 * sizeof(float))
                                          .add(column(offsetof(RTCRay16, dir_z)), offsetof(Ray, d) + 2 * sizeof(float))
                                          .add(column(offsetof(RTCRay16, tnear)), offsetof(Ray, tmin))
                                          .add(column(offsetof(RTCRay16, tfar)), offsetof(Ray, tmax));
static_assert(offsetof(RTCRay16, org_x) == 0 && offsetof(RTCRay16, tfar) == 8 * 16 * sizeof(float));

} // namespace

void pack_ray16(const Ray *rays, uint32_t m, RTCRay16 &p, int *valid, bool vector) {
    uint32_t index[16];
    for (uint32_t i = 0; i < 16; ++i) index[i] = std::min(i, m - 1);
    simd::gather<RayFields>(&p, 16, 16, index, rays, sizeof(Ray), vector);
    packet_valid(p, m, valid);
}

} // namespace mvpt
