// The pass loop of every rendering method: steps of passes, each a list of tiles run in chunks
// (chunks.h); between chunks progress is reported and Ctrl-C and the time budget are answered,
// between steps checkpoints are written. What a step is comes from the method (pass_schedule.h).
#include "renderer.h"
#include "pass_schedule.h"

#include <chrono>
#include <cmath>

namespace mvpt {

void Renderer::run_passes(PassSchedule &schedule, const std::atomic<bool> &cancel, const ProgressFn &progress) {
    using clock = std::chrono::steady_clock;
    // The clock starts with render() (the method's preparation counts); a resumed render's goes
    // on from the seconds of the runs before (for --time).
    const auto t_start =
        m_render_start - std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(m_elapsed_before));
    auto seconds = [&] { return std::chrono::duration<double>(clock::now() - t_start).count(); };
    const double budget = m_opts.time_budget;
    double last_pass = m_last_pass_before, last_checkpoint = m_elapsed_before;
    ChunkTiming timing;
    int pass = m_first_pass;
    while (!schedule.done(pass)) {
        if (cancel.load()) { m_stats.cancelled = true; break; }
        // The passes that still fit in the budget (the first pass always runs).
        const double fit = pass > 0 && budget > 0.0 ? (budget - seconds()) / last_pass : INFINITY;
        const int end = schedule.step_end(pass, fit, last_pass);
        if (end == pass) break;
        const double t_step = seconds();
        const StepTiles step = schedule.begin_step(pass, end);
        // Between chunks the budget stops a step whose next chunk would end past it.
        auto stop = [&](bool between_chunks) {
            const double next = between_chunks ? timing.next : 0.0;
            const bool asked = cancel.load() || (schedule.budget_stops(pass) && budget > 0.0 && seconds() + next > budget);
            return asked && schedule.can_abandon(last_pass, seconds() - t_step, between_chunks);
        };
        auto report = [&](uint64_t samples) {
            report_progress(progress, pass, seconds(), m_stats.samples + samples, schedule.fraction(samples));
        };
        const ChunksDone done = run_in_chunks(schedule.arena(), step.prefix, m_stats.threads, timing,
                                              [&](size_t t) { return schedule.render(t); }, stop, report,
                                              [&](size_t end) { return schedule.chunk_end(end); });
        m_stats.samples += schedule.kept(done);
        if (!done.finished) {
            if (schedule.abandon(done)) { // a pass, though not every tile of it
                m_stats.passes = ++pass;
                report_progress(progress, pass, seconds(), m_stats.samples, schedule.fraction_after(pass - 1));
            }
            m_stats.cancelled = cancel.load();
            break;
        }
        schedule.end_step();
        const double step_pass = (seconds() - t_step) / double(end - pass);
        last_pass = schedule.whole_pass_seconds(step_pass);
        for (int q = pass; q < end; ++q) {
            m_stats.max_pass_seconds = std::max(m_stats.max_pass_seconds, step_pass);
            m_stats.passes = q + 1;
            report_progress(progress, q + 1, seconds(), m_stats.samples, schedule.fraction_after(q));
        }
        pass = end;
        if (m_stats.state_error.empty() && checkpoint_due(seconds(), last_checkpoint))
            save_state(schedule, pass, seconds(), last_pass);
    }
    m_stats.seconds = seconds();
    m_stats.max_chunk_seconds = timing.longest;
    if (!m_opts.state_path.empty() && (m_stats.cancelled || m_opts.state_at_end))
        save_state(schedule, pass, m_stats.seconds, last_pass);
}

void Renderer::save_state(PassSchedule &schedule, int pass, double elapsed, double last_pass) {
    // A state that cannot be written (a full disk, a file-size limit) does not cost the render
    // its images: it goes on without checkpoints and says why (RenderStats::state_error).
    try {
        schedule.save(pass, elapsed, last_pass);
    } catch (const std::runtime_error &e) {
        if (m_stats.state_error.empty()) m_stats.state_error = e.what();
    }
}

void Renderer::report_progress(const ProgressFn &progress, int pass, double elapsed, uint64_t samples,
                               double fraction) const {
    if (!progress) return;
    RenderProgress p;
    p.pass = pass;
    p.elapsed = elapsed;
    p.samples = samples;
    p.fraction = fraction;
    if (m_opts.time_budget > 0.0) p.fraction = std::max(p.fraction, std::min(1.0, p.elapsed / m_opts.time_budget));
    progress(p);
}

} // namespace mvpt
