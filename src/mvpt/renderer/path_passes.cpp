// Path tracing's steps of the pass loop (pass_schedule.h): every pixel of every view takes one
// sample per pass, added to its sums or splatted (path_passes.h); a step is a group of passes
// over all tiles, each tile rendered for all of the step's passes by one task.
#include "path_passes.h"

#include "film_blocks.h"

#include "../core/per_thread.h"
#include "../render/camera.h"
#include "../render/camera_samples.h"

#include <algorithm>
#include <atomic>
#include <tuple>

namespace mvpt {

namespace {
/// A render thread's per-tile buffers (render_group), reused across tiles.
struct TileBuffers {
    /// The tile's samples in order: (pixel x, pixel y, pass).
    std::vector<uint32_t> slot_x, slot_y, slot_pass;
    std::vector<Sampler> samplers;
    std::vector<Ray> rays;
    std::vector<Spectrum> radiance;
    CameraSamples camera;
};

/// The longest group of up to `max` passes (a power of two), halved while `too_long(group)`.
template <typename TooLong> int longest_group(int max, TooLong &&too_long) {
    int g = max;
    while (g > 1 && too_long(g)) g /= 2;
    return g;
}
} // namespace

// Steps run passes in chunks: each task renders one tile for all passes of the step, in pass
// order, so every pixel accumulates its samples in the same order as pass by pass (the images
// are identical) while the threads meet about every quarter of a second instead of once per
// pass (on a loaded machine a descheduled thread holds up every pass boundary). Without a time
// budget a step grows to about a quarter of a second. A step is a whole number of pass groups
// (render_group's batches): 16 passes, halved while a group of all views would exceed
// GroupPaths paths (so that the first step, one group, stays short on large films). Under a
// time budget the first step is one pass; then groups are as long as fits in StepSeconds (the
// budget's granularity), and each step is one group or, near the end, the passes that still
// fit in the budget. Without a time budget the groups depend only on the film size and options,
// so the batches do too (under a budget the number of passes depends on timing anyway).
Renderer::PathPasses::PathPasses(Renderer &r, tbb::task_arena &arena)
    : PassSchedule(arena), m_r(r), m_sample0(uint32_t(r.m_opts.first_pass)) {
    if (r.m_splat)
        for (int v : r.m_views) m_windows.emplace_back(r.m_scene.cameras()[v]->film);
    m_tiles = r.make_tiles(r.m_splat ? &m_windows : nullptr);
    // Target samples per view: the option, or each sensor's sampler, or unbounded under a time
    // budget; a range's passes. (Pass q takes sample first_pass + q of every pixel.)
    const RenderOptions &o = r.m_opts;
    for (int v : r.m_views) {
        int t = o.spp > 0 ? o.spp : r.m_scene.cameras()[v]->sample_count;
        if (o.time_budget > 0.0 && o.spp == 0) t = INT32_MAX;
        if (o.pass_count > 0) t = o.pass_count;
        m_target.push_back(t);
        m_max_target = std::max(m_max_target, t);
    }
    uint64_t pixels = 0;
    for (const Film &f : r.m_films) pixels += f.pixels();
    if (o.time_budget == 0.0) m_group = group_passes(pixels);
    m_step_passes = m_group;
    if (!r.m_splat) return;
    // Splatting: the sums of a group of passes (a step is one group), pass j of view slot s at
    // slot j * views + s.
    m_group_max = group_passes(pixels);
    const std::vector<SplatFootprint> views = r.view_footprints();
    std::vector<SplatFootprint> footprints;
    for (int j = 0; j < m_group_max; ++j) footprints.insert(footprints.end(), views.begin(), views.end());
    arena.execute([&] { m_pass_film = std::make_unique<MvPassFilm>(footprints, false); });
    m_caches = std::make_unique<tbb::enumerable_thread_specific<SplatCache>>([this] { return SplatCache(*m_pass_film); });
}

int Renderer::PathPasses::group_passes(uint64_t pixels) {
    return longest_group(MaxStep, [&](int g) { return uint64_t(g) * pixels > GroupPaths; });
}

uint64_t Renderer::PathPasses::crop_pixels(const Tile &t) const {
    if (!m_r.m_splat) return uint64_t(t.x1 - t.x0) * uint64_t(t.y1 - t.y0);
    const Film &f = m_r.m_films[size_t(t.view_slot)];
    const int m = f.margin;
    const int w = std::min(t.x1, f.width + m) - std::max(t.x0, m), h = std::min(t.y1, f.height + m) - std::max(t.y0, m);
    return uint64_t(std::max(w, 0)) * uint64_t(std::max(h, 0));
}

int Renderer::PathPasses::step_end(int pass, double fit, double last_pass) {
    const bool budget = m_r.m_opts.time_budget > 0.0;
    if (pass > m_r.m_first_pass) { // after a step of this run (splatting: a step is one group)
        if (!budget && last_pass > 0.0 && !m_r.m_splat)
            m_step_passes = std::max(m_group, int(std::clamp(StepSeconds / last_pass, 1.0, double(MaxStep))) / m_group * m_group);
        else if (budget && pass == m_r.m_first_pass + 1)
            m_group = longest_group(m_r.m_splat ? m_group_max : MaxStep,
                                    [&](int g) { return double(g) * last_pass > StepSeconds; });
    }
    if (pass > 0 && budget) {
        fit = std::min(fit, double(MaxStep));
        if (!(fit >= 1.0)) return pass;
        m_step_passes = std::min(m_group, int(fit));
    }
    return std::min(m_max_target, pass + m_step_passes);
}

StepTiles Renderer::PathPasses::begin_step(int pass, int end) {
    m_pass = pass, m_end = end;
    m_step.clear();
    m_step_samples = 0;
    StepTiles step;
    for (const Tile &t : m_tiles)
        if (pass < m_target[t.view_slot]) {
            m_step.push_back(&t);
            const uint64_t samples = uint64_t(std::min(end, m_target[t.view_slot]) - pass) * crop_pixels(t);
            m_step_samples += samples;
            step.add(double(samples));
        }
    return step;
}

bool Renderer::PathPasses::can_abandon(double last_pass, double in_step, bool) const {
    if (m_r.m_splat) return true; // (the step is dropped: it lasts a quarter of a second, or one pass)
    // A step of one pass that is expected to last more than half a second, or has: its
    // finished tiles are kept. Steps of several passes are planned to last a quarter of a
    // second and finish, so that every pixel holds whole passes.
    return m_end - m_pass == 1 && (last_pass > 2.0 * StepSeconds || in_step > 2.0 * StepSeconds);
}

double Renderer::PathPasses::fraction(uint64_t samples) const {
    const double in_step = double(samples) / double(std::max<uint64_t>(m_step_samples, 1));
    return std::min(1.0, (m_pass + in_step * (m_end - m_pass)) / double(m_max_target));
}

RayCounters Renderer::PathPasses::counters() const {
    RayCounters sum = m_r.m_stats.counters;
    for (const RayCounters &c : m_counters) sum += c;
    return sum;
}

uint64_t Renderer::PathPasses::render(size_t t) {
    // The passes of the step that the tile's pixels do not hold yet: a render stopped between
    // tiles keeps the tiles it finished (their pixels have more samples), and a render resumed
    // from its state renders only the others' passes. (Splatting keeps whole steps only.)
    const Tile &tile = *m_step[t];
    const Film &film = m_r.m_films[tile.view_slot];
    const int held = m_r.m_splat ? 0 : int(film.count[size_t(tile.y0) * size_t(film.width) + size_t(tile.x0)]);
    const int end = std::min(m_end, m_target[tile.view_slot]);
    RayCounters &rc = m_counters.local();
    uint64_t samples = 0;
    for (int g = std::max(m_pass, held); g < end; g += m_group) {
        render_group(tile, g, std::min(g + m_group, end), rc);
        samples += uint64_t(std::min(g + m_group, end) - g) * crop_pixels(tile);
    }
    return samples;
}

uint64_t Renderer::PathPasses::kept(const ChunksDone &done) const {
    return m_r.m_splat && !done.finished ? 0 : done.samples;
}

bool Renderer::PathPasses::abandon(const ChunksDone &) {
    if (m_r.m_splat)
        for (SplatCache &c : *m_caches) c.discard();
    return false;
}

void Renderer::PathPasses::end_step() {
    if (!m_r.m_splat) return;
    const size_t views = m_r.m_views.size();
    std::vector<int> passes(views); // each view's passes in the step
    for (size_t s = 0; s < views; ++s) passes[s] = std::max(0, std::min(m_end, m_target[s]) - m_pass);
    std::vector<uint8_t> hold(views);
    arena().execute([&] {
        // What the caches still hold goes to the sums (exact integer sums).
        tbb::parallel_for(m_caches->range(1), [](auto &r) {
            for (SplatCache &c : r) c.flush();
        });
        // Pass by pass, each pixel's sums one estimate; a film's first pass is held for the
        // second's fold, each the other's control variate (film.h).
        for (int j = 0; j < m_end - m_pass; ++j) {
            for (size_t s = 0; s < views; ++s) {
                const Film &f = m_r.m_films[s];
                hold[s] = j < passes[s] && !f.holding && !f.count.empty() && f.count[0] == 0;
            }
            film_blocks(m_r.m_films, [&](Film &f, int s, size_t begin, size_t end) {
                if (j >= passes[size_t(s)]) return;
                const uint32_t offset = m_pass_film->offset(j * int(views) + s);
                if (hold[size_t(s)]) f.hold(*m_pass_film, offset, begin, end);
                else f.fold(*m_pass_film, offset, begin, end);
            });
            for (size_t s = 0; s < views; ++s)
                if (j < passes[s]) m_r.m_films[s].holding = hold[s] != 0;
        }
    });
}

void Renderer::PathPasses::finish() {
    m_caches.reset();
    m_pass_film.reset();
}

/// The samples of passes [pass0, pass1) of a tile in order: one pass, the tile's pixels row by
/// row; several, pixel by pixel in 4x4 blocks, each pixel's passes in a row, so that a 16-wide
/// Embree packet holds one pixel's samples (its camera rays nearly coincide, its bounce and
/// shadow rays leave from nearly one point: matpreview -16 % time). Every pixel still sums its
/// samples in pass order, so the images are those of pass-by-pass rendering.
/// (ox, oy): the tile's origin in full-film pixels (a margin's negative ones stored as uint32).
static void order_samples(int ox, int oy, int x0, int y0, int x1, int y1, uint32_t pass0, uint32_t pass1,
                          std::vector<uint32_t> &sx, std::vector<uint32_t> &sy, std::vector<uint32_t> &sq) {
    sx.clear(), sy.clear(), sq.clear();
    auto add = [&](int x, int y, uint32_t q) {
        sx.push_back(uint32_t(x + ox));
        sy.push_back(uint32_t(y + oy));
        sq.push_back(q);
    };
    if (pass1 - pass0 == 1) {
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) add(x, y, pass0);
        return;
    }
    constexpr int Block = 4;
    for (int by = y0; by < y1; by += Block)
        for (int bx = x0; bx < x1; bx += Block)
            for (int y = by; y < std::min(by + Block, y1); ++y)
                for (int x = bx; x < std::min(bx + Block, x1); ++x)
                    for (uint32_t q = pass0; q < pass1; ++q) add(x, y, q);
}

