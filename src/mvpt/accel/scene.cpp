#include "scene.h"

#include "ray_packet.h"
#include "../render/embree_errors.h"

#include <algorithm>
#include <cstring>
#include <cstdio>

namespace mvpt {

namespace {
/// Embree's own report; an allocation that failed is reported once, by embree_check.
void embree_error(void *, RTCError code, const char *str) {
    if (code != RTC_ERROR_OUT_OF_MEMORY) std::fprintf(stderr, "mvpt: Embree error %d: %s\n", int(code), str ? str : "");
}
} // namespace

Scene::Scene() {
    m_device = embree_checked(rtcNewDevice(nullptr), nullptr, "its device");
    rtcSetDeviceErrorFunction(m_device, embree_error, nullptr);
    m_scene = embree_checked(rtcNewScene(m_device), m_device, "the scene");
    rtcSetSceneBuildQuality(m_scene, RTC_BUILD_QUALITY_HIGH);
}

Scene::~Scene() {
    m_occluders.reset(); // its nodes live in an Embree BVH of m_device
    m_shapes.clear(); // shapes may own Embree sub-scenes
    if (m_scene) rtcReleaseScene(m_scene);
    if (m_device) rtcReleaseDevice(m_device);
}

void Scene::build(SceneParts parts) {
    m_shapes = std::move(parts.shapes);
    m_lights = std::move(parts.lights);
    m_cameras = std::move(parts.cameras);
    m_integrator = std::move(parts.integrator);
    m_source_files = std::move(parts.source_files);
    m_notes = std::move(parts.notes);
    m_warnings = std::move(parts.warnings);
    for (const auto &light : m_lights)
        if (light->is_environment()) m_environment = light.get();

    // One scene-time -> Embree-time map covering every animated shape's keyframes.
    bool animated = false;
    for (auto &shape : m_shapes) {
        float b, e;
        if (!shape->time_range(b, e)) continue;
        m_motion.t0 = animated ? std::min(m_motion.t0, b) : b;
        m_motion.t1 = animated ? std::max(m_motion.t1, e) : e;
        animated = true;
    }
    m_animated = animated;
    for (auto &shape : m_shapes) {
        unsigned gid = shape->attach(m_device, m_scene, m_motion);
        if (gid >= m_geom_to_shape.size()) m_geom_to_shape.resize(gid + 1, nullptr);
        m_geom_to_shape[gid] = shape.get();
        m_bounds.expand(shape->bounds());
        if (shape->emitter) m_lights.push_back(shape->emitter);
    }
    rtcCommitScene(m_scene);
    embree_check(m_device, "the scene's bounding volume hierarchy");
    auto add_medium = [&](const Medium *m) {
        if (m && std::find(m_media.begin(), m_media.end(), m) == m_media.end()) m_media.push_back(m);
    };
    for (auto &shape : m_shapes) add_medium(shape->interior.get()), add_medium(shape->exterior.get());
    for (auto &cam : m_cameras) add_medium(cam->medium.get());
    m_has_media = !m_media.empty();
    if (m_has_media && (m_integrator->name() == "path" || m_integrator->name() == "mvpath"))
        m_notes.push_back("the scene has participating media, which the '" + m_integrator->name() +
                          "' integrator ignores (as Mitsuba 3's 'path' does): use 'volpath' to render them (with "
                          "either method)");

    Point3f center = m_bounds.valid() ? m_bounds.center() : Point3f(0.f);
    float radius = m_bounds.valid() ? norm(m_bounds.max - center) : 1.f;
    for (auto &l : m_lights) l->set_scene_bounds(center, std::max(radius, 1e-3f));
}

RTCRayHit Scene::to_embree(const Ray &ray) const {
    RTCRayHit r;
    if (embree_can_trace(ray)) {
        r.ray.org_x = ray.o.x; r.ray.org_y = ray.o.y; r.ray.org_z = ray.o.z;
        r.ray.dir_x = ray.d.x; r.ray.dir_y = ray.d.y; r.ray.dir_z = ray.d.z;
        r.ray.tnear = ray.tmin;
        r.ray.tfar = ray.tmax;
    } else { // inactive: tnear > tfar
        r.ray.org_x = r.ray.org_y = r.ray.org_z = 0.f;
        r.ray.dir_x = r.ray.dir_y = 0.f; r.ray.dir_z = 1.f;
        r.ray.tnear = 1.f;
        r.ray.tfar = 0.f;
    }
    r.ray.time = m_animated ? m_motion.to_embree(ray.time) : 0.f;
    r.ray.mask = 0xffffffffu;
    r.ray.flags = 0;
    r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return r;
}

bool Scene::intersect(const Ray &ray, SurfaceInteraction &si) const {
    if (!embree_can_trace(ray)) return false;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh = to_embree(ray);
    rtcIntersect1(m_scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    fill_hit(ray, rh.ray.tfar, rh.hit.geomID, rh.hit.instID[0], rh.hit.primID, {rh.hit.u, rh.hit.v}, si);
    return true;
}

void Scene::fill_hit(const Ray &ray, float t, unsigned geom, unsigned inst, uint32_t prim, Vec2f b,
                     SurfaceInteraction &si) const {
    si.time = ray.time;
    si.prim_uv = b;
    if (inst != RTC_INVALID_GEOMETRY_ID) {
        // Instances resolve the inner geometry and move the hit to world space.
        m_geom_to_shape[inst]->fill_instance_interaction(ray, t, geom, prim, b, si);
        return;
    }
    const Shape *shape = m_geom_to_shape[geom];
    si.shape = shape;
    si.instance = nullptr;
    si.prim = prim;
    shape->fill_interaction(ray, t, prim, b, si);
}

bool Scene::occluded(const Ray &ray) const {
    if (!embree_can_trace(ray)) return false;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = ray.o.x; r.org_y = ray.o.y; r.org_z = ray.o.z;
    r.dir_x = ray.d.x; r.dir_y = ray.d.y; r.dir_z = ray.d.z;
    r.tnear = ray.tmin;
    r.tfar = ray.tmax;
    r.time = m_animated ? m_motion.to_embree(ray.time) : 0.f;
    r.mask = 0xffffffffu;
    r.flags = 0;
    rtcOccluded1(m_scene, &ctx, &r);
    return r.tfar < 0.f;
}

void Scene::intersect(const Ray *rays, size_t n, SurfaceInteraction *si, uint8_t *hit, bool coherent) const {
    if (coherent) intersect_stream(rays, n, si, hit);
    else intersect_packets(rays, n, si, hit);
}

void Scene::intersect_stream(const Ray *rays, size_t n, SurfaceInteraction *si, uint8_t *hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    constexpr size_t Chunk = 256;
    RTCRayHit rh[Chunk];
    for (size_t b = 0; b < n; b += Chunk) {
        size_t m = std::min(Chunk, n - b);
        for (size_t i = 0; i < m; ++i) rh[i] = to_embree(rays[b + i]);
        rtcIntersect1M(m_scene, &ctx, rh, unsigned(m), sizeof(RTCRayHit));
        for (size_t i = 0; i < m; ++i) {
            const RTCRayHit &r = rh[i];
            hit[b + i] = r.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            if (hit[b + i])
                fill_hit(rays[b + i], r.ray.tfar, r.hit.geomID, r.hit.instID[0], r.hit.primID, {r.hit.u, r.hit.v},
                         si[b + i]);
        }
    }
}

void Scene::intersect_packets(const Ray *rays, size_t n, SurfaceInteraction *si, uint8_t *hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    alignas(64) RTCRayHit16 p;
    alignas(64) int valid[16];
    for (size_t i = 0; i < 16; ++i) {
        p.ray.time[i] = 0.f;
        p.ray.mask[i] = 0xffffffffu;
        p.ray.flags[i] = 0;
    }
    for (size_t b = 0; b < n; b += 16) {
        const size_t m = std::min<size_t>(16, n - b);
        pack_ray16(rays + b, uint32_t(m), p.ray, valid);
        if (m_animated)
            for (size_t i = 0; i < 16; ++i) p.ray.time[i] = m_motion.to_embree(rays[b + std::min(i, m - 1)].time);
        for (size_t i = 0; i < 16; ++i) p.hit.geomID[i] = p.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect16(valid, m_scene, &ctx, &p);
        for (size_t i = 0; i < m; ++i) {
            hit[b + i] = valid[i] && p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
            if (hit[b + i])
                fill_hit(rays[b + i], p.ray.tfar[i], p.hit.geomID[i], p.hit.instID[0][i], p.hit.primID[i],
                         {p.hit.u[i], p.hit.v[i]}, si[b + i]);
        }
    }
}

void Scene::prepare_segment_culling(bool enable) const {
    std::lock_guard<std::mutex> lock(m_occluders_mutex); // renders of one scene may start concurrently
    if (!enable || m_animated) m_occluders.reset();
    else if (!m_occluders) m_occluders = std::make_unique<OccluderBvh>(m_device, m_shapes);
}

void Scene::occluded_segments(Point3f o, const float *dx, const float *dy, const float *dz, const float *t_max,
                              size_t n, float time, uint8_t *blocked, Vec3f across) const {
    // Most bundles meet no occluder at all. Culling pays from two packets on: one packet of 8
    // traces faster than the test that would spare it (glossy Cornell box, 8 segments: +12 %
    // time with culling; 5x5 light field, 24 segments: -7 %).
    // When one to four occluders meet the bundle (5x5 light field: most bundles that are not
    // free), each segment is tested against them exactly and only packets with a segment
    // that may meet one are traced (light field: a quarter of those packets, -1.6 %
    // instructions). Untraced lanes are ones Embree would find unblocked: images do not change.
    constexpr int MaxBlockers = 4;
    int64_t blockers[MaxBlockers];
    int n_blockers = -1;
    if (m_occluders && n > 8) {
        SegmentBundle bundle;
        if (bundle.build(o, across, dx, dy, dz, t_max, n)) n_blockers = m_occluders->blockers(bundle, blockers, MaxBlockers);
        if (n_blockers == 0) {
            std::fill(blocked, blocked + n, uint8_t(0));
            return;
        }
    }
    // Which segments those occluders may meet, to a margin far beyond the float rounding of
    // Embree's tests (~1e-7 relative).
    uint8_t maybe[128];
    const bool culled = n_blockers > 0 && n <= sizeof(maybe);
    if (culled) {
        const double a[3] = {o.x, o.y, o.z};
        const double margin = 1e-6 * (1.0 + std::max({std::abs(a[0]), std::abs(a[1]), std::abs(a[2])}));
        std::fill(maybe, maybe + n, uint8_t(0));
        for (int k = 0; k < n_blockers; ++k) m_occluders->may_hit(blockers[k], a, dx, dy, dz, t_max, n, margin, 1e-6, maybe);
    }
    // 8-wide packets flagged incoherent: Embree then traces these nearly parallel segments
    // faster than with the coherent flag (10 % on the glossy Cornell box) or as single rays.
    constexpr size_t Width = 8;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    alignas(32) RTCRay8 p;
    const bool origin_ok = embree_can_trace(Ray{o, Vec3f(0.f, 0.f, 1.f), 0.f, 1.f, time});
    for (size_t i = 0; i < Width; ++i) {
        p.org_x[i] = o.x; p.org_y[i] = o.y; p.org_z[i] = o.z;
        p.time[i] = m_animated ? m_motion.to_embree(time) : 0.f;
        p.mask[i] = 0xffffffffu;
        p.flags[i] = 0;
        p.tnear[i] = 0.f;
    }
    for (size_t b = 0; b < n; b += Width) {
        // The arrays hold whole packets: padding lanes have t_max <= 0 and are not traced.
        std::memcpy(p.dir_x, dx + b, sizeof(p.dir_x));
        std::memcpy(p.dir_y, dy + b, sizeof(p.dir_y));
        std::memcpy(p.dir_z, dz + b, sizeof(p.dir_z));
        std::memcpy(p.tfar, t_max + b, sizeof(p.tfar));
        alignas(32) int valid[Width];
        const size_t m = std::min(Width, n - b);
        bool any = false;
        for (size_t i = 0; i < Width; ++i) {
            valid[i] = -int(origin_ok & (p.tfar[i] > 0.f) && i < m && (!culled || maybe[b + i]));
            any |= valid[i] != 0;
        }
        if (any) rtcOccluded8(valid, m_scene, &ctx, &p);
        for (size_t i = 0; i < m; ++i) blocked[b + i] = (valid[i] != 0) & (p.tfar[i] < 0.f);
    }
}

void Scene::occluded(const Ray *rays, size_t n, uint8_t *blocked) const {
    constexpr size_t Width = 16;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    alignas(64) RTCRay16 p;
    alignas(64) int valid[Width];
    for (size_t i = 0; i < Width; ++i) {
        p.time[i] = 0.f;
        p.mask[i] = 0xffffffffu;
        p.flags[i] = 0;
    }
    for (size_t b = 0; b < n; b += Width) {
        const size_t m = std::min(Width, n - b);
        pack_ray16(rays + b, uint32_t(m), p, valid);
        if (m_animated)
            for (size_t i = 0; i < Width; ++i) p.time[i] = m_motion.to_embree(rays[b + std::min(i, m - 1)].time);
        rtcOccluded16(valid, m_scene, &ctx, &p);
        for (size_t i = 0; i < m; ++i) blocked[b + i] = valid[i] && p.tfar[i] < 0.f;
    }
}

void Scene::occluded(const RayColumns &rays, size_t n, uint8_t *blocked) const {
    constexpr size_t Width = 16;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    const float *const cols[8] = {rays.ox, rays.oy, rays.oz, rays.dx, rays.dy, rays.dz, rays.t_max, rays.time};
    alignas(64) RTCRay16 p;
    for (size_t i = 0; i < Width; ++i) {
        p.mask[i] = 0xffffffffu;
        p.flags[i] = 0;
        p.time[i] = 0.f;
    }
    for (size_t b = 0; b < n; b += Width) {
        const size_t m = std::min(Width, n - b);
        // Whole packets are copied column by column; a last partial one repeats its last ray (inactive).
        alignas(64) float tail[8][Width];
        const float *src[8];
        for (size_t q = 0; q < 8; ++q) {
            src[q] = cols[q] + b;
            if (m < Width) {
                for (size_t i = 0; i < Width; ++i) tail[q][i] = src[q][std::min(i, m - 1)];
                src[q] = tail[q];
            }
        }
        std::memcpy(p.org_x, src[0], sizeof(p.org_x));
        std::memcpy(p.org_y, src[1], sizeof(p.org_y));
        std::memcpy(p.org_z, src[2], sizeof(p.org_z));
        std::memcpy(p.dir_x, src[3], sizeof(p.dir_x));
        std::memcpy(p.dir_y, src[4], sizeof(p.dir_y));
        std::memcpy(p.dir_z, src[5], sizeof(p.dir_z));
        std::memcpy(p.tfar, src[6], sizeof(p.tfar));
        if (m_animated)
            for (size_t i = 0; i < Width; ++i) p.time[i] = m_motion.to_embree(src[7][i]);
        std::fill(p.tnear, p.tnear + Width, 0.f);
        alignas(64) int valid[Width];
        packet_valid(p, uint32_t(m), valid);
        rtcOccluded16(valid, m_scene, &ctx, &p);
        for (size_t i = 0; i < m; ++i) blocked[b + i] = (valid[i] != 0) & (p.tfar[i] < 0.f);
    }
}

} // namespace mvpt
