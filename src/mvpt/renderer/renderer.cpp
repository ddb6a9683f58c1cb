#include "renderer.h"
#include "chunks.h"

#include "../core/memory.h"
#include "../core/per_thread.h"

#include "../integrators/mvpath.h"
#include "../render/camera.h"
#include "../render/camera_samples.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <tuple>
#include <vector>
#include <unistd.h>

namespace mvpt {

namespace {
/// A render thread's per-tile buffers (render_tile), reused across tiles.
struct TileBuffers {
    /// The tile's samples in order: (pixel x, pixel y, pass).
    std::vector<uint32_t> slot_x, slot_y, slot_pass;
    std::vector<Sampler> samplers;
    std::vector<Ray> rays;
    std::vector<Spectrum> radiance;
    CameraSamples camera;
};
} // namespace

Renderer::Renderer(const Scene &scene, RenderOptions opts) : m_scene(scene), m_opts(std::move(opts)) {
    const auto &cams = scene.cameras();
    if (m_opts.views.empty())
        for (int i = 0; i < int(cams.size()); ++i) m_views.push_back(i);
    else
        m_views = m_opts.views;
    for (int v : m_views)
        if (v < 0 || v >= int(cams.size()))
            throw std::invalid_argument("view index " + std::to_string(v) + " out of range (the scene has " +
                                        std::to_string(cams.size()) + " views)");
    if (m_opts.spp < 0) throw std::invalid_argument("spp must be >= 0");
    if (m_opts.first_pass < 0 || m_opts.pass_count < 0 || m_opts.first_pass > INT32_MAX - m_opts.pass_count)
        throw std::invalid_argument("the pass range must lie in [0, 2^31)");
    if (!(m_opts.time_budget >= 0.0)) throw std::invalid_argument("time budget must be >= 0");
    if (scene.lights().empty()) m_stats.warnings.push_back("the scene has no emitter: every image is black");
    m_multiview = m_opts.method == RenderMethod::MultiView ||
                  (m_opts.method == RenderMethod::Scene && dynamic_cast<const MultiViewPathIntegrator *>(&scene.integrator()));
    // Refuse films that cannot fit in memory instead of letting the allocation (or the OOM
    // killer) fail mid-render.
    m_stats.estimated_bytes = estimate_peak_bytes();
    const double resident = resident_bytes(), available = available_bytes();
    if (available > 0.0 && m_stats.estimated_bytes - resident > available)
        throw std::runtime_error("the films of the " + std::to_string(m_views.size()) + " views need about " +
                                 std::to_string(int64_t((m_stats.estimated_bytes - resident) / (1 << 20))) +
                                 " MiB but the machine has " + std::to_string(int64_t(available / (1 << 20))) +
                                 " MiB of memory available");
    if (m_multiview) return; // multi-view path tracing keeps its own accumulators (MvFilm)
    m_films.resize(m_views.size());
    for (size_t i = 0; i < m_views.size(); ++i) {
        const FilmDesc &f = cams[m_views[i]]->film;
        size_t n = size_t(f.crop_width) * f.crop_height;
        m_films[i].sum.assign(3 * n, 0.0);
        m_films[i].sum_sq.assign(3 * n, 0.0);
        m_films[i].count.assign(n, 0);
    }
}

double Renderer::estimate_peak_bytes() const {
    // Per view-pixel, the largest set of arrays alive at once, plus per thread its buffers, on
    // top of what the process holds now (scene, libraries). Path tracing: the sums (2 x 3
    // doubles) and count, or the developed image, variance and sample count. Multi-view path
    // tracing: the pass's fixed-point sums and the accumulators during the passes, or the
    // developed images with two more AOVs.
    double view_pixels = 0.0;
    for (int v : m_views) view_pixels += double(m_scene.cameras()[v]->film.crop_width) * m_scene.cameras()[v]->film.crop_height;
    // (Views are developed one by one, each freeing its sums, so the images never coexist with
    // all the sums; then Python takes the images over without copies, converting the sample
    // counts to floats.)
    const double developed = 6 * sizeof(float) + sizeof(uint32_t) + sizeof(float);
    double per_pixel = std::max(double(6 * sizeof(double) + sizeof(uint32_t)), developed), per_thread = 1 << 19;
    if (m_multiview) {
        const MvConfig cfg = multiview_config(m_scene.integrator());
        const bool adaptive = adaptive_maps(cfg);
        const double film = double(MvFilm::bytes_per_pixel(cfg.estimator, adaptive));
        per_pixel = std::max(film + double(MvPassFilm::bytes_per_pixel(cfg.estimator == MvEstimator::Weighted)),
                             developed + 2 * sizeof(float));
        // The splat cache, and the queues of a tile's native samples (up to 16 per pixel).
        per_thread = double(SplatCache::entries_for(m_views.size()) * sizeof(SplatEntry)) + (6 << 20);
    }
    const int threads = m_opts.threads > 0 ? m_opts.threads : tbb::this_task_arena::max_concurrency();
    return resident_bytes() + view_pixels * per_pixel + threads * per_thread;
}

int Renderer::spp_target() const {
    int spp = 0;
    for (int v : m_views) spp = std::max(spp, m_opts.spp > 0 ? m_opts.spp : m_scene.cameras()[v]->sample_count);
    return spp;
}

void Renderer::render(const std::atomic<bool> &cancel, const std::function<void(const RenderProgress &)> &progress) {
    if (m_multiview) {
        render_multiview(cancel, progress);
        return;
    }
    using clock = std::chrono::steady_clock;
    const auto &cams = m_scene.cameras();
    const Integrator &integrator = m_scene.integrator();
    int threads = m_opts.threads > 0 ? m_opts.threads : tbb::this_task_arena::max_concurrency();
    m_stats.threads = threads;
    tbb::task_arena arena(threads);

    // Target samples per view: the option, or each sensor's sampler, or unbounded under a time
    // budget; a range's passes. (Pass q takes sample first_pass + q of every pixel.)
    std::vector<int> target(m_views.size());
    int max_target = 0;
    for (size_t i = 0; i < m_views.size(); ++i) {
        int t = m_opts.spp > 0 ? m_opts.spp : cams[m_views[i]]->sample_count;
        if (m_opts.time_budget > 0.0 && m_opts.spp == 0) t = INT32_MAX;
        if (m_opts.pass_count > 0) t = m_opts.pass_count;
        target[i] = t;
        max_target = std::max(max_target, t);
    }

    const std::vector<Tile> all_tiles = make_tiles();

    tbb::enumerable_thread_specific<RayCounters> counters;
    std::mutex nonfinite_mutex;
    if (!m_opts.resume_path.empty()) read_state(m_opts.resume_path);
    const uint32_t sample0 = uint32_t(m_opts.first_pass);
    // A resumed render's clock goes on from the seconds of the runs before (for --time).
    const auto t_start = clock::now() - std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(m_elapsed_before));
    auto seconds = [&] { return std::chrono::duration<double>(clock::now() - t_start).count(); };
    auto counters_now = [&] {
        RayCounters sum = m_stats.counters;
        for (const RayCounters &c : counters) sum += c;
        return sum;
    };
    double last_pass = m_last_pass_before, last_checkpoint = m_elapsed_before;