void Renderer::PathPasses::render_group(const Tile &tile, int pass0, int pass1, RayCounters &rc) {
    const int view = m_r.m_views[tile.view_slot];
    const Camera &cam = *m_r.m_scene.cameras()[view];
    const uint32_t seed = uint32_t(m_r.m_opts.seed ? *m_r.m_opts.seed : cam.seed); // as Sampler keeps it
    TileBuffers &tb = per_thread<TileBuffers>();
    const bool splat = m_r.m_splat;
    const int ox = splat ? m_windows[size_t(tile.view_slot)].x0 : cam.film.crop_x;
    const int oy = splat ? m_windows[size_t(tile.view_slot)].y0 : cam.film.crop_y;
    order_samples(ox, oy, tile.x0, tile.y0, tile.x1, tile.y1, m_sample0 + uint32_t(pass0), m_sample0 + uint32_t(pass1),
                  tb.slot_x, tb.slot_y, tb.slot_pass);
    // 1024 rather than 256: fuller packets and kernel chunks at the deep, sparse bounces (cbox -2.6 %).
    constexpr size_t BatchPaths = 1024;
    for (size_t b0 = 0; b0 < tb.slot_x.size(); b0 += BatchPaths) {
        const size_t n = std::min(BatchPaths, tb.slot_x.size() - b0);
        const uint32_t *sx = tb.slot_x.data() + b0, *sy = tb.slot_y.data() + b0, *sq = tb.slot_pass.data() + b0;
        tb.samplers.assign(n, Sampler(cam.sampler_kind, seed));
        tb.rays.resize(n);
        tb.radiance.resize(n);
        CameraSamples &cs = tb.camera;
        cs.draw(cam, seed, uint32_t(view), sx, sy, sq, n, splat ? FilmSampling::Box : FilmSampling::Filter, false);
        for (size_t i = 0; i < n; ++i) cs.start(tb.samplers[i], i, uint32_t(view), sx[i], sy[i], sq[i], DimCameraEnd);
        cam.generate_rays(cs.film.data(), cs.lens.data(), cs.time.data(), n, tb.rays.data());
        rc.camera_rays += n;
        m_r.m_scene.integrator().li_batch(m_r.m_scene, tb.rays.data(), tb.samplers.data(), tb.radiance.data(), n, rc,
                                          cam.medium.get());
        if (splat) {
            splat_batch(tile.view_slot, tb.radiance.data(), cs.film.data(), tb.samplers.data(), sx, sy, sq, n, rc);
            continue;
        }
        Film &f = m_r.m_films[tile.view_slot];
        const uint32_t x0 = uint32_t(cam.film.crop_x), y0 = uint32_t(cam.film.crop_y);
        for (size_t i = 0; i < n; ++i) {
            Spectrum L = tb.radiance[i];
            if (!L.is_finite()) [[unlikely]] {
                // Never reaches the film: counted, and the first one kept for replay.
                drop_nonfinite(f, view, int(sx[i]), int(sy[i]), int(sq[i]), rc);
                L = Spectrum(0.f);
            }
            L *= cs.weight[i]; // (1 but for filters with negative lobes)
            const double v[3] = {L[0], L[1], L[2]};
            f.add(size_t(sy[i] - y0) * size_t(f.width) + size_t(sx[i] - x0), v);
        }
    }
}

