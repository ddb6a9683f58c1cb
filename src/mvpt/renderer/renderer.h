// Drives a render: progressive passes over all views, parallel over tiles, in one pass loop
// for every method (pass_loop.cpp); stops at a sample count, a time budget or a cancel
// request (between chunks of tiles, chunks.h); keeps each view's film (film.h) and can save,
// resume and merge its state (renderer_state.cpp).
#pragma once

#include "../render/integrator.h"
#include "../integrators/multiview/mv_context.h"
#include "film.h"
#include "../accel/scene.h"

#include <tbb/task_arena.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mvpt {

class PassSchedule;

/// Rendering method: the scene's integrator, independent path tracing of every view, or
/// multi-view path tracing (docs/multiview-path-tracing.md).
enum class RenderMethod { Scene, PathTracing, MultiView };

struct RenderOptions {
    RenderMethod method = RenderMethod::Scene;
    /// Samples per pixel; 0 uses each sensor's sampler `sample_count`.
    int spp = 0;
    /// Wall-clock budget in seconds (0: none). Passes stop when the next one
    /// would end past the budget; at least one pass always runs.
    double time_budget = 0.0;
    /// Overrides the sensors' sampler seeds when set.
    std::optional<uint32_t> seed;
    /// Worker threads; 0 uses every core.
    int threads = 0;
    /// Indices of the views to render; empty renders all.
    std::vector<int> views;
    /// The render's state file (render_state.h): written at a pass boundary every
    /// `checkpoint_interval` seconds (0: not periodically), when the render is cancelled, and at
    /// its end when `state_at_end`; `state_header` is stored in it as given.
    std::string state_path, state_header;
    double checkpoint_interval = 0.0;
    bool state_at_end = false;
    /// A state file of the same scene and settings to continue from (the caller compares their
    /// headers; the renderer checks that the accumulators fit).
    std::string resume_path;
    /// A range of a render split over processes or machines (docs/distributed.md): with
    /// `pass_count` > 0, every view renders `pass_count` passes whose samples are those of passes
    /// [first_pass, first_pass + pass_count) (spp is ignored; multi-view path tracing numbers a
    /// pixel's native samples from first_pass times the most it takes in a pass). Ranges that do
    /// not overlap take disjoint samples, and their states merge (Renderer::merge).
    int first_pass = 0, pass_count = 0;
    /// Multi-view path tracing, for tests: below 1, the last `thin_passes` passes of a range
    /// (pass_count; never its first) are thinned to this share, as a time budget thins passes
    /// (docs/multiview-path-tracing.md, "Passes thinned to the budget").
    double thin_last_pass = 1.0;
    int thin_passes = 1;
    /// Multi-view: the splits of the shared vertex instead of the scene's `mvpath` setting (-1:
    /// the scene's; 0: chosen per render; 1-64).
    int splits = -1;
    /// Multi-view: run the method's pilot and no pass (the statistics hold its choices and
    /// predicted_gain; the images are black): what `method="auto"` decides from.
    bool pilot_only = false;
};

/// Result of one view: crop-window-sized images, row-major, y down.
struct ViewResult {
    std::string id;
    int width = 0, height = 0;
    std::vector<float> rgb;      ///< mean radiance, 3 floats per pixel
    std::vector<float> variance; ///< variance of the pixel mean, 3 floats per pixel
    std::vector<uint32_t> sample_count; ///< samples per pixel (multi-view: native samples)
    std::vector<float> contributions;   ///< multi-view: contributions received per pixel
    /// Multi-view: mean over passes of the sum of W = 1/D_k per pixel; 1 in expectation when the
    /// densities D are complete (balance, mis_set=all), so it checks the weights (§5).
    std::vector<float> weight_sum;
    uint64_t samples = 0;
    double mean[3] = {0.0, 0.0, 0.0}; ///< the image's mean (RGB), summed as it is developed
    double contributions_total = 0.0; ///< multi-view: the sum of `contributions`
    MvViewStats mv; ///< multi-view statistics of the view
    uint64_t nonfinite = 0; ///< non-finite samples dropped (recorded as zero)
};

