// Volumetric path tracer (Mitsuba 3's `volpath`): unidirectional paths through surfaces and
// participating media, free-flight distance sampling, next-event estimation with the
// transmittance of media and null surfaces along the shadow ray, MIS (power heuristic)
// between emitter sampling and BSDF / phase sampling. Depth counts scattering events (at
// surfaces that are not null, and in media), as Mitsuba's does.
#pragma once

#include "../../render/integrator.h"
#include "path.h"

namespace mvpt {

class Medium;
struct LightSample;

/// Sample dimensions per step of a volumetric path: roulette, free flight and its stream,
/// emitter choice, point and the shadow ray's stream, lobe, direction (phase: at the lobe's).
inline constexpr uint32_t VolDimsPerStep = 8;
/// Where the steps of the estimates of VolPathPart::ScatteredInMedium start (estimate j at
/// DimInScatter + j DimInScatterStride): clear of the blocks of a path that continues from a
/// surface, and of multi-view path tracing's draws at its shared vertex.
inline constexpr uint32_t DimInScatter = 1u << 24, DimInScatterStride = 1u << 20;

/// Which part of a volumetric path's radiance `VolPathIntegrator::trace` estimates.
enum class VolPathPart {
    All,
    /// Only paths that scatter in a medium before the first surface that is not null (the
    /// in-scattering along a camera segment; multi-view path tracing shares the rest, §10).
    /// Emitters on the null surfaces crossed before it count too.
    ScatteredInMedium,
    /// The rest: paths that reach the first surface that is not null (or leave the scene)
    /// without scattering in a medium on the way, weighted by the transmittance there. With
    /// ScatteredInMedium it makes up All.
    ReachesSurface,
};

class VolPathIntegrator final : public Integrator {
public:
    explicit VolPathIntegrator(const PathConfig &cfg) : m_cfg(cfg), m_surfaces(cfg) {}
    const PathConfig &config() const { return m_cfg; }
    /// A scene without media is traced by the path tracer (`surfaces`): the same image in
    /// expectation, as in Mitsuba, at its wavefront's speed.
    Spectrum li(const Scene &scene, const Ray &ray, Sampler &sampler, RayCounters &counters) const override;
    void li_batch(const Scene &scene, const Ray *rays, Sampler *samplers, Spectrum *out, size_t n,
                  RayCounters &counters, const Medium *medium = nullptr) const override;
    /// The path tracer of the same depths, for scenes without media (and multi-view path tracing).
    const PathIntegrator &surfaces() const { return m_surfaces; }
    /// Radiance along a camera ray that starts in `medium` (null: vacuum), from its near plane.
    /// `dims`: the first sampler dimension of the path's step blocks.
    Spectrum li_in(const Scene &scene, Ray ray, const Medium *medium, Sampler &sampler, RayCounters &counters,
                   VolPathPart part = VolPathPart::All, uint32_t dims = DimCameraEnd) const;
    /// Radiance carried back along `ray` (from its origin, in `medium`) by the path that
    /// continues from `start` (its depth, eta, throughput and the previous vertex's sampling
    /// density; `start.valid` is not used). Its steps' sampler blocks start at `dims` plus its
    /// depth's block.
    Spectrum trace(const Scene &scene, Ray ray, const Medium *medium, const PathState &start, Sampler &sampler,
                   RayCounters &counters, VolPathPart part = VolPathPart::All, uint32_t dims = DimCameraEnd) const;
    std::string name() const override { return "volpath"; }

    /// VolPathPart::ScatteredInMedium along `ray` (from its origin, unit direction) when all of
    /// [0, ray.tmax) lies in `medium` and it ends at a surface that is not null: one forced
    /// scattering in it (Medium::sample_within: every call scatters, with a bounded weight,
    /// where a free flight scatters only with the segment's opacity), and the path from there.
    /// `drawn` is false where the medium cannot force it (then the result is zero). `dims` as
    /// for `trace`.
    Spectrum in_scattering(const Scene &scene, const Ray &ray, const Medium &medium, Sampler &sampler,
                           RayCounters &counters, bool &drawn, uint32_t dims = DimInScatter) const;

    /// One emitter sample seen from `p` (a surface point `si`, or a point in a medium when
    /// `si` is null): the emitter's radiance over its density times the transmittance to it,
    /// with the light sample for the MIS weight; zero when blocked. Draws an emitter choice, a
    /// point and the shadow ray's stream from the sampler's current dimension on.
    Spectrum sample_emitter(const Scene &scene, Point3f p, const SurfaceInteraction *si, const Medium *medium,
                            float time, Sampler &sampler, RayCounters &counters, LightSample &ls) const;

private:
    /// The vertex of `path` at the surface `si` (or, when not `hit`, where it escapes): emission
    /// with MIS, next-event estimation, and the BSDF sample (dimensions from `block` + 6) that
    /// the path follows through `ray` (and into `medium`). False: the path ends.
    bool surface_vertex(const Scene &scene, bool hit, SurfaceInteraction &si, uint32_t block, uint32_t max_depth,
                        PathState &path, Ray &ray, const Medium *&medium, Spectrum &result, Sampler &sampler,
                        RayCounters &counters) const;
    /// A scattering at `ray.o` in `medium` coming along `ray.d`, with the path's `throughput`:
    /// next-event estimation (when the medium samples emitters; returned, throughput included)
    /// and the phase function's sample, into `ray` with its density `pdf` (`delta`: no MIS on
    /// the emitter it hits). Draws from the step's sampler block `block` (+3..+5, +6).
    Spectrum scatter_in_medium(const Scene &scene, const Medium &medium, const Spectrum &throughput, uint32_t block,
                               Sampler &sampler, RayCounters &counters, Ray &ray, float &pdf, bool &delta) const;


    PathConfig m_cfg;
    PathIntegrator m_surfaces;
};

} // namespace mvpt
