// The camera samples of a batch of one view's samples (docs/multiview-path-tracing.md §2):
// the numbers of the camera dimensions (film, lens, time) of each (pixel, sample index), and
// the film position, lens point and time they map to, for path tracing and multi-view path
// tracing alike.
#pragma once

#include "../core/math.h"

#include <cstdint>
#include <vector>

namespace mvpt {

class Camera;
class Sampler;

/// How a sample's film position is drawn in its pixel.
enum class FilmSampling {
    /// The pixel centre plus an offset drawn from the sensor's reconstruction filter (path
    /// tracing under the box, or under a filter too wide to splat).
    Filter,
    /// Uniform in the pixel: the sample is splatted with the filter instead (multi-view path
    /// tracing, §5, and path tracing under other filters).
    Box,
};

/// The camera samples of n samples of one view, kept between batches (arrays only grow).
struct CameraSamples {
    std::vector<Vec2f> film; ///< film position (full-film pixels)
    std::vector<Vec2f> lens; ///< point on the unit disk
    std::vector<float> time;
    /// The sample's filter weight h / p (ReconstructionFilter::sample): 1 but for filters
    /// with negative lobes under FilmSampling::Filter.
    std::vector<float> weight;
    /// The independent sampler's hashes of (seed, view, pixel) and of the sample, for
    /// Sampler::start_from; empty for the other samplers.
    std::vector<uint64_t> pixel_hash, sample_hash;
    std::vector<float> draws[5]; ///< the camera dimensions' numbers (independent sampler)

    /// Draws the camera samples of pixels (px[i], py[i]) (full-film coordinates; a margin's
    /// negative ones stored as uint32), sample indices index[i], of view `view` (its scene
    /// index) of camera `cam` with seed `seed`. The lens point is drawn for every camera with
    /// `lens_always` (other views may have a lens), else only for thin lenses.
    void draw(const Camera &cam, uint32_t seed, uint32_t view, const uint32_t *px, const uint32_t *py,
              const uint32_t *index, size_t n, FilmSampling film_sampling, bool lens_always);
    /// Starts `sampler` at sample i of the last draw (view `view`, pixel, index), at dimension `dim`.
    void start(Sampler &sampler, size_t i, uint32_t view, uint32_t px, uint32_t py, uint32_t index,
               uint32_t dim) const;
};

} // namespace mvpt
