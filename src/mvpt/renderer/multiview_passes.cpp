// Multi-view path tracing's passes (docs/multiview-path-tracing.md): native samples of every
// view, shared through mv_native_sample, splatted through per-thread caches into the pass's
// fixed-point sums, which are folded into the accumulators once per pass; adaptive
// native-sample maps between passes (§8).
#include "film_blocks.h"
#include "pass_schedule.h"
#include "renderer.h"

#include "../integrators/multiview/mv_adaptive.h"
#include "../integrators/multiview/mv_sample.h"
#include "../integrators/multiview/mv_split_choice.h"
#include "../integrators/multiview/mvpath.h"
#include "../integrators/path/volpath.h"
#include "../core/sampler.h"
#include "../render/bsdf.h"
#include "../render/camera.h"
#include "../render/shape.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <tuple>

namespace mvpt {

namespace {
/// The key of the regions' random order (multiview_tiles).
constexpr uint64_t RegionOrderKey = 0x726567696f6e; // "region"
/// The key of a thinned pass's draws of which native samples it takes.
constexpr uint64_t ThinKey = 0x7468696e; // "thin"
/// The key of the pilot's seeds and pixels (pilot_splits), and its size: native-sample pairs
/// over all views (at most one per PilotShare pixels), and at least per view.
constexpr uint64_t PilotKey = 0x70696c6f74; // "pilot"
constexpr size_t PilotPixels = 8192, PilotShare = 8, MinPilotPixels = 16;
constexpr int PilotTask = 32; ///< cells of one pilot task
/// Under a time budget a render runs at least this many passes where it can: the two passes
/// that are each other's control variate (§5) and one whose control variate comes from both
/// (docs/performance.md, "Choosing the number of splits": 3 and 4 measured on four cases).
/// The first is whole; later ones are thinned to the share that lets them fit ("Passes thinned
/// to the budget"), and the splits are chosen so that this share is at least MinPassShare.
constexpr double MinBudgetPasses = 3.0, MinPassShare = 0.25;
/// A pass thinned to share q lasts about (ThinOverhead + q) times a whole pass (its sampling and
/// splatting shrink with q, the fold and the tiles' fixed costs do not; 32 views of 96^2, two
/// threads: 0.14 at q = 0.1, 0.35 at 0.25, 0.5-0.6 at 0.5, 0.82 at 0.75). Under a time budget,
/// the passes still wanted are whole if they fit with ThinSlack of a pass to spare (a pass
/// that overruns the budget is dropped), else thinned to the q that does, if q >= MinThinShare.
constexpr double ThinOverhead = 0.05, ThinSlack = 0.1, MinThinShare = 0.1;

/// The whole passes' time that the passes a render still wants under a time budget need at the
/// least, `done` passes done: the first whole, the others of MinPassShare.
double budget_passes(int done) {
    const double thinned = MinBudgetPasses - std::max(done, 1);
    return (done == 0 ? 1.0 : 0.0) + std::max(thinned, 0.0) * (MinPassShare + ThinOverhead) + ThinSlack;
}

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

/// Whether a shape of `scene` has a BSDF without a smooth lobe (glass, a mirror, a null
/// surface): a first vertex that no view can share (§3 test 4). Instances take their shape
/// group's materials, which are not looked into: they count as such shapes.
bool has_specular_surfaces(const Scene &scene) {
    for (const auto &shape : scene.shapes())
        if (!shape->bsdf || !shape->bsdf->has_smooth()) return true;
    return false;
}

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

/// Multi-view path tracing's part in the pass loop (pass_schedule.h): one pass per step over
/// every view's tiles, region by region, its splats folded into the accumulators between
/// passes, then the next pass's native-sample maps. A pass stopped (Ctrl-C, the time budget)
/// is dropped, except the first, whose regions come in a random order: the regions it
/// finished are kept, scaled by the inverse of their share (docs/multiview-path-tracing.md,
/// "A first pass cut short"). Later passes take the regions in scan order; under a time budget
/// they are thinned to what fits where whole ones do not ("Passes thinned to the budget").
class Renderer::MultiviewPasses final : public PassSchedule {
public:
    /// Prepares the method and `r`'s accumulators, and reads the state a render resumes from.
    MultiviewPasses(Renderer &r, tbb::task_arena &arena, const std::atomic<bool> &cancel);
    bool done(int pass) const override;
    int step_end(int pass, double fit, double) override;
    StepTiles begin_step(int pass, int end) override;
    uint64_t render(size_t t) override;
    /// A later pass stops between any two tiles (it is dropped), the first between chunks,
    /// which end with a region.
    bool can_abandon(double, double, bool between_chunks) const override { return m_pass > 0 || between_chunks; }
    bool budget_stops(int) const override { return true; }
    size_t chunk_end(size_t end) const override {
        return m_pass > 0 || end == 0 ? end : m_region_end[m_region[end - 1]];
    }
    uint64_t kept(const ChunksDone &done) const override;
    bool abandon(const ChunksDone &done) override;
    void end_step() override;
    /// A whole pass of the next pass's maps (made at the end of the step: the adaptive maps'
    /// first takes more native samples than the passes before it).
    double whole_pass_seconds(double seconds) const override;
    double fraction(uint64_t samples) const override;
    double fraction_after(int pass) const override;
    void save(int next_pass, double elapsed, double last_pass) override;
    /// After the loop: the statistics into the render's, the images developed.
    void finish();

private:
    uint64_t render_tile(MvThreadState &ts, const Tile &tile);
    /// The work of each tile of a pass of share `share`, in native samples weighed by the tile's
    /// cost per sample in the last pass over the mean (what sizes the chunks: run_in_chunks).
    std::vector<double> tile_work(double share) const;
    /// Whether a thinned pass takes the j-th of the native samples its map gives pixel (px, py) of
    /// view `slot` (a function of the pass, not of the sample's index: the samples taken are
    /// numbered on from the pixel's next one, so that no index is taken twice).
    bool thin_takes(int slot, int px, int py, uint32_t j) const;
    /// The native samples a thinned pass takes of the n its map gives pixel (px, py) of `slot`.
    uint32_t thin_count(int slot, int px, int py, uint32_t n) const {
        uint32_t k = 0;
        for (uint32_t j = 0; j < n; ++j) k += thin_takes(slot, px, py, j);
        return k;
    }
    /// fold_pass counted every native sample of each pixel's map: for the crop-window pixels of
    /// tiles [begin, end), subtracts those `skipped(slot, n, px, py)` says were not taken of the
    /// pixel's n, at (px, py) in full-film coordinates.
    template <class Skipped> void uncount(size_t begin, const Skipped &skipped);
    /// After a pass (not a thinned last one): the native-sample maps of the next (§8), on their schedule.
    void update_maps();
    /// Whether the maps may be made after pass `pass` (update_maps: its schedule aside).
    bool maps_after(int pass) const { return m_adaptive && pass + 1 >= std::max(2, m_cfg.adaptive_warmup); }
    /// The splits of the shared vertex and the paths of a specular first vertex that are
    /// `auto` (0 in m_cfg), chosen (§7, "Choosing the number of splits"): a pilot of two
    /// native samples at each of a fixed set of pixels of every view, from seeds of its own
    /// and with one native sample per pixel everywhere, its contributions recorded, not
    /// splatted. A function of the scene and the settings alone: every range, resume and
    /// thread count of a render chooses the same. Ctrl-C (`cancel`) skips its tasks not begun.
    void pilot_splits(const std::atomic<bool> &cancel);
    /// Two path-traced samples at each of the pilot's pixels of cells [begin, end) of view
    /// `slot` (sample indices of their own), into `probe` (predicted_gain).
    void path_traced_pilot(const MvContext &pilot, int slot, std::pair<int, int> cells, int begin, int end,
                           MvSplitProbe &probe) const;
    /// Under a time budget with splits chosen per render, after the render's first pass (of
    /// `last_pass` seconds, `fit` of them left): the splits chosen again from its measured
    /// length (§7, "Choosing the number of splits"); returns how many passes of the new splits
    /// fit.
    double rechoose_splits(int pass, double fit, double last_pass);
    /// The pilot's native samples of view `slot` into `prim`: two at one pixel of each of cells
    /// [begin, end) of a grid of `cells` (x, y) over the crop window (pilot_cells).
    void pilot_samples(int slot, std::pair<int, int> cells, int begin, int end, MvPrimaries &prim) const;
    /// The pilot's grid over view `slot`'s crop window: about `pixels` cells, at most one per pixel.
    std::pair<int, int> pilot_cells(int slot, size_t pixels) const;
    /// The threads' caches flushed and the pass's sums (times `scale`) folded into the
    /// accumulators, in the render's arena; with `hold`, a whole first pass held instead where
    /// the estimator takes a control variate (Renderer::hold_pass).
    void fold_pass(double scale, double weight = 1.0, bool hold = false);
    /// The crop-window pixels of a tile, [x0, x1) x [y0, y1) in crop-window coordinates.
    struct CropRect {
        int x0, y0, x1, y1;
        uint64_t pixels() const { return uint64_t(std::max(0, x1 - x0)) * uint64_t(std::max(0, y1 - y0)); }
    };
    CropRect crop_of(const Tile &tile) const {
        const Film &mf = m_r.m_films[tile.view_slot];
        const int m = mf.margin;
        return {std::max(tile.x0 - m, 0), std::max(tile.y0 - m, 0), std::min(tile.x1 - m, mf.width),
                std::min(tile.y1 - m, mf.height)};
    }
    /// The statistics of the threads, summed by slot (the ray counters with the runs' before);
    /// the first native sample with a dropped contribution goes to the render's statistics.
    RayCounters thread_sums(std::vector<MvViewStats> &stats, std::vector<uint64_t> &dropped);