void Renderer::PathPasses::splat_batch(int slot, const Spectrum *radiance, const Vec2f *film, const Sampler *samplers,
                                       const uint32_t *sx, const uint32_t *sy, const uint32_t *sq, size_t n,
                                       RayCounters &rc) {
    SplatCache &cache = m_caches->local();
    Film &f = m_r.m_films[size_t(slot)];
    const FilmDesc &fd = m_r.m_scene.cameras()[m_r.m_views[size_t(slot)]]->film;
    const int views = int(m_r.m_views.size()), view = m_r.m_views[size_t(slot)];
    for (size_t i = 0; i < n; ++i) {
        // Pass j of the step splats into its own sums; a box's window is the crop window.
        const int to = int(sq[i] - m_sample0 - uint32_t(m_pass)) * views + slot;
        const uint32_t pixel =
            cache.is_box(to) ? (sy[i] - uint32_t(fd.crop_y)) * uint32_t(f.width) + (sx[i] - uint32_t(fd.crop_x)) : 0;
        const uint64_t hash = samplers[i].sample_hash();
        const Spectrum &L = radiance[i];
        if (!L.is_finite() || !cache.add(to, pixel, film[i], hash, L, 1.f)) [[unlikely]] {
            // Never reaches the film: counted, the first one kept for replay, and zero splatted.
            drop_nonfinite(f, view, int(sx[i]), int(sy[i]), int(sq[i]), rc);
            cache.add(to, pixel, film[i], hash, Spectrum(0.f), 1.f);
        }
    }
}

