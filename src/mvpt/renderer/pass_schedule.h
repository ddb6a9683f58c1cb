// A rendering method's part in the pass loop that every method shares (Renderer::run_passes,
// pass_loop.cpp): which passes a step renders, its tiles, and what happens between steps. The
// loop answers cancellation, the time budget, progress and checkpoints the same way for all.
#pragma once

#include "chunks.h"

#include <tbb/task_arena.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mvpt {

/// The tiles of a step and about how many samples they hold (what sizes its chunks):
/// `prefix[t]` those of tiles [0, t), one entry more than there are tiles.
struct StepTiles {
    std::vector<double> prefix{0.0};
    /// Appends a tile of `samples` samples.
    void add(double samples) { prefix.push_back(prefix.back() + samples); }
};

class PassSchedule {
public:
    explicit PassSchedule(tbb::task_arena &arena) : m_arena(arena) {}
    virtual ~PassSchedule() = default;
    PassSchedule(const PassSchedule &) = delete;
    PassSchedule &operator=(const PassSchedule &) = delete;

    tbb::task_arena &arena() const { return m_arena; }
    /// Whether the sample target is reached before `pass`.
    virtual bool done(int pass) const = 0;
    /// The end of the step that starts at `pass` (it renders passes [pass, end)), given how
    /// many whole passes still fit in the time budget (`fit`: infinite without a budget, below 1
    /// or not a number when none fits) and the seconds of a whole pass as the last pass measured
    /// them (whole_pass_seconds); `pass` ends the render.
    virtual int step_end(int pass, double fit, double last_pass) = 0;
    /// Starts step [pass, end): its tiles.
    virtual StepTiles begin_step(int pass, int end) = 0;
    /// Renders tile `t` of the step; returns its samples.
    virtual uint64_t render(size_t t) = 0;
    /// Whether a stop request (Ctrl-C, the end of the time budget) may abandon the step's
    /// tiles not begun, `in_step` seconds into the step, between two tiles of a chunk or
    /// (`between_chunks`) before a chunk.
    virtual bool can_abandon(double last_pass, double in_step, bool between_chunks) const = 0;
    /// Whether the time budget may stop pass `pass` (a first pass always finishes unless its
    /// method keeps a part of it).
    virtual bool budget_stops(int pass) const { return pass > 0; }
    /// Where a chunk of the step's tiles that would end at tile `end` ends.
    virtual size_t chunk_end(size_t end) const { return end; }
    /// The step's samples that the images keep (`done`: what its tiles rendered).
    virtual uint64_t kept(const ChunksDone &done) const = 0;
    /// After a step abandoned (`done`: what its tiles rendered): whether what it rendered
    /// entered the images as a pass of its own.
    virtual bool abandon(const ChunksDone &) { return false; }
    /// After a step finished (the work between passes).
    virtual void end_step() {}
    /// The seconds a whole pass would have lasted, from those of the step's last pass (a method
    /// that thins its passes scales them up; what `fit` and `last_pass` count in).
    virtual double whole_pass_seconds(double seconds) const { return seconds; }
    /// The share of the sample target reached after `samples` of the step's samples, and
    /// after pass `pass`.
    virtual double fraction(uint64_t samples) const = 0;
    virtual double fraction_after(int pass) const = 0;
    /// Writes the state file at a pass boundary: the next pass, the seconds elapsed, the last
    /// pass's seconds.
    virtual void save(int next_pass, double elapsed, double last_pass) = 0;

private:
    tbb::task_arena &m_arena;
};

} // namespace mvpt
