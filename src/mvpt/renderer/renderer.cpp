// The renderer of a scene's views: the views and the memory their films need, the method's
// pass loop (pass_loop.cpp) and path tracing's images developed from its per-pixel sums.
#include "renderer.h"
#include "path_passes.h"

#include "../core/memory.h"
#include "../core/sampler.h"
#include "../integrators/multiview/mv_context.h"
#include "../integrators/multiview/mvpath.h"
#include "../render/camera.h"
#include "../render/filter.h"
#include "../render/medium.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace mvpt {

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
    if (m_opts.splits < -1 || m_opts.splits > 64) throw std::invalid_argument("splits must be auto or 1 to 64");
    if (scene.lights().empty()) m_stats.warnings.push_back("the scene has no emitter: every image is black");
    m_multiview = m_opts.method == RenderMethod::MultiView ||
                  (m_opts.method == RenderMethod::Scene && dynamic_cast<const MultiViewPathIntegrator *>(&scene.integrator()));
    // Where no two views can share a path in time (one view; a shot of moving shapes whose
    // shutters do not overlap), multi-view path tracing would pay for shifts and splats that
    // never share: the views are path traced instead (docs/multiview-path-tracing.md, "Where
    // nothing can be shared").
    if (m_multiview) {
        std::vector<MvView> views;
        for (int v : m_views) views.push_back(mv_view(*cams[v], uint32_t(v)));
        if (!views_share_in_time(views, mv_scene_moves(scene))) {
            m_multiview = false;
            m_stats.notes.push_back(views.size() < 2 ? "one view: multi-view path tracing has nothing to share, the view is path traced"
                                                     : "no two views' shutters overlap while shapes or lights move: multi-view path "
                                                       "tracing has nothing to share, the views are path traced");
        }
    }
    // Path tracing splats under a filter other than the box (docs/mitsuba-compatibility.md,
    // "Pixel filters"); a filter too wide to splat is importance-sampled instead.
    if (!m_multiview) {
        bool box = true, fits = true;
        for (int v : m_views) {
            const ReconstructionFilter &f = *cams[v]->film.filter;
            box &= f.is_box();
            fits &= f.is_box() || f.radius() <= float(SplatFootprint::MaxRadius);
        }
        m_splat = !box && fits;
    }
    // Refuse films that cannot fit in memory instead of letting the allocation (or the OOM
    // killer) fail mid-render.
    m_stats.estimated_bytes = estimate_peak_bytes();
    const double resident = resident_bytes();
    const MemoryRoom room = available_memory();
    if (room.bytes > 0.0 && m_stats.estimated_bytes - resident > room.bytes)
        throw std::runtime_error("the films of the " + std::to_string(m_views.size()) + " views need about " +
                                 std::to_string(int64_t((m_stats.estimated_bytes - resident) / (1 << 20))) +
                                 " MiB but " + room.limit + " leaves " + std::to_string(int64_t(room.bytes / (1 << 20))) +
                                 " MiB");
    if (m_multiview) return; // multi-view path tracing makes its films when it prepares (prepare_multiview)
    make_films([&](size_t slot) {
        const FilmDesc &f = cams[m_views[slot]]->film;
        if (!m_splat) return Film(f.crop_width, f.crop_height);
        // Each pass's splats are one estimate, with the balance estimator's control variate.
        Film film(f.crop_width, f.crop_height, SampleWindow(f).margin, MvEstimator::Balance, true, false);
        film.signed_filter = f.filter->has_negative_lobes();
        return film;
    });
}

double Renderer::estimate_peak_bytes() const {
    // Per view-pixel, the largest set of arrays alive at once, plus per thread its buffers, on
    // top of what the process holds now (scene, libraries): the films, or the developed image,
    // variance and sample count; multi-view path tracing adds the pass's fixed-point sums
    // during the passes, and two more AOVs to the images.
    double view_pixels = 0.0;
    for (int v : m_views) view_pixels += double(m_scene.cameras()[v]->film.crop_width) * m_scene.cameras()[v]->film.crop_height;
    // (Each view's film is freed once its images are made, so the images never coexist with
    // all the films; then Python takes the images over without copies, converting the sample
    // counts to floats.)
    const double developed = MinBytesPerRenderedPixel;
    double per_pixel = std::max(double(Film::bytes_per_pixel(false, MvEstimator::Balance, false)), developed);
    double per_thread = 1 << 19;
    if (m_multiview) {
        const MvConfig cfg = multiview_config(m_scene.integrator());
        const bool adaptive = adaptive_maps(cfg);
        const double film = double(Film::bytes_per_pixel(true, cfg.estimator, adaptive));
        per_pixel = std::max(film + double(MvPassFilm::bytes_per_pixel(cfg.estimator == MvEstimator::Weighted)),
                             developed + 2 * sizeof(float));
        // The splat cache, and the queues of a tile's camera samples (up to 16 per pixel) and of
        // a batch of its native samples (MvConfig::batch_entries): 6.3 and 9.6 MiB per thread
        // were measured on the Cornell box and a 9x9 light field at 16 threads (2 and 8 MiB caches).
        per_thread = double(SplatCache::entries_for(m_views.size()) * sizeof(SplatEntry)) + (4 << 20);
    } else if (m_splat) {
        // The films of the balance estimator, and the sums of a group of passes (PathPasses).
        const double film = double(Film::bytes_per_pixel(true, MvEstimator::Balance, false));
        const double group = double(PathPasses::group_passes(uint64_t(view_pixels)));
        per_pixel = std::max(film + group * double(MvPassFilm::bytes_per_pixel(false)), developed);
        per_thread += double(SplatCache::entries_for(size_t(group) * m_views.size()) * sizeof(SplatEntry));
    }
    const int threads = m_opts.threads > 0 ? m_opts.threads : tbb::this_task_arena::max_concurrency();
    return resident_bytes() + view_pixels * per_pixel + threads * per_thread;
}

