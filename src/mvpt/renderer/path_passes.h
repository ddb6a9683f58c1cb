// Path tracing's part in the pass loop (pass_schedule.h): steps of whole passes over every
// view's tiles. Under the box filter each sample is added to its pixel's sums (Film::add);
// under other filters (Renderer::m_splat) samples are uniform over the pixels and the filter's
// reach around the crop window, and each is splatted with the filter into the pass's
// fixed-point sums (render/splat_film.h), which are folded into the films pass by pass, each
// pass one estimate per pixel with the control variate of the balance estimator (film.h).
#pragma once

#include "pass_schedule.h"
#include "renderer.h"

#include <tbb/enumerable_thread_specific.h>

#include <memory>
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
    /// Every tile finished keeps its samples, also in a step abandoned (splatting: none).
    uint64_t kept(const ChunksDone &done) const override;
    double fraction(uint64_t samples) const override;
    double fraction_after(int pass) const override { return double(pass + 1) / double(m_max_target); }
    void save(int next_pass, double elapsed, double last_pass) override {
        m_r.write_state(next_pass, elapsed, last_pass, counters());
    }
    /// Splatting: a step abandoned is dropped (its splats reach beyond its tiles).
    bool abandon(const ChunksDone &) override;
    /// Splatting: the step's passes folded into the films.
    void end_step() override;
    /// After the loop: the splats' buffers freed.
    void finish();
    /// The ray counters of the runs before and of this one.
    RayCounters counters() const;
    /// The passes rendered together per tile without a time budget, for `pixels` view-pixels
    /// in all: 16, halved while a group would exceed GroupPaths paths (splatting keeps one
    /// group's sums: at most GroupPaths view-pixels of them beyond one pass's).
    static int group_passes(uint64_t pixels);

private:
    static constexpr double StepSeconds = 0.25;
    static constexpr int MaxStep = 16;
    static constexpr uint64_t GroupPaths = uint64_t(1) << 20;

    /// Passes [pass0, pass1) of a tile as batches of paths through the integrator.
    void render_group(const Tile &tile, int pass0, int pass1, RayCounters &rc);
    /// The crop-window pixels of a tile (splatting: its tiles cover the sample window).
    uint64_t crop_pixels(const Tile &t) const;
    /// Splatting: n samples of view `slot` (radiance, film position, sampler; full-film pixel,
    /// sample index) into the step's sums through the thread's cache.
    void splat_batch(int slot, const Spectrum *radiance, const Vec2f *film, const Sampler *samplers, const uint32_t *sx,
                     const uint32_t *sy, const uint32_t *sq, size_t n, RayCounters &rc);
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
    // Splatting: where each view takes samples, and the sums of a step's passes, pass j of the
    // step's view slot s at slot j * views + s of m_pass_film, with each thread's cache.
    std::vector<SampleWindow> m_windows;
    int m_group_max = 1; ///< the most passes of a step
    std::unique_ptr<MvPassFilm> m_pass_film;
    std::unique_ptr<tbb::enumerable_thread_specific<SplatCache>> m_caches;
};

} // namespace mvpt