    // The samples of a pass group [pass0, pass1) of a tile, as batches of up to BatchPaths
    // paths. One pass: the tile's pixels row by row. Several: pixel by pixel in 4x4 blocks,
    // each pixel's passes in a row, so that a 16-wide Embree packet holds one pixel's samples
    // (its camera rays nearly coincide, its bounce and shadow rays leave from nearly one point:
    // matpreview -16 % time). Every pixel still sums its samples in pass order, so the images
    // are those of pass-by-pass rendering; and without a time budget the groups depend only on
    // the film size and options (below), so the batches do too (under a budget the number of
    // passes depends on timing anyway).
    auto render_tile = [&](const Tile &tile, int pass0, int pass1, RayCounters &rc) {
        int view = m_views[tile.view_slot];
        const Camera &cam = *cams[view];
        const FilmDesc &film = cam.film;
        FilmBuffer &fb = m_films[tile.view_slot];
        const uint32_t seed = uint32_t(m_opts.seed ? *m_opts.seed : cam.seed); // as Sampler keeps it
        TileBuffers &tb = per_thread<TileBuffers>();
        std::vector<uint32_t> &slot_x = tb.slot_x, &slot_y = tb.slot_y, &slot_pass = tb.slot_pass;
        slot_x.clear(), slot_y.clear(), slot_pass.clear();
        auto add = [&](int x, int y, int q) {
            slot_x.push_back(uint32_t(x + film.crop_x));
            slot_y.push_back(uint32_t(y + film.crop_y));
            slot_pass.push_back(uint32_t(q));
        };
        if (pass1 - pass0 == 1) {
            for (int y = tile.y0; y < tile.y1; ++y)
                for (int x = tile.x0; x < tile.x1; ++x) add(x, y, sample0 + pass0);
        } else {
            constexpr int Block = 4;
            for (int by = tile.y0; by < tile.y1; by += Block)
                for (int bx = tile.x0; bx < tile.x1; bx += Block)
                    for (int y = by; y < std::min(by + Block, tile.y1); ++y)
                        for (int x = bx; x < std::min(bx + Block, tile.x1); ++x)
                            for (int q = pass0; q < pass1; ++q) add(x, y, sample0 + q);
        }
        std::vector<Sampler> &samplers = tb.samplers;
        std::vector<Ray> &rays = tb.rays;
        std::vector<Spectrum> &radiance = tb.radiance;
        CameraSamples &cs = tb.camera;
        // 1024 rather than 256: fuller packets and kernel chunks at the deep, sparse bounces (cbox -2.6 %).
        constexpr size_t BatchPaths = 1024;
        for (size_t b0 = 0; b0 < slot_x.size(); b0 += BatchPaths) {
            const size_t n = std::min(BatchPaths, slot_x.size() - b0);
            const uint32_t *sx = slot_x.data() + b0, *sy = slot_y.data() + b0, *sq = slot_pass.data() + b0;
            samplers.assign(n, Sampler(cam.sampler_kind, seed));
            rays.resize(n);
            radiance.resize(n);
            cs.draw(cam, seed, uint32_t(view), sx, sy, sq, n, FilmSampling::Filter, false);
            for (size_t i = 0; i < n; ++i) cs.start(samplers[i], i, uint32_t(view), sx[i], sy[i], sq[i], DimCameraEnd);
            cam.generate_rays(cs.film.data(), cs.lens.data(), cs.time.data(), n, rays.data());
            rc.camera_rays += n;
            integrator.li_batch(m_scene, rays.data(), samplers.data(), radiance.data(), n, rc, cam.medium.get());
            for (size_t i = 0; i < n; ++i) {
                const int px = int(sx[i]), py = int(sy[i]), pass = int(sq[i]);
                Spectrum L = radiance[i];
                size_t pi = size_t(py - film.crop_y) * film.crop_width + size_t(px - film.crop_x);
                if (!L.is_finite()) {
                    // Never reaches the film: counted, and the first one kept for replay.
                    ++rc.nonfinite;
                    ++*fb.nonfinite;
                    std::lock_guard<std::mutex> lock(nonfinite_mutex);
                    auto key = std::make_tuple(int64_t(pass), int64_t(view), int64_t(py), int64_t(px));
                    if (m_stats.nonfinite_view < 0 ||
                        key < std::make_tuple(m_stats.nonfinite_sample, m_stats.nonfinite_view,
                                              m_stats.nonfinite_y, m_stats.nonfinite_x)) {
                        m_stats.nonfinite_view = view; m_stats.nonfinite_x = px;
                        m_stats.nonfinite_y = py; m_stats.nonfinite_sample = pass;
                    }
                    L = Spectrum(0.f);
                }
                for (int c = 0; c < 3; ++c) {
                    fb.sum[3 * pi + c] += L[c];
                    fb.sum_sq[3 * pi + c] += double(L[c]) * L[c];
                }
                ++fb.count[pi];
            }
        }
    };

