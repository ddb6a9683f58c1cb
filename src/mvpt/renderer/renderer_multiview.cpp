// The multi-view pass loop (docs/multiview-path-tracing.md): native samples of every view,
// shared through mv_native_sample, splatted into per-thread fixed-point buffers that are
// merged once per pass; adaptive native-sample maps between passes (§8).
#include "renderer.h"
#include "chunks.h"

#include "../integrators/mv_adaptive.h"
#include "../integrators/mv_sample.h"
#include "../integrators/mvpath.h"
#include "../integrators/volpath.h"
#include "../render/camera.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <tuple>

namespace mvpt {

namespace {
/// Per-thread state of the pass loop.
struct MvThreadState {
    SplatCache cache;
    std::vector<MvViewStats> stats;
    std::vector<uint64_t> dropped;
    MvScratch scratch;
    MvPrimaries primaries;
    MvPendingSamples pending;
    RayCounters counters;
    SampleKey first_dropped = NoSample; ///< the first native sample with a contribution dropped
    explicit MvThreadState(MvPassFilm &film) : cache(film), stats(film.views()), dropped(film.views(), 0) {}
};

/// The path tracers and method settings for a multi-view render of `scene`.
struct MultiviewSettings {
    const PathIntegrator *path = nullptr;
    const VolPathIntegrator *volpath = nullptr; ///< set when the scene's media are rendered (§10)
    MvConfig cfg;
};

MultiviewSettings multiview_settings(const Scene &scene) {
    if (auto *mv = dynamic_cast<const MultiViewPathIntegrator *>(&scene.integrator()))
        return {&mv->path(), nullptr, mv->config()};
    if (auto *pt = dynamic_cast<const PathIntegrator *>(&scene.integrator())) return {pt, nullptr, MvConfig{}};
    if (auto *vp = dynamic_cast<const VolPathIntegrator *>(&scene.integrator())) // without media: the path tracer
        return {&vp->surfaces(), scene.has_media() ? vp : nullptr, MvConfig{}};
    throw std::runtime_error("multi-view path tracing needs a 'path' or 'mvpath' integrator, the scene has '" +
                             scene.integrator().name() + "'");
}
} // namespace

void Renderer::render_multiview(const std::atomic<bool> &cancel,
                                const std::function<void(const RenderProgress &)> &progress) {
    using clock = std::chrono::steady_clock;
    MvConfig cfg;
    const std::vector<SplatFootprint> footprints = prepare_multiview_render(cfg);
    const bool adaptive = adaptive_maps(cfg);
    if (!m_opts.resume_path.empty()) read_state(m_opts.resume_path);
    int threads = m_opts.threads > 0 ? m_opts.threads : tbb::this_task_arena::max_concurrency();
    m_stats.threads = threads;
    tbb::task_arena arena(threads);

    // Target: spp native samples per pixel on average, the same for every view (all views take
    // part in every pass, n >= 1, since each view's D needs its own strategy). Passes take one
    // native sample per pixel until the adaptive maps start, then `adaptive_budget` per pixel.
    // A range renders its passes; its pixels' native samples are numbered from first_pass times
    // the most a pixel takes in a pass, its margins' from first_pass (one per pass).
    const int spp_target = this->spp_target();
    const bool range = m_opts.pass_count > 0;
    const bool unbounded = range || (m_opts.time_budget > 0.0 && m_opts.spp == 0);
    const uint64_t per_pass = adaptive ? uint64_t(cfg.adaptive_max) : 1;
    if ((uint64_t(m_opts.first_pass) + uint64_t(m_opts.pass_count)) * per_pass > UINT32_MAX)
        throw std::invalid_argument("the pass range numbers samples beyond 2^32");
    const uint32_t sample0 = uint32_t(uint64_t(m_opts.first_pass) * per_pass), margin0 = uint32_t(m_opts.first_pass);
    double &native_done = m_native_done; // mean native samples per pixel so far
    uint64_t pixels_total = 0;
    for (const MvFilm &mf : m_mv_films) pixels_total += mf.pixels();

    const std::vector<Tile> tiles = multiview_tiles();
    auto pass_film_ptr = std::make_unique<MvPassFilm>(footprints, cfg.estimator == MvEstimator::Weighted);
    MvPassFilm &pass_film = *pass_film_ptr;
    tbb::enumerable_thread_specific<MvThreadState> state([&] { return MvThreadState(pass_film); });
    int pass = m_first_pass;
    auto render_tile = [&](MvThreadState &ts, const Tile &tile) {
        MvSplatSink sink{ts.cache, ts.dropped.data(), &ts.first_dropped};
        const SampleWindow &w = m_mv.windows[tile.view_slot];
        const MvFilm &mf = m_mv_films[tile.view_slot];
        MvPrimaries &prim = ts.primaries;
        prim.clear();
        for (int y = tile.y0; y < tile.y1; ++y)
            for (int x = tile.x0; x < tile.x1; ++x) {
                // Inside the crop window: the pixel's next native samples; in the margin: one
                // sample per pass.
                const int cx = x - w.margin, cy = y - w.margin;
                const bool inside = cx >= 0 && cy >= 0 && cx < mf.width && cy < mf.height;
                const uint32_t first = inside ? sample0 + mf.native[size_t(cy) * size_t(mf.width) + size_t(cx)]
                                              : margin0 + uint32_t(pass);
                const uint16_t n = mf.map[size_t(y) * size_t(w.width()) + size_t(x)];
                for (uint32_t j = 0; j < n; ++j) prim.push(x + w.x0, y + w.y0, first + j);
            }
        // The tile's camera rays as one stream, then each native sample.
        mv_trace_primaries(m_mv, tile.view_slot, prim);
        for (size_t i = 0; i < prim.size(); ++i)
            mv_native_sample(m_mv, tile.view_slot, prim, i, ts.scratch, ts.pending, sink, ts.counters, ts.stats.data());
        // The tile's suffixes as one wavefront of the path tracer.
        mv_finish_samples(m_mv, tile.view_slot, ts.pending, sink, ts.counters, ts.stats.data());
        return prim.size();
    };

    // Cancellation and the end of the time budget abandon a pass (every view takes part in every
    // pass: an unfinished pass cannot enter the estimates); the first pass always completes.
    const double budget = m_opts.time_budget;
    ChunkTiming chunk_timing;
    // A resumed render's clock goes on from the seconds of the runs before (for --time).
    const auto t_start = clock::now() - std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(m_elapsed_before));
    auto seconds = [&] { return std::chrono::duration<double>(clock::now() - t_start).count(); };
    // The statistics of the threads, summed by slot (the ray counters with the runs' before);
    // the first native sample with a dropped contribution goes to m_stats.
    auto thread_sums = [&](std::vector<MvViewStats> &stats, std::vector<uint64_t> &dropped) {
        RayCounters counters = m_stats.counters;
        stats.assign(m_views.size(), MvViewStats{});
        dropped.assign(m_views.size(), 0);
        SampleKey first{m_stats.nonfinite_sample, m_stats.nonfinite_view, m_stats.nonfinite_y, m_stats.nonfinite_x};
        for (MvThreadState &ts : state) {
            keep_first(first, ts.first_dropped);
            counters += ts.counters;
            for (size_t s = 0; s < m_views.size(); ++s) stats[s] += ts.stats[s], dropped[s] += ts.dropped[s];
        }
        m_stats.nonfinite_sample = first[0], m_stats.nonfinite_view = first[1];
        m_stats.nonfinite_y = first[2], m_stats.nonfinite_x = first[3];
        return counters;
    };
    double last_pass = m_last_pass_before, last_checkpoint = m_elapsed_before;
    auto save_state = [&](int next_pass) {
        std::vector<MvViewStats> stats;
        std::vector<uint64_t> dropped;
        RayCounters counters = thread_sums(stats, dropped);
        for (uint64_t d : dropped) counters.nonfinite += d;
        write_state(next_pass, seconds(), last_pass, counters, stats, dropped);
    };
    for (; range ? pass < m_opts.pass_count : unbounded || native_done < double(spp_target) - 1e-6; ++pass) {
        if (cancel.load()) { m_stats.cancelled = true; break; }
        if (pass > 0 && budget > 0.0 && seconds() + last_pass > budget) break;
        const double t_pass = seconds();
        uint64_t pass_samples = 0; // of the crop windows
        for (const MvFilm &mf : m_mv_films) pass_samples += mf.map_total;

        // ---------------- Native samples, tile by tile, in chunks ----------------
        auto stop = [&] { return cancel.load() || (pass > 0 && budget > 0.0 && seconds() > budget); };
        auto report = [&](uint64_t samples_done) {
            report_progress(progress, pass, seconds(), m_stats.samples + samples_done,
                            range       ? (pass + double(samples_done) / double(pass_samples)) / m_opts.pass_count
                            : unbounded ? 0.0
                                        : std::min(1.0, (native_done + double(samples_done) / double(pixels_total)) /
                                                            spp_target));
        };
        const bool finished = run_in_chunks(arena, tiles.size(), threads, double(pass_samples), chunk_timing,
                                            [&](size_t ti) { return render_tile(state.local(), tiles[ti]); }, stop,
                                            report).finished;
        if (!finished) {
            for (MvThreadState &ts : state) ts.cache.discard();
            m_stats.cancelled = cancel.load();
            break;
        }

        // ---------------- The pass into the accumulators ----------------
        const double t_between = seconds();
        arena.execute([&] {
            // What the caches still hold goes to the pass sums (exact integer sums).
            tbb::parallel_for(state.range(1), [](auto &r) {
                for (MvThreadState &ts : r) ts.cache.flush();
            });
            fold_pass(pass_film);
        });
        native_done += double(pass_samples) / double(pixels_total);
        // Native-sample maps of the next pass (§8), frozen during it. Their statistics change by
        // about 1/passes per pass, so after 16 passes a map serves passes/8 passes (a map costs
        // about as much as folding a pass), except that the last pass's map spends only what is
        // left of the sample target. The schedule depends on the pass index alone.
        const int done = pass + 1;
        if (adaptive && done >= std::max(2, cfg.adaptive_warmup)) {
            double per_pixel = cfg.adaptive_budget;
            const bool last = !unbounded && double(spp_target) - native_done < 2.0 * per_pixel;
            if (!unbounded) per_pixel = std::min(per_pixel, double(spp_target) - double(native_done));
            if (done <= 16 || done % (done / 8) == 0 || last)
                arena.execute([&] { update_native_maps(done, std::max(per_pixel, 1.0)); });
        }
        m_stats.between_passes_seconds += seconds() - t_between;
        last_pass = seconds() - t_pass;
        finish_pass(pass, pass_samples, last_pass, seconds(),
                    range       ? double(pass + 1) / m_opts.pass_count
                    : unbounded ? 0.0
                                : std::min(1.0, native_done / double(spp_target)),
                    progress);
        if (checkpoint_due(seconds(), last_checkpoint)) save_state(pass + 1);
    }
    m_stats.seconds = seconds();
    m_stats.max_chunk_seconds = chunk_timing.longest;
    if (!m_opts.state_path.empty() && (m_stats.cancelled || m_opts.state_at_end)) save_state(pass);
    std::vector<MvViewStats> per_view;
    std::vector<uint64_t> dropped;
    m_stats.counters = thread_sums(per_view, dropped);
    for (size_t s = 0; s < m_views.size(); ++s) {
        per_view[s] += m_mv_stats_before[s];
        m_mv_films[s].nonfinite += dropped[s];
        m_stats.counters.nonfinite += dropped[s];
    }
    // Contributions received: those in the film plus those dropped as not finite (counted from
    // the films rather than per splat).
    for (size_t s = 0; s < m_views.size(); ++s) {
        per_view[s].received += m_mv_films[s].nonfinite;
        for (uint32_t r : m_mv_films[s].received) per_view[s].received += r;
    }
    state.clear(); // the threads' caches
    pass_film_ptr.reset();
    arena.execute([&] { develop_multiview(); });
    for (size_t s = 0; s < m_views.size(); ++s) {
        m_results[s].mv = per_view[s];
        m_stats.mv += per_view[s];
    }
}