std::vector<SplatFootprint> Renderer::view_footprints() const {
    std::vector<SplatFootprint> footprints;
    for (int v : m_views) {
        const FilmDesc &f = m_scene.cameras()[v]->film;
        footprints.push_back(SplatFootprint::of(f.crop_x, f.crop_y, f.crop_width, f.crop_height, *f.filter,
                                                Sampler::dimension_key(DimSplatBase + uint32_t(v))));
    }
    return footprints;
}

int Renderer::spp_target() const {
    int spp = 0;
    for (int v : m_views) spp = std::max(spp, m_opts.spp > 0 ? m_opts.spp : m_scene.cameras()[v]->sample_count);
    return spp;
}

void Renderer::make_films(const std::function<Film(size_t)> &make) {
    m_films.clear();
    m_films.resize(m_views.size());
    tbb::task_arena(m_opts.threads > 0 ? m_opts.threads : tbb::task_arena::automatic).execute([&] {
        tbb::parallel_for(size_t(0), m_views.size(), [&](size_t slot) { m_films[slot] = make(slot); });
    });
}

namespace {

/// The free flights the scene's media have given up so far (Medium::flights_given_up).
uint64_t flights_given_up(const Scene &scene) {
    uint64_t n = 0;
    for (const Medium *m : scene.media()) n += m->flights_given_up();
    return n;
}

} // namespace

void Renderer::render(const std::atomic<bool> &cancel, const ProgressFn &progress) {
    m_render_start = std::chrono::steady_clock::now();
    m_stats.threads = m_opts.threads > 0 ? m_opts.threads : tbb::this_task_arena::max_concurrency();
    const uint64_t given_up_before = flights_given_up(m_scene);
    tbb::task_arena arena(m_stats.threads);
    if (m_multiview) {
        render_multiview(arena, cancel, progress);
    } else {
        if (!m_opts.resume_path.empty()) read_state(m_opts.resume_path);
        PathPasses schedule(*this, arena);
        if (!m_opts.pilot_only) run_passes(schedule, cancel, progress);
        m_stats.counters = schedule.counters();
        schedule.finish();
        arena.execute([&] {
            release_held(); // (splatting: no second pass came)
            develop();
        });
    }
    // (Counted on the media: a render running at the same time on the same scene adds its own.)
    if (const uint64_t n = flights_given_up(m_scene) - given_up_before)
        m_stats.warnings.push_back("heterogeneous media gave up " + std::to_string(n) +
                                   " free flights or transmittance estimates after 2^22 tentative collisions "
                                   "each (weight 0): the image is darker where they were");
}

void Renderer::develop() {
    // The views in parallel, each view's film freed once its images are made; multi-view path
    // tracing adds its AOVs (contributions received, the sum of W). The images' means are
    // summed here, in parallel, rather than by Python afterwards (0.12 s per 5 million
    // view-pixels, on one core).
    m_results.assign(m_views.size(), ViewResult{});
    tbb::parallel_for(size_t(0), m_views.size(), [&](size_t slot) {
        Film &film = m_films[slot];
        ViewResult r;
        r.id = m_scene.cameras()[m_views[slot]]->id;
        r.width = film.width;
        r.height = film.height;
        const size_t n = film.pixels();
        r.rgb.resize(3 * n);
        r.variance.resize(3 * n);
        r.sample_count.resize(n);
        if (m_multiview) r.weight_sum.resize(n);
        double sum[3] = {0.0, 0.0, 0.0};
        for (size_t p = 0; p < n; ++p) {
            film.develop(p, &r.rgb[3 * p], &r.variance[3 * p]);
            for (int c = 0; c < 3; ++c) sum[c] += r.rgb[3 * p + c];
            r.sample_count[p] = film.samples(p);
            r.samples += r.sample_count[p];
            if (m_multiview) r.weight_sum[p] = film.weight_sum(p);
        }
        for (int c = 0; c < 3; ++c) r.mean[c] = n > 0 ? sum[c] / double(n) : 0.0;
        if (m_multiview) {
            r.contributions.assign(film.received.begin(), film.received.end());
            for (float k : r.contributions) r.contributions_total += k;
        }
        r.nonfinite = film.nonfinite;
        film = Film{};
        m_results[slot] = std::move(r);
    });
}

} // namespace mvpt
