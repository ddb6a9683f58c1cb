#include "transmittance.h"

#include "../render/bsdf.h"
#include "../render/medium.h"
#include "../render/shape.h"
#include "../scene/scene.h"

namespace mvpt {

namespace {
/// Longest chain of null surfaces a segment crosses before it counts as blocked.
constexpr int MaxNullCrossings = 256;
} // namespace

SegmentWalk walk_segment(const Scene &scene, Ray ray, const Medium *medium, NullRule rule, RandomStream &rs,
                         RayCounters &counters) {
    SegmentWalk w;
    const Point3f target = ray.at(ray.tmax), origin = ray.o;
    const bool finite = std::isfinite(ray.tmax);
    for (int crossing = 0; crossing < MaxNullCrossings; ++crossing) {
        SurfaceInteraction si;
        ++counters.shadow_rays;
        const bool hit = scene.intersect(ray, si);
        if (medium) {
            w.tr *= medium->transmittance(ray, hit ? si.t : ray.tmax, rs);
            ++w.medium_pieces;
            w.piece_medium = medium;
            w.piece_t0 = dot(ray.o - origin, ray.d);
            w.piece_t1 = w.piece_t0 + (hit ? si.t : ray.tmax);
        }
        w.medium = medium;
        if (!hit) return w;
        const Bsdf &bsdf = *si.shape->bsdf;
        if (rule == NullRule::PureNull ? bsdf.flags() != BsdfNull : (w.tr *= bsdf.null_transmission(si)).is_black()) {
            w.stopped = true;
            w.si = si;
            if (rule == NullRule::Transmission) w.tr = Spectrum(0.f);
            return w;
        }
        w.crossed_emitter |= si.shape->emitter != nullptr;
        if (si.shape->is_medium_transition()) medium = si.shape->target_medium(ray.d, si.n);
        si.time = ray.time;
        Point3f o = si.offset_p(ray.d);
        float rest = finite ? dot(target - o, ray.d) : Infinity;
        if (!(rest > 0.f)) {
            w.medium = medium;
            return w;
        }
        ray = Ray{o, ray.d, 0.f, rest, ray.time};
    }
    w.stopped = true;
    w.tr = Spectrum(0.f);
    return w;
}

} // namespace mvpt
