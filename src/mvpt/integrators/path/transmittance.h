// Segments through participating media and null surfaces (docs/media.md): the transmittance
// of a volumetric path's shadow rays, and the camera segments that multi-view path tracing
// shares a surface vertex along (docs/multiview-path-tracing.md §10).
#pragma once

#include "../../core/sampler.h"
#include "../../render/interaction.h"
#include "../../render/integrator.h"

#include <vector>

namespace mvpt {

class Medium;
class Scene;

/// Which surfaces a segment passes.
enum class NullRule {
    /// Those that let light through (null_transmission > 0; a mask keeps 1 - opacity): shadow rays.
    Transmission,
    /// Only surfaces whose BSDF is `null`: camera segments of multi-view path tracing, whose
    /// shared vertex is the first surface where a path could scatter (§10).
    PureNull,
};

/// Where a walk along a segment ended.
struct SegmentWalk {
    /// A surface the rule does not pass lies on the segment (`si`), or the walk crossed too
    /// many null surfaces (then `si` is invalid).
    bool stopped = false;
    SurfaceInteraction si;
    /// Transmittance from the start to where the walk ended (an unbiased estimate in
    /// heterogeneous media); zero when stopped under NullRule::Transmission.
    Spectrum tr{1.f};
    /// The medium the segment is in where the walk ended.
    const Medium *medium = nullptr;
    /// The pieces of the segment inside a medium: how many, and the last one's medium and its
    /// extent [t0, t1) along the walked ray; whether a null surface crossed is an emitter.
    int medium_pieces = 0;
    const Medium *piece_medium = nullptr;
    float piece_t0 = 0.f, piece_t1 = 0.f;
    bool crossed_emitter = false;
};

/// Walks `ray` (unit direction) over [0, ray.tmax) from its origin, starting in `medium`,
/// through the surfaces `rule` passes.
SegmentWalk walk_segment(const Scene &scene, Ray ray, const Medium *medium, NullRule rule, RandomStream &rs,
                         RayCounters &counters);

/// Buffers of walk_segments, reused between calls.
struct WalkBuffers {
    std::vector<uint32_t> lane;
    std::vector<Ray> rays;
    std::vector<const Medium *> media;
    std::vector<SurfaceInteraction> si;
    std::vector<uint8_t> hit;
};

/// walk_segment for n segments at once, their rays traced as packets crossing by crossing:
/// walks[i] is walk_segment(scene, rays[i], media[i], rule, rs[i], counters), bit for bit.
void walk_segments(const Scene &scene, const Ray *rays, const Medium *const *media, size_t n, NullRule rule,
                   RandomStream *rs, RayCounters &counters, SegmentWalk *walks, WalkBuffers &buf);

/// A free flight along a camera segment, drawn once over the whole segment (multi-view path
/// tracing's medium vertices, docs/multiview-path-tracing.md §10).
struct SegmentFlight {
    bool scattered = false; ///< false: it reached the segment's first surface that is not null (or its end)
    Point3f p;              ///< where it scattered
    const Medium *medium = nullptr; ///< the medium it scattered in
    Spectrum tr{1.f};       ///< transmittance from the start to p
    float pdf = 0.f;        ///< density of p per unit length: 1/3 sum_c sigma_c tr_c
};

/// A free flight along `ray` (unit direction) over [0, ray.tmax), starting in `medium`, through
/// surfaces whose BSDF is `null`, in media of constant extinction: channel c = floor(3u), and
/// the rest of u an optical depth tau ~ Exp(1); it scatters where channel c's optical depth
/// from the start reaches tau. The point's density is the mixture over channels,
/// 1/3 sum_c sigma_c(p) T_c(p): a function of the segment to p alone. No scattering where a
/// medium's extinction is not constant.
SegmentFlight flight_along_segment(const Scene &scene, Ray ray, const Medium *medium, float u, RayCounters &counters);

/// Transmittance along a shadow ray (NullRule::Transmission): zero when blocked.
inline Spectrum shadow_transmittance(const Scene &scene, const Ray &ray, const Medium *medium, RandomStream &rs,
                                     RayCounters &counters) {
    SegmentWalk w = walk_segment(scene, ray, medium, NullRule::Transmission, rs, counters);
    return w.stopped ? Spectrum(0.f) : w.tr;
}

} // namespace mvpt
