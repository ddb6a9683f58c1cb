// The renderer's state file (render_state.h, docs/checkpoints.md): what a render has done at a
// pass boundary, to be resumed with the same images as a render that was never stopped.
#include "renderer.h"

#include "render/camera.h"
#include "render_state.h"

#include <array>

namespace mvpt {

namespace {
/// What identifies the layout of a render's accumulators: the method and every view's crop window.
void put_layout(StateWriter &out, bool multiview, const std::vector<int> &views, const Scene &scene) {
    out.put(uint32_t(multiview));
    out.put(uint64_t(views.size()));
    for (int v : views) {
        const FilmDesc &f = scene.cameras()[v]->film;
        out.put(int32_t(v)), out.put(int32_t(f.crop_width)), out.put(int32_t(f.crop_height));
    }
}

void check_layout(StateReader &in, bool multiview, const std::vector<int> &views, const Scene &scene) {
    if (in.get<uint32_t>() != uint32_t(multiview))
        throw StateError(std::string("the state was rendered with ") + (multiview ? "path tracing" : "multi-view path tracing"));
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

using NonfiniteKey = std::array<int64_t, 4>;
} // namespace

void Renderer::write_state(int next_pass, double elapsed, double last_pass, const RayCounters &counters,
                           const std::vector<MvViewStats> &mv_stats, const std::vector<uint64_t> &mv_dropped) const {
    StateWriter out(m_opts.state_path, m_opts.state_header);
    put_layout(out, m_multiview, m_views, m_scene);
    out.put(int32_t(next_pass)), out.put(elapsed), out.put(last_pass), out.put(m_stats.samples), out.put(counters);
    out.put(NonfiniteKey{m_stats.nonfinite_sample, m_stats.nonfinite_view, m_stats.nonfinite_y, m_stats.nonfinite_x});
    if (!m_multiview) {
        for (const FilmBuffer &fb : m_films) out.put(fb.sum), out.put(fb.sum_sq), out.put(fb.count), out.put(fb.nonfinite->load());
    } else {
        out.put(m_native_done);
        for (size_t s = 0; s < m_views.size(); ++s) {
            MvViewStats stats = m_mv_stats_before[s];
            if (s < mv_stats.size()) stats += mv_stats[s];
            out.put(stats);
            out.put(uint64_t(s < mv_dropped.size() ? mv_dropped[s] : 0));
            m_mv_films[s].save(out);
        }
    }
    out.commit();
}

void Renderer::read_state() {
    StateReader in(m_opts.resume_path);
    check_layout(in, m_multiview, m_views, m_scene);
    m_first_pass = in.get<int32_t>();
    m_elapsed_before = in.get<double>();
    m_last_pass_before = in.get<double>();
    m_stats.samples = in.get<uint64_t>();
    m_stats.counters = in.get<RayCounters>();
    const auto nf = in.get<NonfiniteKey>();
    m_stats.nonfinite_sample = nf[0], m_stats.nonfinite_view = nf[1], m_stats.nonfinite_y = nf[2], m_stats.nonfinite_x = nf[3];
    if (m_first_pass < 0 || !(m_elapsed_before >= 0.0) || !(m_last_pass_before >= 0.0)) throw StateError("the state file '" + m_opts.resume_path + "' is corrupt");
    m_stats.passes = m_stats.first_pass = m_first_pass;
    if (!m_multiview) {
        for (FilmBuffer &fb : m_films) {
            const size_t n = fb.count.size();
            in.get(fb.sum, 3 * n), in.get(fb.sum_sq, 3 * n), in.get(fb.count, n);
            *fb.nonfinite = in.get<uint64_t>();
        }
    } else {
        m_native_done = in.get<double>();
        for (size_t s = 0; s < m_views.size(); ++s) {
            m_mv_stats_before[s] = in.get<MvViewStats>();
            const uint64_t dropped = in.get<uint64_t>();
            m_mv_films[s].load(in);
            m_mv_films[s].nonfinite += dropped;
            m_mv.native_map[s] = m_mv_films[s].map.data();
        }
    }
    in.finish();
}

bool Renderer::checkpoint_due(double elapsed, double &last) const {
    if (m_opts.state_path.empty() || m_opts.checkpoint_interval <= 0.0 || elapsed - last < m_opts.checkpoint_interval)
        return false;
    last = elapsed;
    return true;
}

} // namespace mvpt
