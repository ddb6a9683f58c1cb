// The state that every native sample of a pass of multi-view path tracing reads
// (docs/multiview-path-tracing.md §2–§3): the rendered views, their sample windows and
// native-sample maps, the shortcuts that hold for the whole rig; the sampler dimensions of
// the multi-view decisions; and the per-view statistics of a render.
#pragma once

#include "mv_candidates.h"
#include "mv_shift.h"
#include "mvpath.h"

#include "../../render/camera_projection.h"
#include "../../accel/rig_visibility.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace mvpt {

class Scene;
class VolPathIntegrator;

/// Sampler dimensions of the multi-view decisions at y, far above the path's per-vertex
/// blocks: the choice of the view whose lobe samples the bounce, and one selection draw
/// per target view (indexed by the view's scene index, so adding views does not change
/// the numbers of the others).
inline constexpr uint32_t DimBounceView = 1u << 20;
inline constexpr uint32_t DimSelectBase = DimBounceView + 1;
/// The dimension (plus the target view's scene index) whose number plays the Russian roulette
/// of a contribution's small filter taps (SplatCache::add_footprint).
inline constexpr uint32_t DimSplatBase = 1u << 21;

/// Per-view statistics of a render (§9): as the native view (`native`, `tried`, `rejected`,
/// `sharing`, `rays`) and as a target (`received`).
struct MvViewStats {
    uint64_t native = 0;   ///< native samples taken
    uint64_t received = 0; ///< contributions received (own native samples included)
    uint64_t tried = 0;    ///< shifts to other views tried
    uint64_t rejected[int(ShiftTest::Count)] = {};
    uint64_t sharing = 0; ///< sum over native samples of |S| (views shading the sample)
    uint64_t rays = 0;    ///< rays traced for the native samples (all kinds)
    MvViewStats &operator+=(const MvViewStats &o);
};

/// Read-only state shared by every native sample of a pass.
/// Whether a shape or a light of `scene` moves: then a shared sample keeps its time (§3 test 1).
bool mv_scene_moves(const Scene &scene);

struct MvContext {
    const Scene *scene = nullptr;
    const PathIntegrator *path = nullptr;
    /// The volumetric path tracer when the scene's media are rendered (§10), else null.
    const VolPathIntegrator *volpath = nullptr;
    MvConfig cfg;
    std::vector<MvView> views;                 ///< the rendered views, by slot
    std::vector<SampleWindow> windows;         ///< where each view takes native samples, by slot
    std::vector<const uint16_t *> native_map;  ///< n_k(i) of the current pass over the sample window, by slot
    std::vector<uint32_t> seeds;               ///< sampler seed, by slot
    bool scene_moves = false;                  ///< some shape moves: shifts keep time (§3)
    bool all_time_compatible = true;           ///< every pair of views passes `time_compatible`
    bool all_time_compatible_equal_dt = true;  ///< and all shutters have one length (time factors are 1)
    /// Every view is a static camera with a CameraProjection and nothing moves: shifts are
    /// computed for all views at once from `projections` (by slot) instead of calling each camera.
    bool static_shift = false;
    ProjectionTable projections;
    FilmTable films; ///< sample windows, by slot
    /// Sampler::dimension_key of each view's selection draw (DimSelectBase + its scene index), by slot.
    std::vector<uint64_t> select_keys;
    /// The direction from the first view's lens centre to the second's (a camera row or a
    /// grid's row): it orients the bounding pyramid of a sample's visibility segments.
    Vec3f across{1.f, 0.f, 0.f};
    /// Cells of the scene proven to see the whole rig unblocked (static scenes and cameras).
    std::shared_ptr<const RigVisibility> rig;
    /// Scatterings in media on camera segments are shared too (§10, medium vertices): the
    /// volumetric path tracer renders the media, all of them have a constant extinction, no
    /// emitter has a null BSDF, paths have a bounce and there are views to share with.
    bool medium_vertices = false;

    /// Sets the derived members above from `views` and `scene_moves` (`windows` included).
    void prepare();
};

} // namespace mvpt
