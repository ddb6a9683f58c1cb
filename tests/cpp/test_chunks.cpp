// The chunks of a step (renderer/chunks.h): every tile rendered once when nothing stops them;
// a stop between chunks leaves exactly the tiles before a chunk boundary rendered, and chunks
// end where the step's chunk_end moves them (multi-view path tracing's first pass ends them
// with a region, so that a cut keeps whole regions); a stop between tiles abandons the rest.
#include "mvpt/renderer/chunks.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <vector>

using namespace mvpt;

namespace {
constexpr size_t Tiles = 200, Region = 3;

/// Runs Tiles tiles of one sample each in `threads` threads, chunks ending with a region of
/// Region tiles; `stop(between_chunks, tiles rendered so far)` answers the stop requests.
template <typename Stop> ChunksDone run(int threads, std::vector<int> &rendered, Stop &&stop) {
    tbb::task_arena arena(threads);
    ChunkTiming timing;
    std::atomic<size_t> so_far{0};
    rendered.assign(Tiles, 0);
    std::vector<double> prefix(Tiles + 1);
    for (size_t t = 0; t <= Tiles; ++t) prefix[t] = double(t);
    return run_in_chunks(
        arena, prefix, threads, timing,
        [&](size_t t) {
            ++rendered[t];
            ++so_far;
            return uint64_t(1);
        },
        [&](bool between) { return stop(between, so_far.load()); }, [](uint64_t) {},
        [](size_t end) { return (end + Region - 1) / Region * Region; });
}
} // namespace

TEST(Chunks, EveryTileOnceWithoutStop) {
    std::vector<int> rendered;
    const ChunksDone done = run(2, rendered, [](bool, size_t) { return false; });
    EXPECT_TRUE(done.finished);
    EXPECT_EQ(done.samples, Tiles);
    for (int r : rendered) EXPECT_EQ(r, 1);
}

TEST(Chunks, StopBetweenChunksKeepsWholeRegions) {
    for (int threads : {1, 2, 3}) {
        std::vector<int> rendered;
        const ChunksDone done = run(threads, rendered, [](bool between, size_t) { return between; });
        EXPECT_FALSE(done.finished);
        // The first chunk (two tiles per thread, no timing yet) grown to the end of its region.
        EXPECT_EQ(done.prefix, (2 * size_t(threads) + Region - 1) / Region * Region) << threads;
        EXPECT_EQ(done.samples, done.prefix);
        for (size_t t = 0; t < Tiles; ++t) EXPECT_EQ(rendered[t], t < done.prefix ? 1 : 0) << t;
    }
}

TEST(Chunks, StopBetweenTilesAbandonsTheRest) {
    std::vector<int> rendered;
    const ChunksDone done = run(1, rendered, [](bool between, size_t so_far) { return !between && so_far >= 3; });
    EXPECT_FALSE(done.finished);
    EXPECT_EQ(done.prefix, 0u); // not stopped at a boundary
    EXPECT_EQ(done.samples, 3u);
    for (size_t t = 0; t < Tiles; ++t) EXPECT_EQ(rendered[t], t < 3 ? 1 : 0) << t;
}

TEST(Chunks, ChunkEndsWhereItsTilesHoldTheSamplesAsked) {
    // Tiles of 100, 1, 1, 1, 50, 50 samples (the adaptive maps make tiles unequal).
    const std::vector<double> prefix{0, 100, 101, 102, 103, 153, 203};
    EXPECT_EQ(chunk_last(prefix, 0, 10.0), 1u);   // one tile, even when it holds more
    EXPECT_EQ(chunk_last(prefix, 0, 102.0), 3u);  // [0, 3) holds 102
    EXPECT_EQ(chunk_last(prefix, 1, 2.5), 3u);    // [1, 3) holds 2
    EXPECT_EQ(chunk_last(prefix, 1, 52.0), 4u);   // [1, 5) would hold 53
    EXPECT_EQ(chunk_last(prefix, 1, 53.0), 5u);
    EXPECT_EQ(chunk_last(prefix, 3, 1e9), 6u);    // at most every tile
    EXPECT_EQ(chunk_last(prefix, 5, 0.0), 6u);    // the last tile
}
