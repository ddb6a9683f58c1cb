#include "analytic.h"

#include "../embree_errors.h"

#include <embree3/rtcore_ray.h>

#include <vector>

namespace mvpt {

namespace {

void bounds_callback(const RTCBoundsFunctionArguments *args) {
    auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    BoundingBox b = shape->bounds();
    // Pad by a relative epsilon: the callbacks solve in double precision.
    Vec3f pad = (vmax(vmax(b.max, -b.min), b.max - b.min)) * 1e-5f + Vec3f(1e-6f);
    RTCBounds *o = args->bounds_o;
    o->lower_x = b.min.x - pad.x; o->lower_y = b.min.y - pad.y; o->lower_z = b.min.z - pad.z;
    o->upper_x = b.max.x + pad.x; o->upper_y = b.max.y + pad.y; o->upper_z = b.max.z + pad.z;
}

/// Lanes of one callback call processed at a time (Embree's widest packet).
constexpr unsigned MaxLanes = 16;

void intersect_callback(const RTCIntersectFunctionNArguments *args) {
    auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    RTCRayN *rays = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN *hits = RTCRayHitN_HitN(args->rayhit, args->N);
    const unsigned n = args->N;
    double local[MaxLanes];
    std::vector<double> wide; // wider packets than Embree's documented 16 lanes: not expected
    double *t = n <= MaxLanes ? local : (wide.resize(n), wide.data());
    shape->intersect_t_n(rays, n, args->valid, t);
    for (unsigned i = 0; i < n; ++i) {
        if (std::isnan(t[i])) continue;
        RTCRayN_tfar(rays, n, i) = float(t[i]);
        RTCHitN_Ng_x(hits, n, i) = 0.f;
        RTCHitN_Ng_y(hits, n, i) = 0.f;
        RTCHitN_Ng_z(hits, n, i) = 1.f;
        RTCHitN_u(hits, n, i) = 0.f;
        RTCHitN_v(hits, n, i) = 0.f;
        RTCHitN_primID(hits, n, i) = args->primID;
        RTCHitN_geomID(hits, n, i) = args->geomID;
        RTCHitN_instID(hits, n, i, 0) = args->context->instID[0];
    }
}

void occluded_callback(const RTCOccludedFunctionNArguments *args) {
    auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    const unsigned n = args->N;
    double local[MaxLanes];
    std::vector<double> wide; // wider packets than Embree's documented 16 lanes: not expected
    double *t = n <= MaxLanes ? local : (wide.resize(n), wide.data());
    shape->intersect_t_n(args->ray, n, args->valid, t);
    for (unsigned i = 0; i < n; ++i)
        if (!std::isnan(t[i])) RTCRayN_tfar(args->ray, n, i) = -Infinity;
}

} // namespace

void AnalyticShape::intersect_t_n(const RTCRayN *rays, unsigned n, const int *valid, double *t) const {
    RTCRayN *r = const_cast<RTCRayN *>(rays); // Embree's accessors take non-const packets
    for (unsigned i = 0; i < n; ++i) {
        t[i] = std::nan("");
        if (valid[i] != -1) continue;
        double o[3] = {RTCRayN_org_x(r, n, i), RTCRayN_org_y(r, n, i), RTCRayN_org_z(r, n, i)};
        double d[3] = {RTCRayN_dir_x(r, n, i), RTCRayN_dir_y(r, n, i), RTCRayN_dir_z(r, n, i)};
        t[i] = intersect_t(o, d, RTCRayN_tnear(r, n, i), RTCRayN_tfar(r, n, i));
    }
}

unsigned AnalyticShape::attach(RTCDevice device, RTCScene scene, const MotionTime &) {
    RTCGeometry g = embree_checked(rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER), device, "a shape");
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, this);
    rtcSetGeometryBoundsFunction(g, bounds_callback, nullptr);
    rtcSetGeometryIntersectFunction(g, intersect_callback);
    rtcSetGeometryOccludedFunction(g, occluded_callback);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    embree_check(device, "a shape");
    return id;
}

} // namespace mvpt