    // Passes run in chunks: each task renders one tile for all passes of the chunk, in pass
    // order, so every pixel accumulates its samples in the same order as pass by pass (the
    // images are identical) while the threads meet about every quarter of a second
    // (run_in_chunks) instead of once per pass (on a loaded machine a descheduled thread holds
    // up every pass boundary). Without a time budget a chunk grows to about a quarter of a
    // second. A chunk is a whole number of pass groups (render_tile's batches): 16 passes, halved
    // while a group of all views would exceed GroupPaths paths (so that the first chunk, one
    // group, stays short on large films). Under a time budget the first chunk is one pass;
    // then groups are as long as fits in ChunkSeconds (the budget's granularity), and each
    // chunk is one group or, near the end, the passes that still fit in the budget.
    constexpr double ChunkSeconds = 0.25;
    constexpr int MaxChunk = 16;
    constexpr uint64_t GroupPaths = uint64_t(1) << 20;
    // The longest group of up to MaxChunk passes, halved while `too_long(group)`.
    auto longest_group = [](auto &&too_long) {
        int g = MaxChunk;
        while (g > 1 && too_long(g)) g /= 2;
        return g;
    };
    int group = 1;
    if (m_opts.time_budget == 0.0) {
        uint64_t pixels = 0;
        for (const Tile &t : all_tiles) pixels += uint64_t(t.x1 - t.x0) * uint64_t(t.y1 - t.y0);
        group = longest_group([&](int g) { return uint64_t(g) * pixels > GroupPaths; });
    }
    // Each task renders one tile for its passes of the chunk, the passes that its pixels do not
    // hold yet: a render stopped between tiles keeps the tiles it finished (their pixels have
    // more samples), and a render resumed from its state renders only the others' passes.
    auto render_passes = [&](const Tile &tile, int pass0, int pass1) -> uint64_t {
        const FilmBuffer &fb = m_films[tile.view_slot];
        const int width = cams[m_views[tile.view_slot]]->film.crop_width;
        const int held = int(fb.count[size_t(tile.y0) * size_t(width) + size_t(tile.x0)]);
        const int end = std::min(pass1, target[tile.view_slot]);
        RayCounters &rc = counters.local();
        uint64_t samples = 0;
        for (int g = std::max(pass0, held); g < end; g += group) {
            render_tile(tile, g, std::min(g + group, end), rc);
            samples += uint64_t(std::min(g + group, end) - g) * uint64_t(tile.x1 - tile.x0) * uint64_t(tile.y1 - tile.y0);
        }
        return samples;
    };
    ChunkTiming chunk_timing;
    int chunk = group, pass = m_first_pass;
    while (pass < max_target) {
        if (cancel.load()) { m_stats.cancelled = true; break; }
        double elapsed = seconds();
        if (pass > 0 && m_opts.time_budget > 0.0) {
            // Passes that still fit (checked as a double: the quotient may be infinite or NaN).
            const double fit = std::min((m_opts.time_budget - elapsed) / last_pass, double(MaxChunk));
            if (!(fit >= 1.0)) break;
            chunk = std::min(group, int(fit));
        }
        const int pass_end = std::min(max_target, pass + chunk);
        auto t_chunk = clock::now();

        std::vector<const Tile *> tiles;
        uint64_t chunk_samples = 0;
        for (const Tile &t : all_tiles)
            if (pass < target[t.view_slot]) {
                tiles.push_back(&t);
                chunk_samples += uint64_t(std::min(pass_end, target[t.view_slot]) - pass) * uint64_t(t.x1 - t.x0) *
                                 uint64_t(t.y1 - t.y0);
            }
        // Cancellation, and the end of the time budget after the first pass, stop between the
        // tiles of a pass that is expected to last more than half a second, or once it has (its
        // finished tiles kept). Chunks of several passes are short (they are planned to last a
        // quarter of a second) and finish, so that every pixel holds whole passes.
        const double chunk_start = seconds();
        const bool long_pass = pass_end - pass == 1 && last_pass > 2.0 * ChunkSeconds;
        auto stop = [&] {
            const bool asked = cancel.load() || (pass > 0 && m_opts.time_budget > 0.0 && seconds() > m_opts.time_budget);
            return asked && pass_end - pass == 1 && (long_pass || seconds() - chunk_start > 2.0 * ChunkSeconds);
        };
        auto report = [&](uint64_t samples_done) {
            const double in_chunk = double(samples_done) / double(std::max<uint64_t>(chunk_samples, 1));
            report_progress(progress, pass, seconds(), m_stats.samples + samples_done,
                            std::min(1.0, (pass + in_chunk * (pass_end - pass)) / double(max_target)));
        };
        const ChunksDone done = run_in_chunks(arena, tiles.size(), threads, double(chunk_samples), chunk_timing,
                                              [&](size_t ti) { return render_passes(*tiles[ti], pass, pass_end); },
                                              stop, report);
        m_stats.samples += done.samples;
        if (!done.finished) {
            m_stats.cancelled = cancel.load();
            break;
        }
        last_pass = std::chrono::duration<double>(clock::now() - t_chunk).count() / double(pass_end - pass);
        for (int q = pass; q < pass_end; ++q)
            finish_pass(q, 0, last_pass, seconds(), double(q + 1) / double(max_target), progress);
        pass = pass_end;
        if (checkpoint_due(seconds(), last_checkpoint)) write_state(pass, seconds(), last_pass, counters_now());
        if (m_opts.time_budget == 0.0 && last_pass > 0.0)
            chunk = std::max(group, int(std::clamp(ChunkSeconds / last_pass, 1.0, double(MaxChunk))) / group * group);
        else if (m_opts.time_budget > 0.0 && pass == m_first_pass + 1)
            group = longest_group([&](int g) { return double(g) * last_pass > ChunkSeconds; });
    }
    m_stats.max_chunk_seconds = chunk_timing.longest;
    m_stats.seconds = seconds();
    m_stats.counters = counters_now();
    if (!m_opts.state_path.empty() && (m_stats.cancelled || m_opts.state_at_end))
        write_state(pass, m_stats.seconds, last_pass, m_stats.counters);
    develop();
}