struct RenderStats {
    double seconds = 0.0;
    /// Longest pass, to judge how closely a time budget can be met (path tracing without a
    /// time budget runs passes in chunks: there, the longest chunk's mean pass).
    double max_pass_seconds = 0.0;
    /// The longest stretch of a pass (or group of passes) between two progress reports.
    double max_chunk_seconds = 0.0;
    /// Multi-view path tracing: the time spent between passes (caches flushed, the pass folded
    /// into the accumulators, the next native-sample maps), in all.
    double between_passes_seconds = 0.0;
    /// The process's peak memory the render was expected to reach (bytes): what it held when
    /// the renderer was made plus the films, images and per-thread buffers.
    double estimated_bytes = 0.0;
    int passes = 0;
    /// Multi-view path tracing: when its first pass was cut short (Ctrl-C, the time budget),
    /// the share of its regions rendered, whose sums were scaled by its inverse; else 0.
    double cut_pass_share = 0.0;
    /// Multi-view path tracing: when its last pass was thinned to fit the time budget, the share
    /// q of the native samples it took (its sums scaled by 1/q, weighing q); else 0.
    double thinned_pass_share = 0.0;
    /// Multi-view path tracing under a time budget: the passes thinned to fit it (the last
    /// included) and the sum of their shares.
    int thinned_passes = 0;
    double thinned_shares = 0.0;
    /// The pass a resumed render started from (0: not resumed).
    int first_pass = 0;
    bool cancelled = false;
    uint64_t samples = 0;
    RayCounters counters;
    /// First non-finite sample in (sample index, view, y, x) order, for replay (-1 if none);
    /// independent of the thread count.
    int64_t nonfinite_view = -1, nonfinite_x = -1, nonfinite_y = -1, nonfinite_sample = -1;
    int threads = 0;
    /// "pt" or "mvpt" (what ran), and the multi-view estimator ("balance" / "weighted").
    std::string method = "pt", estimator;
    int splits = 0; ///< multi-view: light samples and bounces per shared vertex (MvConfig::splits)
    int delta_splits = 0; ///< multi-view: paths per specular first vertex (MvConfig::delta_splits)
    /// Multi-view with splits chosen per render: the pilot's a, r, c0 and c1 (SplitStatistics), else zeros.
    std::array<double, 4> split_pilot{};
    /// Multi-view: path tracing's relMSE over this method's at equal time, as the pilot predicts
    /// it (predicted_gain; 0: no prediction).
    double predicted_gain = 0.0;
    /// Things the user should know about the run (e.g. a filter replaced by a box).
    std::vector<std::string> notes;
    /// Things that make the images useless (a scene that cannot produce light).
    std::vector<std::string> warnings;
    MvViewStats mv; ///< multi-view statistics summed over views
    /// Why the state file could not be written (at a checkpoint or at the end), else empty:
    /// the render went on without it.
    std::string state_error;
};

struct RenderProgress {
    int pass = 0;
    double fraction = 0.0; ///< of the spp or the time budget, whichever is further along
    double elapsed = 0.0;
    uint64_t samples = 0;
};

using ProgressFn = std::function<void(const RenderProgress &)>;

class Renderer {
public:
    Renderer(const Scene &scene, RenderOptions opts);
    /// Run to completion, cancellation, or budget; `progress` is called after each pass.
    void render(const std::atomic<bool> &cancel, const ProgressFn &progress = {});
    /// Instead of rendering: the sum of the state files of disjoint ranges (or seeds) of this
    /// render, added in the order given, developed into the results; `state_path`, if set, gets
    /// the merged state.
    void merge(const std::vector<std::string> &paths, bool develop = true);

    const std::vector<ViewResult> &results() const { return m_results; }
    /// The results, moved out (the renderer keeps none).
    std::vector<ViewResult> take_results() { return std::move(m_results); }
    const RenderStats &stats() const { return m_stats; }
    const std::vector<int> &views() const { return m_views; }

private:
    /// 16x16 tiles of the views (view_slot indexes m_views).
    struct Tile {
        int view_slot;
        int x0, y0, x1, y1; // pixel range of the crop window (or of the sample window, where samples are splatted)
    };
    /// The largest sample target of the rendered views (option or sensors).
    int spp_target() const;
    /// RenderStats::estimated_bytes.
    double estimate_peak_bytes() const;

    // The pass loop of every method (pass_loop.cpp) and each method's part in it.
    class PathPasses;      // path_passes.h
    class MultiviewPasses; // multiview_passes.cpp
    /// Steps of passes as `schedule` makes them, until the sample target, the time budget or
    /// a cancel request.
    void run_passes(PassSchedule &schedule, const std::atomic<bool> &cancel, const ProgressFn &progress);
    /// schedule.save, a failure to write kept in m_stats.state_error instead of thrown.
    void save_state(PassSchedule &schedule, int pass, double elapsed, double last_pass);
    /// Calls `progress` (when set) with the pass, the seconds elapsed, the samples so far and
    /// `fraction` of the sample target, raised to the share of the time budget spent.
    void report_progress(const ProgressFn &progress, int pass, double elapsed,
                         uint64_t samples, double fraction) const;
    /// Every view's images from its film (each film freed once its images are made).
    void develop();
    /// The films of the views, make(slot) each, in parallel within the render's threads (on
    /// one core, zeroing the accumulators of many large views took a noticeable share of a
    /// short render).
    void make_films(const std::function<Film(size_t)> &make);

