// Multi-view path tracing through participating media (docs/multiview-path-tracing.md §10):
// the shared vertex is the first surface a camera ray meets that is not null; each view's
// contribution is multiplied by the transmittance of its own camera segment, and the
// in-scattering along the native camera segment is shared as medium vertices where every
// medium is homogeneous (mv_medium_vertex.cpp), else the native view's own radiance.
#pragma once

#include "mv_sample.h"
#include "../path/transmittance.h"

namespace mvpt {

class Medium;

/// The dimension (plus the view's scene index) whose stream estimates the transmittance of
/// a view's camera segment to the shared vertex.
inline constexpr uint32_t DimCameraSegmentBase = 1u << 22;
/// The dimension of the shared next-event estimate's stream (the transmittance to the light):
/// in the shared vertex's block, after the path tracer's draws there.
inline constexpr uint32_t DimSharedShadow = DimCameraEnd + 5;

/// The first surface along a native camera ray that is not null.
struct MvMediaVertex {
    /// The walk from the near plane: the vertex (walk.si), the transmittance to it (walk.tr),
    /// the medium the ray arrives in (walk.medium) and the segment's media pieces.
    SegmentWalk walk;
    Ray near; ///< the walked ray: the camera ray from its near plane
    /// False: the ray leaves the scene (or crosses too many null surfaces).
    bool found() const { return walk.stopped && walk.si.is_valid(); }
};

/// Walks view `slot`'s camera `ray` through media and null surfaces from its near plane.
MvMediaVertex mv_media_first_vertex(const MvContext &ctx, int slot, const Ray &ray, Sampler &sampler,
                                    RayCounters &counters);

/// How many estimates of the in-scattering a native sample takes: 1 + InScatterPerOpacity
/// (1 - T_l(y)) rounded, at most MaxInScatterEstimates.
inline constexpr float InScatterPerOpacity = 8.f;
inline constexpr int MaxInScatterEstimates = 9;

/// The native view's in-scattering along its camera segment to the shared vertex y (§10), the
/// mean of several estimates (more where the segment is more opaque), each a forced
/// scattering where the segment has one piece in a medium that can draw it, else the
/// volumetric path tracer's ScatteredInMedium part.
Spectrum mv_in_scattering(const MvContext &ctx, int slot, const Ray &ray, const MvMediaVertex &y, Sampler &sampler,
                          RayCounters &counters);

/// Test 5 of §3 through media: candidate i sees the shared vertex `p` when no surface that is
/// not null lies on its camera segment (from its near plane); fills sc.visible and, for the
/// visible ones, the segment's transmittance sc.tr[i] (sc.tr[0], the native view's, is
/// `tr_native`). With `selected_only`, unselected candidates are not traced. `sampler` (or
/// null: a fixed stream, for the densities alone) gives each view's transmittance stream.
void mv_media_visibility(const MvContext &ctx, MvScratch &sc, Point3f p, float time, Spectrum tr_native,
                         bool selected_only, Sampler *sampler, RayCounters &counters, MvViewStats *st_l);

/// The dimension of a native sample's medium vertex (§10): its block of draws (the layout of a
/// volumetric path's step, VolDimsPerStep), then its suffix's steps from depth 1.
inline constexpr uint32_t DimMediumVertex = 3u << 22, DimMediumVertexStride = 1u << 20;
/// How many flights a native sample draws along its camera segment (each a medium vertex).
inline constexpr int MediumFlights = 4;

/// Whether the scatterings on camera segments can be shared (MvContext::medium_vertices).
bool mv_can_share_medium_vertices(const MvContext &ctx);

/// The medium vertex of a native sample of view `slot` (§10): a free flight along its camera
/// segment `near` (from the near plane, lens point `lens` on the unit disk, at `time`; the
/// sample's own pixel `pixel` and film position `film`); where it scatters, the point is
/// shifted to every view that sees it, shaded once (next-event estimation and a phase sample
/// from the views' mixture) and joins `pending` with a suffix from depth 1.
void mv_medium_vertex(const MvContext &ctx, int slot, const Ray &near, Vec2f lens, uint32_t pixel, Vec2f film,
                      const SampleKey &key, Sampler &sampler, MvScratch &sc, MvPendingSamples &pending,
                      RayCounters &counters, MvViewStats &st);

/// The medium a ray leaving the shared vertex `si` in world direction `d` enters: the shape's
/// when it bounds media, else `arrival`, the one the camera ray was in.
const Medium *mv_medium_towards(const SurfaceInteraction &si, Vec3f d, const Medium *arrival);

} // namespace mvpt