std::vector<Renderer::Tile> Renderer::make_tiles() const {
    constexpr int TileSize = 16;
    std::vector<Tile> tiles;
    for (size_t i = 0; i < m_views.size(); ++i) {
        const FilmDesc &f = m_scene.cameras()[m_views[i]]->film;
        for (int y = 0; y < f.crop_height; y += TileSize)
            for (int x = 0; x < f.crop_width; x += TileSize)
                tiles.push_back({int(i), x, y, std::min(x + TileSize, f.crop_width), std::min(y + TileSize, f.crop_height)});
    }
    return tiles;
}

void Renderer::finish_pass(int pass, uint64_t pass_samples, double pass_seconds, double elapsed, double fraction,
                           const std::function<void(const RenderProgress &)> &progress) {
    m_stats.max_pass_seconds = std::max(m_stats.max_pass_seconds, pass_seconds);
    m_stats.passes = pass + 1;
    m_stats.samples += pass_samples;
    report_progress(progress, pass + 1, elapsed, m_stats.samples, fraction);
}

void Renderer::report_progress(const std::function<void(const RenderProgress &)> &progress, int pass, double elapsed,
                               uint64_t samples, double fraction) const {
    if (!progress) return;
    RenderProgress p;
    p.pass = pass;
    p.elapsed = elapsed;
    p.samples = samples;
    p.fraction = fraction;
    if (m_opts.time_budget > 0.0) p.fraction = std::max(p.fraction, std::min(1.0, p.elapsed / m_opts.time_budget));
    progress(p);
}

