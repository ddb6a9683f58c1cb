#include "analytic.h"

#include <embree3/rtcore_ray.h>

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

double hit_of(const AnalyticShape *shape, RTCRayN *rays, unsigned n, unsigned i) {
    double o[3] = {RTCRayN_org_x(rays, n, i), RTCRayN_org_y(rays, n, i), RTCRayN_org_z(rays, n, i)};
    double d[3] = {RTCRayN_dir_x(rays, n, i), RTCRayN_dir_y(rays, n, i), RTCRayN_dir_z(rays, n, i)};
    return shape->intersect_t(o, d, RTCRayN_tnear(rays, n, i), RTCRayN_tfar(rays, n, i));
}

void intersect_callback(const RTCIntersectFunctionNArguments *args) {
    auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    RTCRayN *rays = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN *hits = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        double t = hit_of(shape, rays, args->N, i);
        if (std::isnan(t)) continue;
        RTCRayN_tfar(rays, args->N, i) = float(t);
        RTCHitN_Ng_x(hits, args->N, i) = 0.f;
        RTCHitN_Ng_y(hits, args->N, i) = 0.f;
        RTCHitN_Ng_z(hits, args->N, i) = 1.f;
        RTCHitN_u(hits, args->N, i) = 0.f;
        RTCHitN_v(hits, args->N, i) = 0.f;
        RTCHitN_primID(hits, args->N, i) = args->primID;
        RTCHitN_geomID(hits, args->N, i) = args->geomID;
        RTCHitN_instID(hits, args->N, i, 0) = args->context->instID[0];
    }
}

void occluded_callback(const RTCOccludedFunctionNArguments *args) {
    auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        if (!std::isnan(hit_of(shape, args->ray, args->N, i)))
            RTCRayN_tfar(args->ray, args->N, i) = -Infinity;
    }
}

} // namespace

unsigned AnalyticShape::attach(RTCDevice device, RTCScene scene, const MotionTime &) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, this);
    rtcSetGeometryBoundsFunction(g, bounds_callback, nullptr);
    rtcSetGeometryIntersectFunction(g, intersect_callback);
    rtcSetGeometryOccludedFunction(g, occluded_callback);
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    return id;
}

} // namespace mvpt