bool Renderer::adaptive_maps(const MvConfig &cfg) const {
    // The adaptive maps' statistics are kept only if a map will be made (after the warm-up).
    const int warmup = std::max(2, cfg.adaptive_warmup);
    if (m_opts.pass_count > 0) return cfg.adaptive && m_opts.pass_count > warmup;
    return cfg.adaptive && (m_opts.time_budget > 0.0 || spp_target() > warmup);
}

std::vector<SplatFootprint> Renderer::prepare_multiview_render(MvConfig &cfg) {
    const MultiviewSettings settings = multiview_settings(m_scene);
    cfg = settings.cfg;
    m_stats.method = "mvpt";
    m_stats.estimator = cfg.estimator == MvEstimator::Balance ? (cfg.mis_selected_only ? "balance-selected" : "balance")
                                                              : (cfg.mis_selected_only ? "weighted-selected" : "weighted");
    m_mv_stats_before.assign(m_views.size(), MvViewStats{});
    return prepare_multiview(settings.path, settings.volpath, cfg, adaptive_maps(cfg));
}

std::vector<SplatFootprint> Renderer::prepare_multiview(const PathIntegrator *path, const VolPathIntegrator *volpath,
                                                        const MvConfig &cfg, bool adaptive) {
    const auto &cams = m_scene.cameras();
    // The method's context: views by slot, their seeds, the maps of the current pass.
    m_mv = MvContext{};
    m_mv.scene = &m_scene;
    m_mv.path = path;
    m_mv.volpath = volpath;
    m_mv.cfg = cfg;
    // Moving shapes or lights: a shared sample keeps its time (§3 test 1).
    m_mv.scene_moves = m_scene.is_animated();
    for (const auto &light : m_scene.lights()) m_mv.scene_moves |= light->moves();
    m_mv_films.clear();
    for (int v : m_views) {
        const Camera &cam = *cams[v];
        m_mv.views.push_back({&cam, uint32_t(v), cam.shutter_open, cam.shutter_close - cam.shutter_open});
        m_mv.seeds.push_back(m_opts.seed ? *m_opts.seed : cam.seed);
        if (!cam.film.filter->is_box() && cam.film.filter->radius() > float(SplatFootprint::MaxRadius))
            throw std::runtime_error("view '" + cam.id + "': multi-view path tracing splats with filters of radius up to " +
                                     std::to_string(SplatFootprint::MaxRadius) + " pixels");
    }
    m_mv.prepare(); // the sample windows: crop windows grown by the filters' reach
    // The control variate of the balance estimator needs E[sum W] = 1 (§5: D over all valid views).
    const bool use_cv = cfg.estimator == MvEstimator::Balance && cfg.control_variate && !cfg.mis_selected_only;
    std::vector<SplatFootprint> footprints;
    for (size_t slot = 0; slot < m_views.size(); ++slot) {
        const FilmDesc &f = m_mv.views[slot].camera->film;
        footprints.push_back(SplatFootprint::of(f.crop_x, f.crop_y, f.crop_width, f.crop_height, *f.filter,
                                                Sampler::dimension_key(DimSplatBase + m_mv.views[slot].scene_index)));
        m_mv_films.emplace_back(f.crop_width, f.crop_height, m_mv.windows[slot].margin, cfg.estimator, use_cv, adaptive);
        m_mv.native_map.push_back(m_mv_films.back().map.data());
    }
    m_scene.prepare_segment_culling(); // visibility bundles that meet no occluder are not traced
    m_mv.rig.reset();
    // (Through media every camera segment is walked for its transmittance: no cells.)
    if (m_mv.static_shift && m_scene.occluder_bvh() && m_mv.views.size() >= 2 && !volpath) {
        // Lens points of every view: the corners of the square around each lens disk.
        std::vector<Point3f> lens;
        for (const MvView &v : m_mv.views)
            for (Vec2f xi : {Vec2f(-1.f, -1.f), Vec2f(1.f, -1.f), Vec2f(-1.f, 1.f), Vec2f(1.f, 1.f)})
                lens.push_back(v.camera->lens_point(v.t0, xi));
        if (cfg.rig_cells > 0)
            m_mv.rig = std::make_shared<RigVisibility>(*m_scene.occluder_bvh(), lens, m_mv.across, cfg.rig_cells);
    }

    return footprints;
}

