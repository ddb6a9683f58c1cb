// Embree query cost per ray on a scene's own rays: one by one (rtcIntersect1), as 8/16-wide
// packets, as streams (rtcIntersect1M, coherent or not), for camera rays (tile order, as the
// renderer makes them), secondary and tertiary rays (cosine-distributed bounces) and shadow
// rays to the first light. The measure behind the wavefront path tracer's choice of
// queries (README, Performance). Process CPU time, best of 7.
//
//   python bench/profile_paths.py cbox-rgb --res 64 --write-xml /tmp/cbox.xml   # prints BASE
//   build/prof/mvpt_embree_rays /tmp/cbox.xml BASE 4                           # 4 spp of camera rays
#include "mvpt/loader/load_scene.h"
#include "mvpt/renderer/renderer.h"
#include "mvpt/core/warp.h"
#include "mvpt/render/bsdf.h"
#include <chrono>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>
using namespace mvpt;
/// CPU time of this process: unaffected by other processes sharing the cores.
static double cpu_seconds() { timespec ts; clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts); return ts.tv_sec + 1e-9 * ts.tv_nsec; }

static void fill(RTCRayHit &rh, const Ray &r) {
    rh.ray.org_x = r.o.x; rh.ray.org_y = r.o.y; rh.ray.org_z = r.o.z;
    rh.ray.dir_x = r.d.x; rh.ray.dir_y = r.d.y; rh.ray.dir_z = r.d.z;
    rh.ray.tnear = r.tmin; rh.ray.tfar = r.tmax; rh.ray.time = 0; rh.ray.mask = ~0u; rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID; rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}