void Renderer::develop() {
    // View by view, each view's sums freed once its images are made.
    const auto &cams = m_scene.cameras();
    m_results.clear();
    for (size_t i = 0; i < m_views.size(); ++i) {
        const Camera &cam = *cams[m_views[i]];
        FilmBuffer &fb = m_films[i];
        ViewResult r;
        r.id = cam.id;
        r.width = cam.film.crop_width;
        r.height = cam.film.crop_height;
        size_t n = size_t(r.width) * r.height;
        r.rgb.resize(3 * n);
        r.variance.resize(3 * n);
        r.sample_count = fb.count;
        r.nonfinite = fb.nonfinite->load();
        for (size_t p = 0; p < n; ++p) {
            double k = fb.count[p];
            r.samples += fb.count[p];
            for (int c = 0; c < 3; ++c) {
                double mean = k > 0 ? fb.sum[3 * p + c] / k : 0.0;
                double var = k > 1 ? std::max(0.0, (fb.sum_sq[3 * p + c] - k * mean * mean) / (k * (k - 1))) : 0.0;
                r.rgb[3 * p + c] = float(mean);
                r.variance[3 * p + c] = float(std::min(var, double(FLT_MAX))); // finite even for huge samples
            }
        }
        fb.sum = std::vector<double>(), fb.sum_sq = std::vector<double>(), fb.count = std::vector<uint32_t>();
        m_results.push_back(std::move(r));
    }
}

} // namespace mvpt
