// Path tracing's part in the pass loop (pass_schedule.h): steps of whole passes over every
// view's tiles, each sample added to its pixel's sums (Film::add).
#pragma once

#include "pass_schedule.h"
#include "renderer.h"

#include <tbb/enumerable_thread_specific.h>

#include <mutex>
#include <vector>

namespace mvpt {

class Renderer::PathPasses final : public PassSchedule {
public:
    /// The schedule of `r`'s render (its state, when resumed, already read).
    PathPasses(Renderer &r, tbb::task_arena &arena);
    bool done(int pass) const override { return pass >= m_max_target; }
    int step_end(int pass, double fit, double last_pass) override;
    StepTiles begin_step(int pass, int end) override;
    uint64_t render(size_t t) override;
    bool can_abandon(double last_pass, double in_step, bool between_chunks) const override;
    /// Every tile finished keeps its samples, also in a step abandoned.
    uint64_t kept(const ChunksDone &done) const override { return done.samples; }
    double fraction(uint64_t samples) const override;
    double fraction_after(int pass) const override { return double(pass + 1) / double(m_max_target); }
    void save(int next_pass, double elapsed, double last_pass) override {
        m_r.write_state(next_pass, elapsed, last_pass, counters());
    }
    /// The ray counters of the runs before and of this one.
    RayCounters counters() const;

private:
    static constexpr double StepSeconds = 0.25;
    static constexpr int MaxStep = 16;
    static constexpr uint64_t GroupPaths = uint64_t(1) << 20;

    /// Passes [pass0, pass1) of a tile as batches of paths through the integrator.
    void render_group(const Tile &tile, int pass0, int pass1, RayCounters &rc);
    /// A non-finite sample of pixel (px, py), pass `pass`: counted, and the first one (in
    /// pass, view, y, x order) recorded for replay.
    void drop_nonfinite(Film &film, int view, int px, int py, int pass, RayCounters &rc);

    Renderer &m_r;
    std::vector<Tile> m_tiles;
    std::vector<int> m_target; ///< passes per view
    int m_max_target = 0;
    uint32_t m_sample0;        ///< the sample index of pass 0
    int m_group = 1;           ///< passes rendered together per tile (one batch order)
    int m_step_passes = 1;     ///< passes of the next step
    // The current step: its passes, tiles and samples.
    int m_pass = 0, m_end = 0;
    std::vector<const Tile *> m_step;
    uint64_t m_step_samples = 0;
    tbb::enumerable_thread_specific<RayCounters> m_counters;
    std::mutex m_nonfinite_mutex;
};

} // namespace mvpt