template <int N, typename RH> static void fillN(RH &p, int i, const Ray &r) {
    p.ray.org_x[i] = r.o.x; p.ray.org_y[i] = r.o.y; p.ray.org_z[i] = r.o.z;
    p.ray.dir_x[i] = r.d.x; p.ray.dir_y[i] = r.d.y; p.ray.dir_z[i] = r.d.z;
    p.ray.tnear[i] = r.tmin; p.ray.tfar[i] = r.tmax; p.ray.time[i] = 0; p.ray.mask[i] = ~0u; p.ray.flags[i] = 0;
    p.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID; p.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

int main(int argc, char **argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s scene.xml base_dir spp\n", argv[0]);
        return 2;
    }
    std::ifstream in(argv[1]); std::stringstream xml; xml << in.rdbuf();
    auto scene = load_scene_string(xml.str(), argv[2]);
    int spp = atoi(argv[3]);
    RTCScene sc = scene->embree_scene();
    const Camera &cam = *scene->cameras()[0];
    int W = cam.film.crop_width, H = cam.film.crop_height;
    std::vector<Ray> cam_rays, sec_rays, shadow_rays, ter_rays;
    Sampler smp;
    for (int s = 0; s < spp; ++s)
      for (int ty = 0; ty < H; ty += 16) for (int tx = 0; tx < W; tx += 16)
        for (int y = ty; y < std::min(H, ty + 16); ++y) for (int x = tx; x < std::min(W, tx + 16); ++x) {
            smp.start(0, x, y, s);
            Vec2f u = smp.next_2d();
            cam_rays.push_back(cam.generate_ray({x + u.x, y + u.y}, {0, 0}, 0));
        }
    auto bounce = [&](const std::vector<Ray> &rays, std::vector<Ray> &out, std::vector<Ray> *sh) {
        for (size_t i = 0; i < rays.size(); ++i) {
            SurfaceInteraction si;
            if (!scene->intersect(rays[i], si)) continue;
            smp.start(1, i, 0, 0);
            Vec3f wo = warp::square_to_cosine_hemisphere(smp.next_2d());
            if (dot(si.sh_frame.n, rays[i].d) > 0) wo.z = -wo.z;
            out.push_back(si.spawn_ray(si.to_world(wo)));
            if (sh) {
                auto [ls, w] = scene->lights()[0]->sample_li(si.p, smp.next_2d(), 0);
                sh->push_back(si.spawn_ray_to(ls.p));
            }
        }
    };
    bounce(cam_rays, sec_rays, &shadow_rays);
    bounce(sec_rays, ter_rays, &shadow_rays);
    // Rays of each 256-batch reordered by direction octant (counting sort).
    auto octant_sorted = [](const std::vector<Ray> &rays) {
        std::vector<Ray> out;
        for (size_t b = 0; b < rays.size(); b += 256) {
            size_t e = std::min(rays.size(), b + 256);
            for (int o = 0; o < 8; ++o)
                for (size_t i = b; i < e; ++i)
                    if (((rays[i].d.x < 0) | ((rays[i].d.y < 0) << 1) | ((rays[i].d.z < 0) << 2)) == o) out.push_back(rays[i]);
        }
        return out;
    };
    std::vector<Ray> sec_sorted = octant_sorted(sec_rays), ter_sorted = octant_sorted(ter_rays), shadow_sorted = octant_sorted(shadow_rays);
    std::printf("%zu camera, %zu secondary, %zu tertiary, %zu shadow rays\n", cam_rays.size(), sec_rays.size(), ter_rays.size(), shadow_rays.size());
    const int reps = 7;
    auto bench = [&](const char *name, const std::vector<Ray> &rays, auto fn) {
        double best = 1e30; long hits = 0;
        for (int r = 0; r < reps; ++r) {
            double t0 = cpu_seconds(); hits = fn(rays);
            best = std::min(best, cpu_seconds() - t0);
        }
        std::printf("  %-28s %7.1f ns/ray  (hits %ld)\n", name, best / rays.size() * 1e9, hits);
    };
    auto one = [&](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
        for (auto &r : rays) { RTCRayHit rh; fill(rh, r); rtcIntersect1(sc, &ctx, &rh); h += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID; } return h; };
    auto scene_one = [&](const std::vector<Ray> &rays) { long h = 0; for (auto &r : rays) { SurfaceInteraction si; h += scene->intersect(r, si); } return h; };
    auto p8 = [&](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
        for (size_t b = 0; b < rays.size(); b += 8) { alignas(32) RTCRayHit8 p; alignas(32) int valid[8];
          for (int i = 0; i < 8; ++i) { valid[i] = b + i < rays.size() ? -1 : 0; fillN<8>(p, i, rays[std::min(b + i, rays.size() - 1)]); }
          rtcIntersect8(valid, sc, &ctx, &p); for (int i = 0; i < 8; ++i) h += valid[i] && p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID; } return h; };
    auto p16 = [&](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
        for (size_t b = 0; b < rays.size(); b += 16) { alignas(64) RTCRayHit16 p; alignas(64) int valid[16];
          for (int i = 0; i < 16; ++i) { valid[i] = b + i < rays.size() ? -1 : 0; fillN<16>(p, i, rays[std::min(b + i, rays.size() - 1)]); }
          rtcIntersect16(valid, sc, &ctx, &p); for (int i = 0; i < 16; ++i) h += valid[i] && p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID; } return h; };
    auto stream = [&](RTCIntersectContextFlags f) { return [&, f](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx); ctx.flags = f;
        std::vector<RTCRayHit> buf(256);
        for (size_t b = 0; b < rays.size(); b += 256) { size_t n = std::min<size_t>(256, rays.size() - b);
          for (size_t i = 0; i < n; ++i) fill(buf[i], rays[b + i]);
          rtcIntersect1M(sc, &ctx, buf.data(), n, sizeof(RTCRayHit)); for (size_t i = 0; i < n; ++i) h += buf[i].hit.geomID != RTC_INVALID_GEOMETRY_ID; } return h; }; };
    auto occ1 = [&](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
        for (auto &r : rays) { RTCRayHit rh; fill(rh, r); rtcOccluded1(sc, &ctx, &rh.ray); h += rh.ray.tfar < 0; } return h; };
    auto occ16 = [&](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
        for (size_t b = 0; b < rays.size(); b += 16) { alignas(64) RTCRayHit16 p; alignas(64) int valid[16];
          for (int i = 0; i < 16; ++i) { valid[i] = b + i < rays.size() ? -1 : 0; fillN<16>(p, i, rays[std::min(b + i, rays.size() - 1)]); }
          rtcOccluded16(valid, sc, &ctx, &p.ray); for (int i = 0; i < 16; ++i) h += valid[i] && p.ray.tfar[i] < 0; } return h; };
    auto occ8 = [&](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx);
        for (size_t b = 0; b < rays.size(); b += 8) { alignas(32) RTCRayHit8 p; alignas(32) int valid[8];
          for (int i = 0; i < 8; ++i) { valid[i] = b + i < rays.size() ? -1 : 0; fillN<8>(p, i, rays[std::min(b + i, rays.size() - 1)]); }
          rtcOccluded8(valid, sc, &ctx, &p.ray); for (int i = 0; i < 8; ++i) h += valid[i] && p.ray.tfar[i] < 0; } return h; };
    auto occM = [&](RTCIntersectContextFlags f) { return [&, f](const std::vector<Ray> &rays) { long h = 0; RTCIntersectContext ctx; rtcInitIntersectContext(&ctx); ctx.flags = f;
        std::vector<RTCRayHit> buf(256);
        for (size_t b = 0; b < rays.size(); b += 256) { size_t n = std::min<size_t>(256, rays.size() - b);
          for (size_t i = 0; i < n; ++i) fill(buf[i], rays[b + i]);
          rtcOccluded1M(sc, &ctx, (RTCRay *)buf.data(), n, sizeof(RTCRayHit)); for (size_t i = 0; i < n; ++i) h += buf[i].ray.tfar < 0; } return h; }; };
    for (auto [nm, rs] : {std::pair<const char *, std::vector<Ray> *>{"camera", &cam_rays}, {"secondary", &sec_rays}, {"tertiary", &ter_rays}, {"secondary sorted", &sec_sorted}, {"tertiary sorted", &ter_sorted}}) {
        std::printf("%s\n", nm);
        bench("Scene::intersect", *rs, scene_one);
        bench("rtcIntersect1", *rs, one);
        bench("rtcIntersect8", *rs, p8);
        bench("rtcIntersect16", *rs, p16);
        bench("rtcIntersect1M incoherent", *rs, stream(RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT));
        bench("rtcIntersect1M coherent", *rs, stream(RTC_INTERSECT_CONTEXT_FLAG_COHERENT));
    }
    std::printf("shadow\n");
    bench("rtcOccluded1", shadow_rays, occ1);
    bench("rtcOccluded8", shadow_rays, occ8);
    bench("rtcOccluded16", shadow_rays, occ16);
    bench("rtcOccluded1M incoherent", shadow_rays, occM(RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT));
    bench("rtcOccluded1M coherent", shadow_rays, occM(RTC_INTERSECT_CONTEXT_FLAG_COHERENT));
    bench("rtcOccluded16 sorted", shadow_sorted, occ16);
}
