// One native sample of multi-view path tracing (docs/multiview-path-tracing.md §2–§7):
// camera ray of view l, shift of its first hit y to every other view, selection,
// visibility, balance-heuristic densities D_k (§5), shared next-event estimation and
// bounce (§7); its contributions are splatted by mv_splat.h.
#pragma once

#include "mv_candidates.h"
#include "mv_context.h"
#include "mv_selection.h"
#include "mv_splat.h"
#include "../path/transmittance.h"

#include "../../render/camera_samples.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace mvpt {

class Medium;
class Scene;
class VolPathIntegrator;

/// The camera segments of a shared vertex's candidates, walked through media as one batch
/// (mv_media_visibility, §10): which candidate each is, its ray, medium and random stream.
struct MvMediaWalks {
    std::vector<uint32_t> candidate;
    std::vector<Ray> rays;
    std::vector<const Medium *> media;
    std::vector<RandomStream> streams;
    std::vector<SegmentWalk> walks;
    WalkBuffers buffers;
    void clear() {
        candidate.clear(), rays.clear(), media.clear(), streams.clear();
    }
};

/// Scratch arrays only grow: resizing them to each sample's count would refill them.
template <typename V> void grow_scratch(V &v, size_t n) {
    if (v.size() < n) v.resize(n);
}

/// Per-thread scratch space (kept between samples to avoid allocations).
struct MvScratch {
    ViewShifts shifts;  ///< the shift of y to every view
    MvCandidates cand;  ///< the views that passed the cheap tests
    std::vector<ViewLobe> lobe; ///< candidates' lobes (for the material similarity only)
    std::vector<float> s_sel, d, sm;
    std::vector<uint8_t> visible, blocked;
    std::vector<uint32_t> selected; ///< 32-bit: written by a vector loop
    std::vector<float> segments; ///< visibility segments (directions, lengths) as arrays
    std::vector<uint32_t> valid_set;
    std::vector<float> g_valid, n_valid; ///< G and n of the valid strategies, for D
    std::vector<float> g_targets, d_targets;
    std::vector<int> sharing;
    float alpha = 1.f;     ///< roughness at the current shared vertex
    bool material = false; ///< s_M is evaluated at the current shared vertex
    std::vector<Vec3f> sharing_wi;
    std::vector<float> view_pdf;
    std::vector<float> p_delta, smooth_scale; ///< the sharing views' lobe classes (LobeClasses)
    std::vector<Spectrum> tr; ///< candidates' camera-segment transmittance (media, §10)
    MvMediaWalks walks;
};

/// The camera samples of a tile's native samples (§2) and their first hits: the camera rays
/// are traced together as one coherent stream (mv_trace_primaries), as the path tracer does.
struct MvPrimaries {
    std::vector<uint32_t> px, py;         ///< pixel (full-film coordinates)
    std::vector<uint32_t> sample_index;   ///< the pixel's native-sample index
    CameraSamples camera;                 ///< film position, unit-disk lens point and time
    std::vector<Ray> rays;
    std::vector<SurfaceInteraction> si;
    std::vector<uint8_t> hit;
    size_t size() const { return px.size(); }
    void clear() { px.clear(), py.clear(), sample_index.clear(); }
    void push(int x, int y, uint32_t index) {
        px.push_back(uint32_t(x)), py.push_back(uint32_t(y)), sample_index.push_back(index);
    }
};

/// The shift of a shared vertex `y` of a native sample of view `slot_l` to every view with the
/// cheap tests (§3 tests 1–3), into sc.shifts.
void mv_shift_views(const MvContext &ctx, int slot_l, const MvVertex &y, MvScratch &sc);

/// The densities D_k (§5) that a native sample of view `slot` whose camera ray (from
/// `lens_point`, unit-disk point `lens`, at `time`) hits `hit` gives every view k that can share
/// it, by slot, with the visibility of every candidate traced (no selection draws): as in
/// mv_native_sample. For tests: the samples of all views that reach the same shifted sample
/// must compute the same D_k, which makes their balance weights sum to one.
std::vector<std::pair<int, float>> mv_balance_densities(const MvContext &ctx, int slot, const SurfaceInteraction &hit,
                                                        Point3f lens_point, float time, Vec2f lens, MvScratch &sc);

/// Draw the camera samples of the native samples queued in `prim` (pixels and sample
/// indices, of the view in `slot`) and trace their camera rays as one stream.
void mv_trace_primaries(const MvContext &ctx, int slot, MvPrimaries &prim);

/// Take native sample `i` of `prim` (traced by mv_trace_primaries) of the view in `slot`:
/// contributions that need no suffix are splatted now, the others join `pending`.
void mv_native_sample(const MvContext &ctx, int slot, MvPrimaries &prim, size_t i, MvScratch &scratch,
                      MvPendingSamples &pending, MvSplatSink &sink, RayCounters &counters, MvViewStats *stats);

/// Take every native sample of `prim` (mv_native_sample) and trace and splat the pending ones
/// (mv_finish_samples) whenever their entries reach ctx.cfg.batch_entries, and at the end: the
/// entries written by a batch's samples are read back while they are in the core's cache.
void mv_native_samples(const MvContext &ctx, int slot, MvPrimaries &prim, MvScratch &scratch, MvPendingSamples &pending,
                       MvSplatSink &sink, RayCounters &counters, MvViewStats *stats);

} // namespace mvpt
