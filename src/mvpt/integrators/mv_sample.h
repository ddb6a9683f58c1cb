// One native sample of multi-view path tracing (docs/multiview-path-tracing.md §2–§7):
// camera ray of view l, shift of its first hit y to every other view, selection,
// visibility, balance-heuristic densities D_k (§5), shared next-event estimation and
// bounce (§7), and the contributions splatted into each sharing view.
#pragma once

#include "mv_candidates.h"
#include "mv_selection.h"
#include "mv_shift.h"
#include "mvpath.h"
#include "transmittance.h"

#include "../render/splat_film.h"
#include "../render/camera_projection.h"
#include "../render/camera_samples.h"
#include "../scene/rig_visibility.h"

#include <cstdint>
#include <memory>
#include <vector>

namespace mvpt {

class Medium;
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

/// Scratch arrays only grow: resizing them to each sample's count would refill them.
template <typename V> void grow_scratch(V &v, size_t n) {
    if (v.size() < n) v.resize(n);
}

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

/// Native samples whose suffix (the path continuing from the shared bounce, §7) waits to
/// be traced with the other samples of its tile as one wavefront of the path tracer
/// (PathIntegrator::trace_batch), and whose NEE shadow ray waits likewise;
/// mv_finish_samples then splats their contributions.
struct MvPendingSamples {
    /// Per sample: its sharing views' entries [first, first + count) below (the native view
    /// first), its suffix (an index into the suffix arrays, or -1), its valid-path flag when it
    /// has no suffix, the shared NEE's shadow ray (its radiance counts if unblocked) or -1, and
    /// the view that sampled a delta lobe (then only its entry gets the suffix, else -1).
    /// The radiance of entry j (§7) is
    ///   L_j = [nee] f_nee_j * nee_weight + [suffix] (f_bounce_j * b_scale) * suffix,
    /// with delta_bounce in place of f_bounce_j * b_scale for a delta lobe's view.
    struct Sample {
        uint32_t first = 0, count = 0;
        int32_t suffix = -1, delta_view = -1;
        int32_t shadow = -1;
        bool valid = false;
        bool nee = false; ///< nee_weight is not black
        /// A medium vertex (§10): its contributions are added as native-only radiance (to E,
        /// with W = 0), since no fixed sum of their weights is known.
        bool medium = false;
        uint64_t hash = 0; ///< the native sample's Sampler::sample_hash (for the splats' taps)
        SampleKey key = NoSample; ///< the native sample, for the report of dropped contributions
        float b_scale = 0.f;
        Spectrum nee_weight{0.f}, delta_bounce{0.f};
        Spectrum e{0.f}; ///< the native view's own radiance E
    };
    std::vector<Sample> samples;
    /// Per sharing view of each sample: slot, pixel, W = 1/D, and the BSDF values f_k |cos|
    /// towards the light sample and the bounce direction.
    std::vector<int> slot;
    std::vector<uint32_t> pixel; ///< sample-window pixel index
    std::vector<Vec2f> film;     ///< film position (full-film pixels)
    std::vector<float> w;
    std::vector<Spectrum> f_nee, f_bounce; ///< with one more element than the others
    size_t entries = 0; ///< entries in use (the arrays above keep their size between tiles)
    /// Room for n more entries; returns the first.
    size_t add_entries(size_t n);
    /// The suffixes: start rays, path states and sample streams; results.
    std::vector<Ray> rays;
    std::vector<PathState> states;
    std::vector<Sampler> samplers;
    std::vector<const Medium *> media; ///< the medium each suffix starts in (scenes with media)
    std::vector<uint32_t> dims;        ///< the first sampler dimension of each suffix's steps (scenes with media)
    std::vector<Spectrum> radiance;
    std::vector<uint8_t> valid;
    /// The shared NEE's shadow rays, traced as packets with the suffixes; results.
    std::vector<Ray> shadow_rays;
    std::vector<uint8_t> shadow_blocked;
    void clear();
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

/// What the entries of one pending sample have in common once its suffix is traced.
struct MvSplatTerms {
    Spectrum nee_weight, suffix;
    float b_scale;
    bool nee, bounce, valid; ///< the light sample is unblocked; the bounce serves every view; a valid sample
};

/// W·L of one entry (§7): ([nee] f_nee * nee_weight + [bounce] (f_bounce * b_scale) * suffix) W,
/// zero when the sample is not valid.
Spectrum mv_entry_value(const MvSplatTerms &t, const Spectrum &f_nee, const Spectrum &f_bounce, float w);

/// Adds entries [begin, end) of one sample to `cache`: W·L (mv_entry_value) and W at film
/// position films[i] (window pixel pixels[i]) of view slots[i], of the native sample with
/// Sampler::sample_hash `sample`, the same bits as SplatCache::add; entries that do not fit are
/// counted in dropped[slot] (and returned). f_nee and f_bounce are read 16 bytes per entry: one
/// Spectrum past `end` must be readable.
size_t mv_splat_entries(SplatCache &cache, const MvSplatTerms &t, const Spectrum *f_nee, const Spectrum *f_bounce,
                      const float *w, const int *slots, const uint32_t *pixels, const Vec2f *films, uint64_t sample,
                      size_t begin, size_t end, uint64_t *dropped);

/// Trace the pending samples' suffixes as one wavefront and splat their contributions; the
/// suffixes' rays count for the view in `slot` (pending samples are flushed per tile).
void mv_finish_samples(const MvContext &ctx, int slot, MvPendingSamples &pending, MvSplatSink &sink,
                       RayCounters &counters, MvViewStats *stats);

} // namespace mvpt