void Renderer::PathPasses::drop_nonfinite(Film &film, int view, int px, int py, int pass, RayCounters &rc) {
    ++rc.nonfinite;
    std::atomic_ref<uint64_t>(film.nonfinite).fetch_add(1, std::memory_order_relaxed);
    RenderStats &st = m_r.m_stats;
    std::lock_guard<std::mutex> lock(m_nonfinite_mutex);
    const auto key = std::make_tuple(int64_t(pass), int64_t(view), int64_t(py), int64_t(px));
    if (st.nonfinite_view < 0 ||
        key < std::make_tuple(st.nonfinite_sample, st.nonfinite_view, st.nonfinite_y, st.nonfinite_x))
        std::tie(st.nonfinite_sample, st.nonfinite_view, st.nonfinite_y, st.nonfinite_x) = key;
}

std::vector<Renderer::Tile> Renderer::make_tiles(const std::vector<SampleWindow> *windows) const {
    constexpr int TileSize = 16;
    std::vector<Tile> tiles;
    for (size_t i = 0; i < m_views.size(); ++i) {
        const FilmDesc &f = m_scene.cameras()[m_views[i]]->film;
        const int width = windows ? (*windows)[i].width() : f.crop_width;
        const int height = windows ? (*windows)[i].height() : f.crop_height;
        for (int y = 0; y < height; y += TileSize)
            for (int x = 0; x < width; x += TileSize)
                tiles.push_back({int(i), x, y, std::min(x + TileSize, width), std::min(y + TileSize, height)});
    }
    return tiles;
}

} // namespace mvpt
