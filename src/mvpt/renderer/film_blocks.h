// Work over every view's film in blocks of pixels, in parallel (the folds of passes into the
// accumulators, the release of a held pass).
#pragma once

#include "film.h"

#include <tbb/parallel_for.h>

#include <utility>
#include <vector>

namespace mvpt {

/// f(film, slot, begin, end) over every view's pixels in blocks, in parallel.
template <class F> void film_blocks(std::vector<Film> &films, const F &f) {
    constexpr size_t Block = 4096;
    std::vector<std::pair<size_t, size_t>> blocks; // (slot, first pixel)
    for (size_t slot = 0; slot < films.size(); ++slot)
        for (size_t p = 0; p < films[slot].pixels(); p += Block) blocks.emplace_back(slot, p);
    tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
        const auto [slot, begin] = blocks[b];
        f(films[slot], int(slot), begin, std::min(films[slot].pixels(), begin + Block));
    });
}

} // namespace mvpt
