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
#include <vector>

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

/// The end of a chunk that starts at tile `first`: the largest `last` > `first` whose tiles
/// [first, last) hold at most `samples` samples, `prefix[t]` being those of tiles [0, t) (at
/// least one tile, at most every one).
inline size_t chunk_last(const std::vector<double> &prefix, size_t first, double samples) {
    const auto begin = prefix.begin() + std::ptrdiff_t(first) + 1;
    const auto end = std::upper_bound(begin, prefix.end(), prefix[first] + samples);
    return std::max(first + 1, size_t(end - prefix.begin()) - 1);
}

/// Renders tiles [0, tiles) with render(tile) (which returns its samples) in chunks of about a
/// quarter of a second, `prefix[t]` being about the samples of tiles [0, t) (tiles + 1
/// entries: chunks are sized by the tiles' own samples, which the adaptive maps make unequal,
/// weighed by their cost where the method knows it), so that `report(samples so far)` is
/// called that often; a chunk ends where `chunk_end(proposed end)` says. Before each chunk
/// after the first the loop asks `stop(true)` (timing.next: the chunk's expected seconds,
/// shorter for the last chunk of the tiles), and between tiles every task asks `stop(false)`;
/// a true answer abandons the tiles not begun (`finished` is then false). A tile is rendered
/// whole or not at all.
template <typename Render, typename Stop, typename Report, typename ChunkEnd>
ChunksDone run_in_chunks(tbb::task_arena &arena, const std::vector<double> &prefix, int threads, ChunkTiming &timing,
                         Render &&render, Stop &&stop, Report &&report, ChunkEnd &&chunk_end) {
    using clock = std::chrono::steady_clock;
    constexpr double ChunkSeconds = 0.25;
    std::atomic<bool> abandoned{false};
    const size_t tiles = prefix.empty() ? 0 : prefix.size() - 1;
    uint64_t done = 0;
    for (size_t first = 0; first < tiles && !abandoned.load();) {
        const double per_sample = timing.seconds_per_sample; // CPU seconds
        const size_t proposed = per_sample > 0.0 ? chunk_last(prefix, first, ChunkSeconds * threads / per_sample)
                                                 : std::min(tiles, first + size_t(2 * threads));
        const size_t last = std::min(tiles, chunk_end(proposed));
        timing.next = per_sample > 0.0 ? (prefix[last] - prefix[first]) * per_sample / threads : timing.last;
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
        // (Per sample as the prefix counts them, which may weigh tiles by their cost.)
        if (prefix[last] > prefix[first]) timing.seconds_per_sample = took * threads / (prefix[last] - prefix[first]);
        timing.longest = std::max(timing.longest, took);
        timing.last = took;
        first = last;
        if (!abandoned.load() && first < tiles) report(done);
    }
    return {!abandoned.load(), done, 0};
}

} // namespace mvpt
