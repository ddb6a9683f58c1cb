// The tiles of a pass (or of a group of passes) run in chunks of about a quarter of a second,
// so that progress, Ctrl-C and a time budget are answered that often however many views and
// pixels a pass has: one mechanism for every rendering method.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>

namespace mvpt {

/// What the chunks of a render have measured: CPU seconds per sample, the longest chunk and
/// the last one; and how long the next one is expected to take (from the seconds per sample,
/// or as long as the last one before any was measured).
struct ChunkTiming {
    double seconds_per_sample = 0.0, longest = 0.0, last = 0.0, next = 0.0;
};

/// How a run of chunks ended: whether every tile was rendered, and the samples rendered;
/// when it was stopped between two chunks, `prefix` is where: tiles [0, prefix) were rendered
/// and no other (else 0).
struct ChunksDone {
    bool finished = true;
    uint64_t samples = 0;
    size_t prefix = 0;
};

/// Renders tiles [0, tiles) with render(tile) (which returns its samples) in chunks of about a
/// quarter of a second, `samples` being about what all tiles hold, so that `report(samples so
/// far)` is called that often; a chunk ends where `chunk_end(proposed end)` says. Before each
/// chunk after the first the loop asks `stop(true)` (timing.next: the chunk's expected
/// seconds, shorter for the last chunk of the tiles), and between tiles every task asks
/// `stop(false)`; a true answer abandons the tiles not begun (`finished` is then false). A
/// tile is rendered whole or not at all.
template <typename Render, typename Stop, typename Report, typename ChunkEnd>
ChunksDone run_in_chunks(tbb::task_arena &arena, size_t tiles, int threads, double samples, ChunkTiming &timing,
                         Render &&render, Stop &&stop, Report &&report, ChunkEnd &&chunk_end) {
    using clock = std::chrono::steady_clock;
    constexpr double ChunkSeconds = 0.25;
    std::atomic<bool> abandoned{false};
    uint64_t done = 0;
    for (size_t first = 0; first < tiles && !abandoned.load();) {
        const double per_tile = timing.seconds_per_sample * samples / double(tiles); // CPU seconds
        const size_t count = per_tile > 0.0 ? size_t(std::clamp(ChunkSeconds * threads / per_tile, 1.0, 1e9))
                                            : size_t(2 * threads);
        const size_t last = std::min(tiles, chunk_end(std::min(tiles, first + count)));
        timing.next = per_tile > 0.0 ? double(last - first) * per_tile / threads : timing.last;
        if (first > 0 && stop(true)) return {false, done, first};
        const auto t0 = clock::now();
        std::atomic<uint64_t> chunk{0};
        arena.execute([&] {
            tbb::parallel_for(tbb::blocked_range<size_t>(first, last, 1), [&](const tbb::blocked_range<size_t> &r) {
                uint64_t n = 0;
                for (size_t ti = r.begin(); ti != r.end(); ++ti) {
                    if (stop(false)) abandoned = true;
                    if (abandoned.load(std::memory_order_relaxed)) break;
                    n += render(ti);
                }
                chunk += n;
            });
        });
        const double took = std::chrono::duration<double>(clock::now() - t0).count();
        done += chunk.load();
        if (chunk.load() > 0) timing.seconds_per_sample = took * threads / double(chunk.load());
        timing.longest = std::max(timing.longest, took);
        timing.last = took;
        first = last;
        if (!abandoned.load() && first < tiles) report(done);
    }
    return {!abandoned.load(), done, 0};
}

} // namespace mvpt