std::vector<Renderer::Tile> Renderer::multiview_tiles() const {
    // Tiles by image region, then view: consecutive tiles render the same region of every
    // view, whose native samples splat into overlapping neighbourhoods of the other views, so
    // that a thread's splat cache sums a pixel's contributions before handing them on. Tasks
    // are runs of consecutive tiles, not whole regions: a 48^2 film has 9 regions, and two
    // threads sharing 9 tasks idled 8 % of each light-field pass (CPU use 0.91 -> 0.99).
    // (Tiles cover the sample windows, in window coordinates.)
    std::vector<Tile> tiles;
    for (size_t slot = 0; slot < m_views.size(); ++slot) {
        constexpr int TileSize = 16;
        const SampleWindow &w = m_mv.windows[slot];
        for (int y = 0; y < w.height(); y += TileSize)
            for (int x = 0; x < w.width(); x += TileSize)
                tiles.push_back({int(slot), x, y, std::min(x + TileSize, w.width()), std::min(y + TileSize, w.height())});
    }
    std::stable_sort(tiles.begin(), tiles.end(),
                     [](const Tile &a, const Tile &b) { return std::tie(a.y0, a.x0) < std::tie(b.y0, b.x0); });
    return tiles;
}

void Renderer::fold_pass(MvPassFilm &pass_film) {
    // Each pixel's pass estimate into the accumulators, in blocks of pixels of one view.
    constexpr size_t Block = 4096;
    std::vector<std::pair<size_t, size_t>> blocks; // (slot, first pixel)
    for (size_t slot = 0; slot < m_views.size(); ++slot)
        for (size_t p = 0; p < m_mv_films[slot].pixels(); p += Block) blocks.emplace_back(slot, p);
    tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
        const auto [slot, begin] = blocks[b];
        MvFilm &mf = m_mv_films[slot];
        mf.fold(pass_film, pass_film.offset(int(slot)), begin, std::min(mf.pixels(), begin + Block));
    });
    for (MvFilm &mf : m_mv_films) ++mf.passes;
}