    Renderer &m_r;
    MvConfig m_cfg;
    std::vector<SplatFootprint> m_footprints;
    bool m_adaptive = false;
    // Target: spp native samples per pixel on average, the same for every view (all views take
    // part in every pass, n >= 1, since each view's D needs its own strategy). Passes take one
    // native sample per pixel until the adaptive maps start, then `adaptive_budget` per pixel.
    // A range renders its passes; its pixels' native samples are numbered from first_pass times
    // the most a pixel takes in a pass, its margins' from first_pass (one per pass).
    int m_spp_target = 0;
    bool m_range = false, m_unbounded = false;
    uint32_t m_sample0 = 0, m_margin0 = 0;
    uint64_t m_pixels_total = 0;
    std::vector<Tile> m_tiles;
    bool m_random_order = false; ///< the tiles' regions are in a random order (the first pass)
    /// The region of each tile (regions numbered in the tiles' order) and where each ends.
    std::vector<uint32_t> m_region;
    std::vector<size_t> m_region_end;
    std::unique_ptr<MvPassFilm> m_pass_film;
    tbb::enumerable_thread_specific<MvThreadState> m_state;
    // The current pass and its native samples (of the crop windows).
    int m_pass = 0;
    uint64_t m_pass_samples = 0;
    /// The share of its native samples the pass takes (below 1: a thinned pass), and those of the
    /// crop windows it took.
    double m_share = 1.0;
    /// The thinned pass is the render's last (after it ran, done() says so).
    bool m_last_thinned = false;
    std::atomic<uint64_t> m_thin_taken{0};
    /// Each tile's seconds and native samples in the last pass (scan order; empty before), by
    /// which the next pass's chunks are sized.
    std::vector<std::pair<float, uint32_t>> m_tile_cost;
    /// Splits chosen per render under a time budget (m_pass_unit > 0): chosen again after the
    /// first pass from the pilot's statistics and the seconds of a pass per unit of model cost
    /// its pace gave.
    SplitStatistics m_pilot;
    double m_pass_unit = 0.0;
};

Renderer::MultiviewPasses::MultiviewPasses(Renderer &r, tbb::task_arena &arena, const std::atomic<bool> &cancel)
    : PassSchedule(arena), m_r(r), m_footprints(r.prepare_multiview_render(m_cfg)),
      m_state([this] { return MvThreadState(*m_pass_film); }) {
    const RenderOptions &o = r.m_opts;
    m_adaptive = r.adaptive_maps(m_cfg);
    if (!o.resume_path.empty()) r.read_state(o.resume_path);
    m_spp_target = r.spp_target();
    m_range = o.pass_count > 0;
    m_unbounded = m_range || (o.time_budget > 0.0 && o.spp == 0);
    const uint64_t per_pass = m_adaptive ? uint64_t(m_cfg.adaptive_max) : 1;
    if ((uint64_t(o.first_pass) + uint64_t(o.pass_count)) * per_pass > UINT32_MAX)
        throw std::invalid_argument("the pass range numbers samples beyond 2^32");
    m_sample0 = uint32_t(uint64_t(o.first_pass) * per_pass), m_margin0 = uint32_t(o.first_pass);
    for (const Film &mf : r.m_films) m_pixels_total += mf.pixels();
    m_random_order = r.m_first_pass == 0;
    m_tiles = r.multiview_tiles(m_random_order);
    for (size_t t = 0; t < m_tiles.size(); ++t) {
        const bool next = t > 0 && (m_tiles[t].x0 != m_tiles[t - 1].x0 || m_tiles[t].y0 != m_tiles[t - 1].y0);
        if (next) m_region_end.push_back(t);
        m_region.push_back(uint32_t(m_region_end.size()));
    }
    m_region_end.push_back(m_tiles.size());
    arena.execute(
        [&] { m_pass_film = std::make_unique<MvPassFilm>(m_footprints, m_cfg.estimator == MvEstimator::Weighted); });
    // Paths of specular first vertices are split only where the scene has such surfaces.
    if (m_cfg.delta_splits == 0 && !has_specular_surfaces(r.m_scene)) m_cfg.delta_splits = r.m_mv.cfg.delta_splits = 1;
    if (m_cfg.splits == 0 || m_cfg.delta_splits == 0 || o.pilot_only) pilot_splits(cancel);
    r.m_stats.splits = m_cfg.splits;
    r.m_stats.delta_splits = m_cfg.delta_splits;
}

std::pair<int, int> Renderer::MultiviewPasses::pilot_cells(int slot, size_t pixels) const {
    const Film &mf = m_r.m_films[size_t(slot)];
    const int side = int(std::ceil(std::sqrt(double(pixels))));
    return {std::min(side, mf.width), std::min(side, mf.height)};
}

void Renderer::MultiviewPasses::pilot_samples(int slot, std::pair<int, int> cells, int begin, int end,
                                              MvPrimaries &prim) const {
    const Film &mf = m_r.m_films[size_t(slot)];
    const SampleWindow &w = m_r.m_mv.windows[size_t(slot)];
    const auto [gx, gy] = cells;
    const uint64_t key = hash_ints(m_r.m_mv.seeds[size_t(slot)], m_r.m_mv.views[size_t(slot)].scene_index, PilotKey);
    for (int c = begin; c < end; ++c) {
        const int i = c % gx, j = c / gx;
        const int x0 = i * mf.width / gx, x1 = (i + 1) * mf.width / gx;
        const int y0 = j * mf.height / gy, y1 = (j + 1) * mf.height / gy;
        const uint64_t h = hash_ints(key, uint64_t(i), uint64_t(j));
        const int x = x0 + int(uint32_t(h) % uint32_t(x1 - x0)), y = y0 + int(uint32_t(h >> 32) % uint32_t(y1 - y0));
        for (uint32_t index = 0; index < 2; ++index) prim.push(x + w.margin + w.x0, y + w.margin + w.y0, index);
    }
}

void Renderer::MultiviewPasses::path_traced_pilot(const MvContext &pilot, int slot, std::pair<int, int> cells, int begin,
                                                  int end, MvSplitProbe &probe) const {
    MvPrimaries prim;
    pilot_samples(slot, cells, begin, end, prim);
    for (uint32_t &index : prim.sample_index) index += 2; // (the native pilot's are 0 and 1)
    mv_trace_primaries(pilot, slot, prim);
    const MvView &l = pilot.views[size_t(slot)];
    const Integrator &tracer = pilot.volpath ? static_cast<const Integrator &>(*pilot.volpath)
                                             : static_cast<const Integrator &>(*pilot.path);
    RayCounters counters;
    for (size_t i = 0; i + 1 < prim.size(); i += 2) {
        std::array<double, 2> pair{};
        for (size_t j = 0; j < 2; ++j) {
            Sampler sampler(l.camera->sampler_kind, pilot.seeds[size_t(slot)]);
            prim.camera.start(sampler, i + j, l.scene_index, prim.px[i + j], prim.py[i + j], prim.sample_index[i + j], 0);
            const Spectrum L = tracer.li(*pilot.scene, prim.rays[i + j], sampler, counters);
            pair[j] = std::isfinite(L.mean()) ? double(L.mean()) : 0.0;
        }
        probe.path_traced.push_back(pair);
    }
}

void Renderer::MultiviewPasses::pilot_splits(const std::atomic<bool> &cancel) {
    const size_t views = m_r.m_mv.views.size();
    auto set = [&](int b, int k) {
        if (m_cfg.splits == 0) m_cfg.splits = m_r.m_mv.cfg.splits = b;
        if (m_cfg.delta_splits == 0) m_cfg.delta_splits = m_r.m_mv.cfg.delta_splits = k;
    };
    if (views < 2) return set(1, 1); // nothing is shared
    MvContext pilot = m_r.m_mv;
    pilot.cfg.splits = PilotSplits;
    for (uint32_t &seed : pilot.seeds) seed = uint32_t(hash_ints(seed, PilotKey));
    size_t largest = 0; // every view takes one native sample per pixel, whatever the maps say now
    for (const SampleWindow &w : pilot.windows) largest = std::max(largest, size_t(w.width()) * size_t(w.height()));
    const std::vector<uint16_t> ones(largest, 1);
    pilot.native_map.assign(views, ones.data());
    // Tasks of PilotTask cells of one view, each recording into a probe of its own.
    struct Task {
        int slot, begin, end;
        std::pair<int, int> cells;
    };
    std::vector<Task> tasks;
    const size_t pairs = std::min(PilotPixels, size_t(m_pixels_total) / PilotShare);
    for (size_t slot = 0; slot < views; ++slot) {
        const auto cells = pilot_cells(int(slot), std::max(MinPilotPixels, pairs / views));
        for (int c = 0; c < cells.first * cells.second; c += PilotTask)
            tasks.push_back({int(slot), c, std::min(c + PilotTask, cells.first * cells.second), cells});
    }
    std::vector<MvSplitProbe> probes(tasks.size());
    std::atomic<size_t> taken{0};
    const auto t0 = std::chrono::steady_clock::now();
    arena().execute([&] {
        tbb::parallel_for(size_t(0), tasks.size(), [&](size_t t) {
            if (cancel.load()) return; // (the render stops before its first pass)
            const int slot = tasks[t].slot;
            MvThreadState &ts = m_state.local();
            MvSplatSink sink{ts.cache, ts.dropped.data(), &ts.first_dropped}; // (nothing is splatted)
            std::vector<MvViewStats> stats(views);
            RayCounters counters;
            MvPrimaries &prim = ts.primaries;
            prim.clear();
            pilot_samples(slot, tasks[t].cells, tasks[t].begin, tasks[t].end, prim);
            taken += prim.size();
            ts.pending.probe = &probes[t];
            mv_trace_primaries(pilot, slot, prim);
            mv_native_samples(pilot, slot, prim, ts.scratch, ts.pending, sink, counters, stats.data());
            ts.pending.probe = nullptr;
        });
    });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    arena().execute([&] {
        tbb::parallel_for(size_t(0), tasks.size(), [&](size_t t) {
            if (!cancel.load()) path_traced_pilot(pilot, tasks[t].slot, tasks[t].cells, tasks[t].begin, tasks[t].end, probes[t]);
        });
    });
    double writes = 0.0;
    for (const SplatFootprint &f : m_footprints) writes += f.mean_writes() / double(views);
    SplitStatistics st = split_statistics(probes, m_cfg.adaptive_eps, writes);
    m_r.m_stats.split_pilot = {st.a, st.r, st.c0, st.c1};
    // The paths of specular first vertices for the splits chosen without a budget (or given).
    const int b0 = m_cfg.splits > 0 ? m_cfg.splits : choose_splits(st);
    const int k = m_cfg.delta_splits > 0 ? m_cfg.delta_splits : choose_delta_splits(st, b0);
    m_r.m_stats.predicted_gain = predicted_gain(st, b0, k);
    const double pilot_cost = st.c0 + PilotSplits * (st.c1 + st.d1); // (the pilot's own paths)
    // From here on they are a fixed part of a native sample's variance and cost.
    st.a += std::max(st.r_d, 0.0) / k, st.c0 += k * st.d1, st.r_d = st.d1 = 0.0;
    const double budget = m_r.m_opts.time_budget;
    if (m_cfg.splits > 0 || !(budget > 0.0) || m_range || !(st.c1 > 0.0) || taken.load() == 0)
        return set(choose_splits(st), k);
    // Under a time budget, a pass of B splits lasts about the pilot's time per unit of model
    // cost times its own cost, and the splits leave time for MinBudgetPasses passes, the later
    // ones thinned (budget_passes); budgets make renders depend on time anyway, so the choice may too.
    double pass_samples = 0.0;
    for (const Film &mf : m_r.m_films) pass_samples += double(mf.map.size());
    m_pass_unit = pass_samples * seconds / (double(taken.load()) * pilot_cost);
    m_pilot = st;
    set(choose_splits(st, splits_fitting(st, m_pass_unit, budget, budget_passes(0))), k);
}

double Renderer::MultiviewPasses::rechoose_splits(int pass, double fit, double last_pass) {
    // The pilot records rather than splats: what a pass spends beyond its pace (the splats, the
    // fold between passes) is a part of a native sample's cost that no split changes.
    SplitStatistics st = m_pilot;
    st.c0 = std::max(st.c0, last_pass / m_pass_unit - m_cfg.splits * st.c1);
    const int b = choose_splits(st, splits_fitting(st, m_pass_unit, fit * last_pass, budget_passes(pass)));
    const double longer = (st.c0 + b * st.c1) / (st.c0 + m_cfg.splits * st.c1);
    m_cfg.splits = m_r.m_mv.cfg.splits = m_r.m_stats.splits = b;
    return fit / longer;
}

bool Renderer::MultiviewPasses::done(int pass) const {
    if (m_last_thinned) return true;
    if (m_range) return pass >= m_r.m_opts.pass_count;
    return !m_unbounded && !(m_r.m_native_done < double(m_spp_target) - 1e-6);
}

int Renderer::MultiviewPasses::step_end(int pass, double fit, double last_pass) {
    m_share = 1.0, m_last_thinned = false;
    if (m_pass_unit > 0.0 && pass == m_r.m_first_pass + 1 && fit > 0.0 && std::isfinite(fit))
        fit = rechoose_splits(pass, fit, last_pass);
    const RenderOptions &o = m_r.m_opts; // tests: the last passes of a range thinned
    if (o.thin_last_pass < 1.0 && m_range && pass + o.thin_passes >= o.pass_count && (pass > 0 || o.pass_count == 1)) {
        m_share = o.thin_last_pass, m_last_thinned = pass + 1 == o.pass_count;
        return pass + 1;
    }
    // The first pass is cut rather than thinned, and a range's passes are whole.
    if (pass == 0 || m_range || !std::isfinite(fit)) return fit >= 1.0 ? pass + 1 : pass;
    // The passes still wanted (at least the next) each whole if they fit with time to spare,
    // else thinned to what does; if that is too thin, a last pass thinned to what fits ("Passes
    // thinned to the budget").
    const int wanted = std::max(1, int(MinBudgetPasses) - pass);
    double q = (fit - ThinSlack) / wanted - ThinOverhead;
    if (q >= 1.0) return pass + 1;
    m_last_thinned = !(q >= MinThinShare) || wanted == 1;
    if (m_last_thinned) q = fit - ThinOverhead - ThinSlack;
    if (!(q >= MinThinShare)) return pass; // (also when fit is not a number)
    m_share = q;
    return pass + 1;
}

StepTiles Renderer::MultiviewPasses::begin_step(int pass, int) {
    m_pass = pass;
    if (pass > 0 && m_random_order) m_tiles = m_r.multiview_tiles(m_random_order = false);
    m_pass_samples = 0;
    for (const Film &mf : m_r.m_films) m_pass_samples += mf.map_total;
    m_thin_taken = 0;
    StepTiles step;
    for (double work : tile_work(m_share)) step.add(work);
    m_tile_cost.assign(m_random_order ? 0 : m_tiles.size(), {0.f, 0u});
    return step;
}

std::vector<double> Renderer::MultiviewPasses::tile_work(double share) const {
    // Each tile's native samples (the adaptive maps make them unequal), counted in parallel,
    // times its cost per native sample in the last pass over the mean (regions differ).
    double seconds = 0.0, last = 0.0;
    if (!m_random_order && m_tile_cost.size() == m_tiles.size())
        for (const auto &[s, n] : m_tile_cost) seconds += s, last += double(n);
    const double mean = seconds > 0.0 && last > 0.0 ? seconds / last : 0.0;
    std::vector<double> work(m_tiles.size());
    auto tile = [&](size_t t) {
        const Tile &tile = m_tiles[t];
        const Film &mf = m_r.m_films[tile.view_slot];
        const size_t width = size_t(m_r.m_mv.windows[tile.view_slot].width());
        uint64_t n = 0;
        for (int y = tile.y0; y < tile.y1; ++y)
            for (int x = tile.x0; x < tile.x1; ++x) n += mf.map[size_t(y) * width + size_t(x)];
        const auto [s, last_n] = mean > 0.0 ? m_tile_cost[t] : std::pair<float, uint32_t>{};
        const double cost = last_n > 0 ? std::clamp(double(s) / last_n / mean, 0.1, 10.0) : 1.0;
        work[t] = share * double(n) * cost;
    };
    arena().execute([&] { tbb::parallel_for(size_t(0), m_tiles.size(), tile); });
    return work;
}

bool Renderer::MultiviewPasses::thin_takes(int slot, int px, int py, uint32_t j) const {
    const MvContext &mv = m_r.m_mv;
    const uint64_t h =
        hash_ints(mv.seeds[size_t(slot)], mv.views[size_t(slot)].scene_index, px, py, uint32_t(m_pass), j, ThinKey);
    return double(bits_to_unit_float(uint32_t(h))) < m_share;
}

double Renderer::MultiviewPasses::whole_pass_seconds(double seconds) const {
    // The last pass whole, then scaled by the next's work over its own: its native samples, each
    // tile's at its cost per sample in the last pass where the last pass ran in scan order.
    const double whole = m_share < 1.0 ? seconds / (ThinOverhead + m_share) : seconds;
    double next = 0.0, last = 0.0;
    if (!m_tile_cost.empty()) {
        for (double w : tile_work(1.0)) next += w;
        for (const auto &[s, n] : m_tile_cost) last += double(n);
        last /= m_share;
    } else {
        for (const Film &mf : m_r.m_films) next += double(mf.map_total);
        last = double(m_pass_samples);
    }
    return next > 0.0 && last > 0.0 ? whole * next / last : whole;
}

uint64_t Renderer::MultiviewPasses::render(size_t t) {
    const auto t0 = std::chrono::steady_clock::now();
    const uint64_t n = render_tile(m_state.local(), m_tiles[t]);
    if (!m_tile_cost.empty())
        m_tile_cost[t] = {std::chrono::duration<float>(std::chrono::steady_clock::now() - t0).count(), uint32_t(n)};
    return n;
}

uint64_t Renderer::MultiviewPasses::render_tile(MvThreadState &ts, const Tile &tile) {
    const MvContext &mv = m_r.m_mv;
    MvSplatSink sink{ts.cache, ts.dropped.data(), &ts.first_dropped};
    const SampleWindow &w = mv.windows[tile.view_slot];
    const Film &mf = m_r.m_films[tile.view_slot];
    MvPrimaries &prim = ts.primaries;
    prim.clear();
    const bool thin = m_share < 1.0;
    uint64_t taken = 0; // of the crop window, in a thinned pass
    for (int y = tile.y0; y < tile.y1; ++y)
        for (int x = tile.x0; x < tile.x1; ++x) {
            // Inside the crop window: the pixel's next native samples; in the margin: one
            // sample per pass. A thinned pass takes each with probability m_share.
            const int cx = x - w.margin, cy = y - w.margin;
            const bool inside = cx >= 0 && cy >= 0 && cx < mf.width && cy < mf.height;
            const uint32_t first = inside ? m_sample0 + mf.native[size_t(cy) * size_t(mf.width) + size_t(cx)]
                                          : m_margin0 + uint32_t(m_pass);
            const uint16_t n = mf.map[size_t(y) * size_t(w.width()) + size_t(x)];
            uint32_t k = 0;
            for (uint32_t j = 0; j < n; ++j)
                if (!thin || thin_takes(tile.view_slot, x + w.x0, y + w.y0, j)) prim.push(x + w.x0, y + w.y0, first + k++);
            if (inside) taken += k;
        }
    if (thin) m_thin_taken += taken;
    // The tile's camera rays as one stream, then each native sample, their suffixes traced as
    // wavefronts of the path tracer in batches.
    mv_trace_primaries(mv, tile.view_slot, prim);
    mv_native_samples(mv, tile.view_slot, prim, ts.scratch, ts.pending, sink, ts.counters, ts.stats.data());
    return prim.size();
}

uint64_t Renderer::MultiviewPasses::kept(const ChunksDone &done) const {
    if (done.finished) return m_share < 1.0 ? m_thin_taken.load() : m_pass_samples;
    // A cut first pass: one native sample per pixel of the tiles rendered (the adaptive maps
    // start later).
    uint64_t n = 0;
    if (m_pass == 0)
        for (size_t t = 0; t < done.prefix; ++t) n += crop_of(m_tiles[t]).pixels();
    return n;
}

void Renderer::MultiviewPasses::fold_pass(double scale, double weight, bool hold) {
    // What the caches still hold goes to the pass sums (exact integer sums).
    tbb::parallel_for(m_state.range(1), [](auto &r) {
        for (MvThreadState &ts : r) ts.cache.flush();
    });
    if (!hold || !m_r.hold_pass(*m_pass_film)) m_r.fold_pass(*m_pass_film, scale, weight);
}

template <class Skipped> void Renderer::MultiviewPasses::uncount(size_t begin, const Skipped &skipped) {
    tbb::parallel_for(begin, m_tiles.size(), [&](size_t t) {
        const Tile &tile = m_tiles[t];
        Film &mf = m_r.m_films[tile.view_slot];
        const SampleWindow &w = m_r.m_mv.windows[tile.view_slot];
        const CropRect c = crop_of(tile);
        for (int y = c.y0; y < c.y1; ++y)
            for (int x = c.x0; x < c.x1; ++x) {
                const size_t p = size_t(y) * size_t(mf.width) + size_t(x);
                mf.native[p] -= skipped(tile.view_slot, uint32_t(mf.n(p)), x + w.margin + w.x0, y + w.margin + w.y0);
            }
    });
}

bool Renderer::MultiviewPasses::abandon(const ChunksDone &done) {
    // Regions [0, regions) finished (chunk_end); none when the pass stopped inside a chunk.
    const uint32_t regions = done.prefix < m_region.size() ? m_region[done.prefix] : 0;
    if (m_pass > 0 || regions == 0) {
        for (MvThreadState &ts : m_state) ts.cache.discard();
        return false;
    }
    // A first pass cut short: its regions were taken in a random order (multiview_tiles), so
    // each was among the first `regions` with probability regions / all, and the pass's sums
    // divided by that are an unbiased estimate of the pass (docs/multiview-path-tracing.md).
    const double share = double(regions) / double(m_region_end.size());
    arena().execute([&] {
        fold_pass(1.0 / share);
        // The pixels of the regions not rendered took no native sample (fold counted one).
        uncount(done.prefix, [](int, uint32_t, int, int) { return 1u; });
    });
    m_r.m_native_done += double(kept(done)) / double(m_pixels_total);
    m_r.m_stats.cut_pass_share = share;
    return true;
}

void Renderer::MultiviewPasses::end_step() {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    if (m_share < 1.0) { // a thinned pass: its sums scaled by 1/q, weighing q (film.h)
        arena().execute([&] {
            fold_pass(1.0 / m_share, m_share);
            uncount(0, [&](int slot, uint32_t n, int px, int py) { return n - thin_count(slot, px, py, n); });
        });
        m_r.m_native_done += double(m_thin_taken.load()) / double(m_pixels_total);
        RenderStats &st = m_r.m_stats;
        ++st.thinned_passes, st.thinned_shares += m_share;
        if (m_last_thinned) st.thinned_pass_share = m_share;
        else update_maps();
    } else {
        // The films' first pass is held for the second's fold (§5, "The first two passes"),
        // unless a map made from it would draw the second's samples (a range from a later pass).
        const bool first = m_r.m_native_done == 0.0 && !maps_after(m_pass);
        arena().execute([&] { fold_pass(1.0, 1.0, first); });
        m_r.m_native_done += double(m_pass_samples) / double(m_pixels_total);
        update_maps();
    }
    m_r.m_stats.between_passes_seconds += std::chrono::duration<double>(clock::now() - t0).count();
}

void Renderer::MultiviewPasses::update_maps() {
    // Native-sample maps of the next pass (§8), frozen during it. Their statistics change by
    // about 1/passes per pass, so after 16 passes a map serves passes/8 passes (a map costs
    // about as much as folding a pass), except that the last pass's map spends only what is
    // left of the sample target. The schedule depends on the pass index alone.
    const int done = m_pass + 1;
    if (maps_after(m_pass)) {
        const double left = double(m_spp_target) - m_r.m_native_done;
        double per_pixel = m_cfg.adaptive_budget;
        const bool last = !m_unbounded && left < 2.0 * per_pixel;
        if (!m_unbounded) per_pixel = std::min(per_pixel, left);
        if (done <= 16 || done % (done / 8) == 0 || last)
            arena().execute([&] { m_r.update_native_maps(done, std::max(per_pixel, 1.0)); });
    }
}

double Renderer::MultiviewPasses::fraction(uint64_t samples) const {
    if (m_range) return (m_pass + double(samples) / double(m_pass_samples)) / m_r.m_opts.pass_count;
    if (m_unbounded) return 0.0;
    return std::min(1.0, (m_r.m_native_done + double(samples) / double(m_pixels_total)) / m_spp_target);
}

double Renderer::MultiviewPasses::fraction_after(int pass) const {
    if (m_range) return double(pass + 1) / m_r.m_opts.pass_count;
    return m_unbounded ? 0.0 : std::min(1.0, m_r.m_native_done / double(m_spp_target));
}

RayCounters Renderer::MultiviewPasses::thread_sums(std::vector<MvViewStats> &stats, std::vector<uint64_t> &dropped) {
    RenderStats &st = m_r.m_stats;
    RayCounters counters = st.counters;
    const size_t views = m_r.m_views.size();
    stats.assign(views, MvViewStats{});
    dropped.assign(views, 0);
    SampleKey first{st.nonfinite_sample, st.nonfinite_view, st.nonfinite_y, st.nonfinite_x};
    for (MvThreadState &ts : m_state) {
        keep_first(first, ts.first_dropped);
        counters += ts.counters;
        for (size_t s = 0; s < views; ++s) stats[s] += ts.stats[s], dropped[s] += ts.dropped[s];
    }
    st.nonfinite_sample = first[0], st.nonfinite_view = first[1], st.nonfinite_y = first[2], st.nonfinite_x = first[3];
    return counters;
}

void Renderer::MultiviewPasses::save(int next_pass, double elapsed, double last_pass) {
    std::vector<MvViewStats> stats;
    std::vector<uint64_t> dropped;
    RayCounters counters = thread_sums(stats, dropped);
    for (uint64_t d : dropped) counters.nonfinite += d;
    m_r.write_state(next_pass, elapsed, last_pass, counters, stats, dropped);
}

void Renderer::MultiviewPasses::finish() {
    std::vector<MvViewStats> per_view;
    std::vector<uint64_t> dropped;
    m_r.m_stats.counters = thread_sums(per_view, dropped);
    for (size_t s = 0; s < m_r.m_views.size(); ++s) {
        Film &mf = m_r.m_films[s];
        per_view[s] += m_r.m_mv_stats_before[s];
        mf.nonfinite += dropped[s];
        m_r.m_stats.counters.nonfinite += dropped[s];
        // Contributions received: those in the film plus those dropped as not finite (counted
        // from the films rather than per splat).
        per_view[s].received += mf.nonfinite;
        for (uint32_t c : mf.received) per_view[s].received += c;
    }
    m_state.clear(); // the threads' caches
    m_pass_film.reset();
    arena().execute([&] {
        m_r.release_held(); // (no second pass came)
        m_r.develop();
    });
    for (size_t s = 0; s < m_r.m_views.size(); ++s) {
        m_r.m_results[s].mv = per_view[s];
        m_r.m_stats.mv += per_view[s];
    }
}

void Renderer::render_multiview(tbb::task_arena &arena, const std::atomic<bool> &cancel, const ProgressFn &progress) {
    MultiviewPasses schedule(*this, arena, cancel);
    if (!m_opts.pilot_only) run_passes(schedule, cancel, progress);
    schedule.finish();
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
    if (m_opts.splits >= 0) cfg.splits = m_opts.splits;
    m_stats.method = "mvpt";
    m_stats.estimator = cfg.estimator == MvEstimator::Balance ? (cfg.mis_selected_only ? "balance-selected" : "balance")
                                                              : (cfg.mis_selected_only ? "weighted-selected" : "weighted");
    m_stats.splits = cfg.splits;
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
    m_mv.scene_moves = mv_scene_moves(m_scene);
    for (int v : m_views) {
        const Camera &cam = *cams[v];
        m_mv.views.push_back(mv_view(cam, uint32_t(v)));
        m_mv.seeds.push_back(m_opts.seed ? *m_opts.seed : cam.seed);
        if (!cam.film.filter->is_box() && cam.film.filter->radius() > float(SplatFootprint::MaxRadius))
            throw std::runtime_error("view '" + cam.id + "': multi-view path tracing splats with filters of radius up to " +
                                     std::to_string(SplatFootprint::MaxRadius) + " pixels");
    }
    m_mv.prepare(); // the sample windows: crop windows grown by the filters' reach
    // The control variate of the balance estimator needs E[sum W] = 1 (§5: D over all valid views).
    const bool use_cv = cfg.estimator == MvEstimator::Balance && cfg.control_variate && !cfg.mis_selected_only;
    std::vector<SplatFootprint> footprints = view_footprints();
    make_films([&](size_t slot) {
        const FilmDesc &f = m_mv.views[slot].camera->film;
        Film film(f.crop_width, f.crop_height, m_mv.windows[slot].margin, cfg.estimator, use_cv, adaptive);
        film.signed_filter = f.filter->has_negative_lobes();
        return film;
    });
    for (const Film &film : m_films) m_mv.native_map.push_back(film.map.data());
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

std::vector<Renderer::Tile> Renderer::multiview_tiles(bool random_regions) const {
    // Tiles by image region, then view: consecutive tiles render the same region of every
    // view, whose native samples splat into overlapping neighbourhoods of the other views, so
    // that a thread's splat cache sums a pixel's contributions before handing them on. Tasks
    // are runs of consecutive tiles, not whole regions: a 48^2 film has 9 regions, and two
    // threads sharing 9 tasks idled 8 % of each light-field pass (CPU use 0.91 -> 0.99).
    // In a random order drawn from the seed, a first pass cut short keeps a uniformly random
    // subset of the regions. (Tiles cover the sample windows, in window coordinates.)
    std::vector<Tile> tiles;
    for (size_t slot = 0; slot < m_views.size(); ++slot) {
        constexpr int TileSize = 16;
        const SampleWindow &w = m_mv.windows[slot];
        for (int y = 0; y < w.height(); y += TileSize)
            for (int x = 0; x < w.width(); x += TileSize)
                tiles.push_back({int(slot), x, y, std::min(x + TileSize, w.width()), std::min(y + TileSize, w.height())});
    }
    const uint64_t seed = hash_ints(m_mv.seeds.empty() ? 0 : m_mv.seeds[0], RegionOrderKey);
    auto key = [&](const Tile &t) {
        return std::make_tuple(random_regions ? hash_ints(seed, uint64_t(t.y0), uint64_t(t.x0)) : 0, t.y0, t.x0);
    };
    std::stable_sort(tiles.begin(), tiles.end(), [&](const Tile &a, const Tile &b) { return key(a) < key(b); });
    return tiles;
}

void Renderer::fold_pass(MvPassFilm &pass_film, double scale, double weight) {
    // Each pixel's pass estimate into the accumulators; a held first pass is added with it.
    film_blocks(m_films, [&](Film &mf, int slot, size_t begin, size_t end) {
        mf.fold(pass_film, pass_film.offset(slot), begin, end, scale, weight);
    });
    for (Film &mf : m_films) mf.short_weight += 1.0 - weight, mf.holding = false;
}

bool Renderer::hold_pass(MvPassFilm &pass_film) {
    if (!m_films.front().control_variate) return false;
    film_blocks(m_films, [&](Film &mf, int slot, size_t begin, size_t end) {
        mf.hold(pass_film, pass_film.offset(slot), begin, end);
    });
    for (Film &mf : m_films) mf.holding = true;
    return true;
}

void Renderer::release_held() {
    film_blocks(m_films, [&](Film &mf, int, size_t begin, size_t end) {
        if (mf.holding) mf.release(begin, end);
    });
    for (Film &mf : m_films) mf.holding = false;
}

void Renderer::update_native_maps(int passes, double per_pixel) {
    // Views in groups of about 2^22 pixels, the views of a group in parallel and each view's
    // map in parallel over its pixels: the temporary arrays of the maps stay within a fixed
    // size however many threads run.
    constexpr size_t GroupPixels = size_t(1) << 22;
    for (size_t first = 0; first < m_views.size();) {
        size_t last = first, group = 0;
        while (last < m_views.size() && (last == first || group + m_films[last].pixels() <= GroupPixels))
            group += m_films[last++].pixels();
        tbb::parallel_for(first, last, [&](size_t slot) {
            const FilmDesc &f = m_mv.views[slot].camera->film;
            Film &mf = m_films[slot];
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

} // namespace mvpt
