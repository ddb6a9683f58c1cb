// The independent sampler's numbers for many samples at once: the wavefront path tracer
// draws every scattering vertex's numbers in one loop, 8 samples per AVX-512 instruction
// when the CPU has it. Integer hashing and exact conversions, so the numbers are bit for
// bit those of Sampler::next_1d / next_2d.
#pragma once

#include <cstddef>
#include <cstdint>

namespace mvpt {

/// Numbers of one path vertex, in the order li draws them: next_1d, next_2d, next_1d,
/// next_2d, next_1d from dimension `dim[i]` of the independent sample `hash[i]`:
/// out[0][i]; out[1][i], out[2][i]; out[3][i]; out[4][i], out[5][i]; out[6][i].
void independent_vertex_draws(const uint64_t *hash, const uint32_t *dim, size_t n, float *const out[7]);

/// Sampler::start(view, px[i], py, sample) of n independent samples of one pixel row, into
/// pixel_hash[i] and sample_hash[i], and their first three draws from dimension 0 in the
/// order next_2d, next_2d, next_1d (film, lens, time): out[0][i], out[1][i]; out[2][i],
/// out[3][i]; out[4][i]. Bit-identical to the sampler's own calls.
void independent_start_draws(uint64_t seed, uint32_t view, const uint32_t *px, uint32_t py, uint32_t sample, size_t n,
                             uint64_t *pixel_hash, uint64_t *sample_hash, float *const out[5]);
/// The same for n samples of any pixels (px[i], py[i]) and sample indices sample[i].
void independent_start_draws(uint64_t seed, uint32_t view, const uint32_t *px, const uint32_t *py,
                             const uint32_t *sample, size_t n, uint64_t *pixel_hash, uint64_t *sample_hash,
                             float *const out[5]);

} // namespace mvpt