void Renderer::update_native_maps(int passes, double per_pixel) {
    // Views in groups of about 2^22 pixels, the views of a group in parallel and each view's
    // map in parallel over its pixels: the temporary arrays of the maps stay within a fixed
    // size however many threads run.
    constexpr size_t GroupPixels = size_t(1) << 22;
    for (size_t first = 0; first < m_views.size();) {
        size_t last = first, group = 0;
        while (last < m_views.size() && (last == first || group + m_mv_films[last].pixels() <= GroupPixels))
            group += m_mv_films[last++].pixels();
        tbb::parallel_for(first, last, [&](size_t slot) {
            const FilmDesc &f = m_mv.views[slot].camera->film;
            MvFilm &mf = m_mv_films[slot];
            AdaptiveInput in;
            in.width = f.crop_width;
            in.height = f.crop_height;
            in.passes = passes;
            in.v_sum = mf.sum.data();
            in.e_sum = mf.e_sum.data();
            in.e_sq = mf.e_sq.data();
            in.s_sq = mf.s_sq.data();
            in.native = mf.native.data();
            in.received = mf.received.data();
            in.previous_level = mf.level;
            in.eps = m_mv.cfg.adaptive_eps;
            std::vector<uint16_t> map;
            mf.level = adapt_native_map(in, m_mv.cfg.adaptive_max, per_pixel * double(mf.pixels()), map);
            mf.set_map(map);
        });
        first = last;
    }
}

