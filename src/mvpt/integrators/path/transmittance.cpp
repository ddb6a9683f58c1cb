#include "transmittance.h"

#include "../../render/bsdf.h"
#include "../../render/medium.h"
#include "../../render/shape.h"
#include "../../accel/scene.h"

namespace mvpt {

namespace {
/// Longest chain of null surfaces a segment crosses before it counts as blocked.
constexpr int MaxNullCrossings = 256;

/// Moves `ray` past the null surface `si` that it met, into the medium beyond (`medium`), for
/// the rest of its segment towards `target` (at infinity unless `finite`); false when nothing
/// of the segment is left.
bool step_past(const SurfaceInteraction &si, Point3f target, bool finite, Ray &ray, const Medium *&medium) {
    if (si.shape->is_medium_transition()) medium = si.shape->target_medium(ray.d, si.n);
    const Point3f o = si.offset_p(ray.d);
    const float rest = finite ? dot(target - o, ray.d) : Infinity;
    if (!(rest > 0.f)) return false;
    ray = Ray{o, ray.d, 0.f, rest, ray.time};
    return true;
}
} // namespace

namespace {
/// One piece of a walk from `origin` towards `target`: `ray` reached `si` (`hit`) or its end,
/// through `medium`. Updates the walk, and the ray and medium past a surface the rule passes;
/// false when the walk has ended.
bool walk_piece(SegmentWalk &w, Ray &ray, const Medium *&medium, bool hit, const SurfaceInteraction &si, NullRule rule,
                RandomStream &rs, Point3f origin, Point3f target, bool finite) {
    if (medium) {
        w.tr *= medium->transmittance(ray, hit ? si.t : ray.tmax, rs);
        ++w.medium_pieces;
        w.piece_medium = medium;
        w.piece_t0 = dot(ray.o - origin, ray.d);
        w.piece_t1 = w.piece_t0 + (hit ? si.t : ray.tmax);
    }
    w.medium = medium;
    if (!hit) return false;
    const Bsdf &bsdf = *si.shape->bsdf;
    if (rule == NullRule::PureNull ? bsdf.flags() != BsdfNull : (w.tr *= bsdf.null_transmission(si)).is_black()) {
        w.stopped = true;
        w.si = si;
        if (rule == NullRule::Transmission) w.tr = Spectrum(0.f);
        return false;
    }
    w.crossed_emitter |= si.shape->emitter != nullptr;
    if (!step_past(si, target, finite, ray, medium)) {
        w.medium = medium;
        return false;
    }
    return true;
}

/// A walk that crossed MaxNullCrossings null surfaces: blocked.
void too_many_crossings(SegmentWalk &w) {
    w.stopped = true;
    w.tr = Spectrum(0.f);
}
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
        if (!walk_piece(w, ray, medium, hit, si, rule, rs, origin, target, finite)) return w;
    }
    too_many_crossings(w);
    return w;
}

void walk_segments(const Scene &scene, const Ray *rays, const Medium *const *media, size_t n, NullRule rule,
                   RandomStream *rs, RayCounters &counters, SegmentWalk *walks, WalkBuffers &buf) {
    buf.lane.resize(n), buf.rays.resize(n), buf.media.resize(n), buf.si.resize(n), buf.hit.resize(n);
    size_t active = 0;
    for (size_t i = 0; i < n; ++i) {
        walks[i] = SegmentWalk{};
        buf.lane[active] = uint32_t(i), buf.rays[active] = rays[i], buf.media[active++] = media[i];
    }
    for (int crossing = 0; crossing < MaxNullCrossings && active > 0; ++crossing) {
        counters.shadow_rays += active;
        std::fill(buf.si.begin(), buf.si.begin() + ptrdiff_t(active), SurfaceInteraction{}); // as walk_segment's
        scene.intersect(buf.rays.data(), active, buf.si.data(), buf.hit.data(), true);
        size_t next = 0; // the walks that go on move to the front, in order
        for (size_t a = 0; a < active; ++a) {
            const uint32_t i = buf.lane[a];
            const Ray &start = rays[i];
            const bool on = walk_piece(walks[i], buf.rays[a], buf.media[a], buf.hit[a] != 0, buf.si[a], rule, rs[i],
                                       start.o, start.at(start.tmax), std::isfinite(start.tmax));
            if (!on) continue;
            buf.lane[next] = i, buf.rays[next] = buf.rays[a], buf.media[next++] = buf.media[a];
        }
        active = next;
    }
    for (size_t a = 0; a < active; ++a) too_many_crossings(walks[buf.lane[a]]);
}

SegmentFlight flight_along_segment(const Scene &scene, Ray ray, const Medium *medium, float u,
                                   RayCounters &counters) {
    SegmentFlight f;
    const float u3 = u * 3.f;
    const int c = std::min(int(u3), 2);
    float tau = -std::log1p(-std::min(u3 - float(c), OneMinusEpsilon)); // optical depth left in channel c
    const Point3f target = ray.at(ray.tmax);
    const bool finite = std::isfinite(ray.tmax);
    for (int crossing = 0; crossing < MaxNullCrossings; ++crossing) {
        Spectrum sigma(0.f);
        if (medium && !medium->constant_extinction(sigma)) return f;
        // Where the flight ends if no surface comes first.
        const float t_end = sigma[c] > 0.f ? tau / sigma[c] : Infinity;
        Ray query = ray;
        query.tmax = std::min(ray.tmax, t_end);
        SurfaceInteraction si;
        ++counters.rays;
        const bool hit = scene.intersect(query, si);
        if (!hit && t_end < ray.tmax) { // it scatters in this piece
            for (int i = 0; i < 3; ++i) f.tr[i] *= std::exp(-sigma[i] * t_end);
            f.scattered = true;
            f.p = ray.at(t_end);
            f.medium = medium;
            f.pdf = (sigma[0] * f.tr[0] + sigma[1] * f.tr[1] + sigma[2] * f.tr[2]) * (1.f / 3.f);
            return f;
        }
        if (!hit) return f; // it leaves the segment
        for (int i = 0; i < 3; ++i) f.tr[i] *= std::exp(-sigma[i] * si.t);
        tau -= sigma[c] * si.t;
        if (si.shape->bsdf->flags() != BsdfNull) return f; // the surface term's vertex (§10)
        if (!step_past(si, target, finite, ray, medium)) return f;
    }
    return f;
}

} // namespace mvpt