    /// Path tracing: 16x16 tiles of every view's crop window, or (`windows`, by slot) of its
    /// sample window, in the window's coordinates.
    std::vector<Tile> make_tiles(const std::vector<SampleWindow> *windows = nullptr) const;

    /// Multi-view path tracing: the whole render, in `arena`.
    void render_multiview(tbb::task_arena &arena, const std::atomic<bool> &cancel, const ProgressFn &progress);
    /// Multi-view path tracing: the method's settings, context, accumulators and maps.
    std::vector<SplatFootprint> prepare_multiview_render(MvConfig &cfg);
    /// Multi-view path tracing: the method's context, accumulators and native-sample maps of
    /// every view; returns where each view's contributions land.
    std::vector<SplatFootprint> prepare_multiview(const PathIntegrator *path, const VolPathIntegrator *volpath,
                                                  const MvConfig &cfg, bool adaptive);
    /// Multi-view path tracing: whether this render makes adaptive native-sample maps.
    bool adaptive_maps(const MvConfig &cfg) const;
    /// Multi-view path tracing: 16x16 tiles of every view's sample window, region by region,
    /// the regions in scan order or (`random_regions`) in a random order drawn from the seed.
    std::vector<Tile> multiview_tiles(bool random_regions) const;
    /// Multi-view path tracing: one pass's sums (times `scale`) into every view's accumulators,
    /// as estimates of weight `weight` (below 1: a thinned pass, film.h).
    void fold_pass(MvPassFilm &pass_film, double scale = 1.0, double weight = 1.0);
    /// Multi-view: the films' first pass (whole) held rather than folded (Film::hold), for the
    /// balance estimator with its control variate; false (nothing done) otherwise.
    bool hold_pass(MvPassFilm &pass_film);
    /// Where each rendered view's splats land (by slot): its crop window and filter, the taps'
    /// roulette keyed by its scene index.
    std::vector<SplatFootprint> view_footprints() const;
    /// A held first pass folded without a control variate (Film::release), in every film that holds one.
    void release_held();
    /// Multi-view path tracing: the native-sample maps of the next pass (§8) after `passes`.
    void update_native_maps(int passes, double per_pixel);

    // State files (renderer_state.cpp).
    /// The state file at a pass boundary: the next pass, the elapsed seconds, a whole pass's
    /// seconds (what a time budget expects of the next: PassSchedule::whole_pass_seconds), the
    /// ray counters so far and, for multi-view path tracing, its statistics and dropped
    /// contributions by slot.
    void write_state(int next_pass, double elapsed, double last_pass, const RayCounters &counters,
                     const std::vector<MvViewStats> &mv_stats = {}, const std::vector<uint64_t> &mv_dropped = {}) const;
    /// Loads the state file at `path` into the accumulators (made for this render).
    void read_state(const std::string &path);
    /// Adds another renderer's loaded state to this one's.
    void add_state(const Renderer &other);
    /// Whether a checkpoint is due (`last`: the time of the previous one, set when it is).
    bool checkpoint_due(double elapsed, double &last) const;

    const Scene &m_scene;
    RenderOptions m_opts;
    bool m_multiview = false; ///< multi-view path tracing (else independent path tracing)
    /// Path tracing splats its samples with the views' pixel filters (path_passes.h): some view's
    /// filter is not a box, and every filter reaches at most SplatFootprint::MaxRadius.
    bool m_splat = false;
    std::vector<int> m_views;
    std::vector<Film> m_films; ///< by slot
    MvContext m_mv;
    /// Where a resumed render starts: its first pass, the seconds and (multi-view) the mean
    /// native samples per pixel and the statistics of the runs before.
    int m_first_pass = 0;
    double m_elapsed_before = 0.0, m_last_pass_before = 0.0, m_native_done = 0.0;
    /// When render() began: a time budget counts from there (the method's preparation included).
    std::chrono::steady_clock::time_point m_render_start;
    std::vector<MvViewStats> m_mv_stats_before;
    std::vector<ViewResult> m_results;
    RenderStats m_stats;
};

} // namespace mvpt