void Renderer::develop_multiview() {
    // The estimate and its variance are the mean and spread of the per-pass estimates, as for
    // path tracing (the weighted estimator: its ratio of sums over all passes plus the plain mean
    // of native-only radiance); then the multi-view AOVs. Each view's accumulators are freed as
    // soon as its images are made.
    m_results.assign(m_views.size(), ViewResult{});
    tbb::parallel_for(size_t(0), m_views.size(), [&](size_t slot) {
        const Camera &cam = *m_mv.views[slot].camera;
        MvFilm &mf = m_mv_films[slot];
        ViewResult r;
        r.id = cam.id;
        r.width = mf.width;
        r.height = mf.height;
        const size_t n = mf.pixels();
        r.rgb.resize(3 * n);
        r.variance.resize(3 * n);
        r.weight_sum.resize(n);
        for (size_t p = 0; p < n; ++p) {
            mf.develop(p, &r.rgb[3 * p], &r.variance[3 * p]);
            r.samples += mf.native[p];
            r.weight_sum[p] = mf.weight_sum(p);
        }
        r.contributions.assign(mf.received.begin(), mf.received.end());
        r.sample_count = std::move(mf.native);
        r.nonfinite = mf.nonfinite;
        mf = MvFilm{};
        m_results[slot] = std::move(r);
    });
}

} // namespace mvpt
