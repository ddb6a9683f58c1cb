// The renderer's state file (render_state.h, docs/checkpoints.md): what a render has done at a
// pass boundary, to be resumed with the same images as a render that was never stopped.
#include "renderer.h"

#include "../render/camera.h"
#include "render_state.h"

#include <tbb/task_arena.h>

#include <array>

namespace mvpt {

namespace {
/// The kinds of accumulators a state holds, as its layout names them.
enum class FilmKind : uint32_t { PathTracing = 0, MultiView = 1, PathTracingSplats = 2 };
const char *film_kind_name(uint32_t kind) {
    switch (kind) {
    case uint32_t(FilmKind::PathTracing): return "path tracing";
    case uint32_t(FilmKind::MultiView): return "multi-view path tracing";
    case uint32_t(FilmKind::PathTracingSplats): return "path tracing with a splatted pixel filter";
    default: return "an unknown method";
    }
}

/// What identifies the layout of a render's accumulators: the method and every view's crop window.
void put_layout(StateWriter &out, FilmKind kind, const std::vector<int> &views, const Scene &scene) {
    out.put(uint32_t(kind));
    out.put(uint64_t(views.size()));
    for (int v : views) {
        const FilmDesc &f = scene.cameras()[v]->film;
        out.put(int32_t(v)), out.put(int32_t(f.crop_width)), out.put(int32_t(f.crop_height));
    }
}

void check_layout(StateReader &in, FilmKind kind, const std::vector<int> &views, const Scene &scene) {
    const uint32_t theirs = in.get<uint32_t>();
    if (theirs != uint32_t(kind))
        throw StateError(std::string("the state was rendered with ") + film_kind_name(theirs) + ", this render uses " +
                         film_kind_name(uint32_t(kind)));
    if (in.get<uint64_t>() != views.size()) throw StateError("the state has another number of views");
    for (int v : views) {
        const FilmDesc &f = scene.cameras()[v]->film;
        const int32_t index = in.get<int32_t>(), w = in.get<int32_t>(), h = in.get<int32_t>();
        if (index != v || w != f.crop_width || h != f.crop_height)
            throw StateError("the state's view " + std::to_string(index) + " is " + std::to_string(w) + "x" +
                             std::to_string(h) + " pixels; this render's view " + std::to_string(v) + " ('" +
                             scene.cameras()[v]->id + "') is " + std::to_string(f.crop_width) + "x" +
                             std::to_string(f.crop_height));
    }
}

FilmKind film_kind(bool multiview, bool splat) {
    return multiview ? FilmKind::MultiView : splat ? FilmKind::PathTracingSplats : FilmKind::PathTracing;
}

} // namespace

void Renderer::write_state(int next_pass, double elapsed, double last_pass, const RayCounters &counters,
                           const std::vector<MvViewStats> &mv_stats, const std::vector<uint64_t> &mv_dropped) const {
    StateWriter out(m_opts.state_path, m_opts.state_header);
    put_layout(out, film_kind(m_multiview, m_splat), m_views, m_scene);
    out.put(int32_t(next_pass)), out.put(elapsed), out.put(last_pass), out.put(m_stats.samples), out.put(counters);
    out.put(SampleKey{m_stats.nonfinite_sample, m_stats.nonfinite_view, m_stats.nonfinite_y, m_stats.nonfinite_x});
    if (m_multiview) out.put(m_native_done), out.put(int32_t(m_stats.splits)); // (the splits chosen, for a merge's statistics)
    for (size_t s = 0; s < m_views.size(); ++s) {
        if (m_multiview) {
            MvViewStats stats = m_mv_stats_before[s];
            if (s < mv_stats.size()) stats += mv_stats[s];
            out.put(stats);
            out.put(uint64_t(s < mv_dropped.size() ? mv_dropped[s] : 0));
        }
        m_films[s].save(out);
    }
    out.commit();
}

void Renderer::read_state(const std::string &path) {
    StateReader in(path);
    check_layout(in, film_kind(m_multiview, m_splat), m_views, m_scene);
    m_first_pass = in.get<int32_t>();
    m_elapsed_before = in.get<double>();
    m_last_pass_before = in.get<double>();
    m_stats.samples = in.get<uint64_t>();
    m_stats.counters = in.get<RayCounters>();
    const auto nf = in.get<SampleKey>();
    m_stats.nonfinite_sample = nf[0], m_stats.nonfinite_view = nf[1], m_stats.nonfinite_y = nf[2], m_stats.nonfinite_x = nf[3];
    if (m_first_pass < 0 || !(m_elapsed_before >= 0.0) || !(m_last_pass_before >= 0.0))
        throw StateError("the state file '" + path + "' is corrupt");
    m_stats.passes = m_stats.first_pass = m_first_pass;
    if (m_multiview) m_native_done = in.get<double>(), m_stats.splits = in.get<int32_t>();
    for (size_t s = 0; s < m_views.size(); ++s) {
        uint64_t dropped = 0;
        if (m_multiview) m_mv_stats_before[s] = in.get<MvViewStats>(), dropped = in.get<uint64_t>();
        m_films[s].load(in);
        m_films[s].check_loaded(m_first_pass, m_multiview ? m_mv.cfg.adaptive_max : 1); // (path tracing's splats: 1 a pass)
        m_films[s].nonfinite += dropped;
        if (m_multiview) m_mv.native_map[s] = m_films[s].map.data();
    }
    in.finish();
}

void Renderer::add_state(const Renderer &o) {
    m_stats.passes += o.m_stats.passes;
    m_first_pass += o.m_first_pass;
    m_elapsed_before += o.m_elapsed_before;
    m_stats.samples += o.m_stats.samples;
    m_stats.counters += o.m_stats.counters;
    SampleKey first{m_stats.nonfinite_sample, m_stats.nonfinite_view, m_stats.nonfinite_y, m_stats.nonfinite_x};
    keep_first(first, {o.m_stats.nonfinite_sample, o.m_stats.nonfinite_view, o.m_stats.nonfinite_y, o.m_stats.nonfinite_x});
    m_stats.nonfinite_sample = first[0], m_stats.nonfinite_view = first[1], m_stats.nonfinite_y = first[2];
    m_stats.nonfinite_x = first[3];
    m_native_done += o.m_native_done;
    for (size_t s = 0; s < m_films.size(); ++s) {
        m_films[s].merge(o.m_films[s]);
        if (m_multiview) m_mv_stats_before[s] += o.m_mv_stats_before[s];
    }
}

void Renderer::merge(const std::vector<std::string> &paths, bool develop_images) {
    if (paths.empty()) throw std::invalid_argument("nothing to merge");
    MvConfig cfg;
    for (size_t i = 0; i < paths.size(); ++i) {
        if (i == 0) {
            if (m_multiview) prepare_multiview_render(cfg);
            read_state(paths[0]);
            release_held(); // (a state's first pass held: folded without its control variate)
            continue;
        }
        Renderer other(m_scene, m_opts);
        if (m_multiview) other.prepare_multiview_render(cfg);
        other.read_state(paths[i]);
        other.release_held();
        add_state(other);
    }
    m_stats.seconds = m_elapsed_before;
    m_stats.first_pass = 0;
    m_stats.threads = m_opts.threads > 0 ? m_opts.threads : tbb::this_task_arena::max_concurrency();
    if (!m_opts.state_path.empty())
        write_state(m_first_pass, m_elapsed_before, m_last_pass_before, m_stats.counters, {}, {});
    if (!develop_images) return;
    if (!m_multiview) {
        develop();
        return;
    }
    for (size_t s = 0; s < m_views.size(); ++s) { // contributions received, as MultiviewPasses::finish counts them
        m_mv_stats_before[s].received += m_films[s].nonfinite;
        for (uint32_t r : m_films[s].received) m_mv_stats_before[s].received += r;
    }
    develop();
    for (size_t s = 0; s < m_views.size(); ++s) {
        m_results[s].mv = m_mv_stats_before[s];
        m_stats.mv += m_mv_stats_before[s];
    }
}

bool Renderer::checkpoint_due(double elapsed, double &last) const {
    if (m_opts.state_path.empty() || m_opts.checkpoint_interval <= 0.0 || elapsed - last < m_opts.checkpoint_interval)
        return false;
    last = elapsed;
    return true;
}

} // namespace mvpt
