#include "sampler_batch.h"

#include "sampler.h"
#include "simd.h"

namespace mvpt {

namespace {

/// Scalar draws (any CPU).
void draws_scalar(const uint64_t *hash, const uint32_t *dim, size_t begin, size_t n, float *const out[7]) {
    for (size_t i = begin; i < n; ++i) {
        uint64_t b0 = Sampler::independent_bits(hash[i], dim[i]), b1 = Sampler::independent_bits(hash[i], dim[i] + 1),
                 b2 = Sampler::independent_bits(hash[i], dim[i] + 2), b3 = Sampler::independent_bits(hash[i], dim[i] + 3),
                 b4 = Sampler::independent_bits(hash[i], dim[i] + 4);
        out[0][i] = bits_to_unit_float(uint32_t(b0));
        out[1][i] = bits_to_unit_float(uint32_t(b1));
        out[2][i] = bits_to_unit_float(uint32_t(b1 >> 32));
        out[3][i] = bits_to_unit_float(uint32_t(b2));
        out[4][i] = bits_to_unit_float(uint32_t(b3));
        out[5][i] = bits_to_unit_float(uint32_t(b3 >> 32));
        out[6][i] = bits_to_unit_float(uint32_t(b4));
    }
}

#if defined(__GNUC__) && defined(__x86_64__)
using U64x8 = simd::u64x8;
using F32x8 = simd::f32x8;
using I32x8 = simd::i32x8;

/// mix_bits on 8 lanes.
[[gnu::target("avx512f,avx512dq,avx512vl")]] inline U64x8 mix8(U64x8 v) {
    v ^= v >> 30;
    v *= 0xbf58476d1ce4e5b9ULL;
    v ^= v >> 27;
    v *= 0x94d049bb133111ebULL;
    v ^= v >> 31;
    return v;
}

/// bits_to_unit_float of 32-bit values held in the low or high halves of 8 lanes:
/// (bits >> 8) < 2^24 converts exactly, the scale is a power of two, and the clamp is min.
[[gnu::target("avx512f,avx512dq,avx512vl")]] inline F32x8 unit8(U64x8 bits, int shift) {
    U64x8 top24 = (bits >> shift) & 0xffffffffULL;
    top24 >>= 8;
    I32x8 i = __builtin_convertvector(top24, I32x8);
    F32x8 f = __builtin_convertvector(i, F32x8) * 0x1p-24f;
    F32x8 cap = {OneMinusEpsilon, OneMinusEpsilon, OneMinusEpsilon, OneMinusEpsilon,
                 OneMinusEpsilon, OneMinusEpsilon, OneMinusEpsilon, OneMinusEpsilon};
    return f < cap ? f : cap;
}

[[gnu::target("avx512f,avx512dq,avx512vl")]] size_t draws_avx512(const uint64_t *hash, const uint32_t *dim, size_t n,
                                                                  float *const out[7]) {
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        U64x8 h, d;
        __builtin_memcpy(&h, hash + i, sizeof(h));
        for (int l = 0; l < 8; ++l) d[l] = dim[i + l];
        const uint64_t golden = 0x9e3779b97f4a7c15ULL;
        U64x8 b[5];
        for (int k = 0; k < 5; ++k) b[k] = mix8(h + golden * (d + uint64_t(k + 1)));
        F32x8 f[7] = {unit8(b[0], 0), unit8(b[1], 0), unit8(b[1], 32), unit8(b[2], 0),
                      unit8(b[3], 0), unit8(b[3], 32), unit8(b[4], 0)};
        for (int k = 0; k < 7; ++k) __builtin_memcpy(out[k] + i, &f[k], sizeof(F32x8));
    }
    return i;
}

bool has_avx512() {
    static const bool yes = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                            __builtin_cpu_supports("avx512vl");
    return yes;
}
#endif

} // namespace

void independent_vertex_draws(const uint64_t *hash, const uint32_t *dim, size_t n, float *const out[7]) {
    size_t done = 0;
#if defined(__GNUC__) && defined(__x86_64__)
    if (has_avx512()) done = draws_avx512(hash, dim, n, out);
#endif
    draws_scalar(hash, dim, done, n, out);
}


namespace {

/// Lane i's pixel row and sample index: one for all lanes (a pixel row of one pass) or per lane.
struct StartLanes {
    const uint32_t *px, *py, *sample;
    uint32_t row, index; ///< used where py / sample are null
    uint32_t y(size_t i) const { return py ? py[i] : row; }
    uint32_t s(size_t i) const { return sample ? sample[i] : index; }
};

/// independent_start_draws on lanes [begin, n) (any CPU).
void start_draws_scalar(uint64_t h_view, const StartLanes &in, size_t begin, size_t n, uint64_t *pixel_hash,
                        uint64_t *sample_hash, float *const out[5]) {
    for (size_t i = begin; i < n; ++i) {
        uint64_t ph = hash_combine(hash_combine(h_view, in.px[i]), in.y(i));
        uint64_t sh = hash_combine(ph, in.s(i));
        pixel_hash[i] = ph;
        sample_hash[i] = sh;
        uint64_t b0 = Sampler::independent_bits(sh, 0), b1 = Sampler::independent_bits(sh, 1),
                 b2 = Sampler::independent_bits(sh, 2);
        out[0][i] = bits_to_unit_float(uint32_t(b0));
        out[1][i] = bits_to_unit_float(uint32_t(b0 >> 32));
        out[2][i] = bits_to_unit_float(uint32_t(b1));
        out[3][i] = bits_to_unit_float(uint32_t(b1 >> 32));
        out[4][i] = bits_to_unit_float(uint32_t(b2));
    }
}

#if defined(__GNUC__) && defined(__x86_64__)
/// hash_combine on 8 lanes.
[[gnu::target("avx512f,avx512dq,avx512vl")]] inline U64x8 combine8(U64x8 h, U64x8 v) {
    return mix8(h ^ (v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2)));
}

[[gnu::target("avx512f,avx512dq,avx512vl")]] size_t start_draws_avx512(uint64_t h_view, const StartLanes &in, size_t n,
                                                                        uint64_t *pixel_hash, uint64_t *sample_hash,
                                                                        float *const out[5]) {
    const U64x8 hv = {h_view, h_view, h_view, h_view, h_view, h_view, h_view, h_view};
    const uint64_t golden = 0x9e3779b97f4a7c15ULL;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        U64x8 x, y, s;
        for (int l = 0; l < 8; ++l) x[l] = in.px[i + l], y[l] = in.y(i + l), s[l] = in.s(i + l);
        U64x8 ph = combine8(combine8(hv, x), y);
        U64x8 sh = combine8(ph, s);
        __builtin_memcpy(pixel_hash + i, &ph, sizeof(ph));
        __builtin_memcpy(sample_hash + i, &sh, sizeof(sh));
        U64x8 b0 = mix8(sh + golden * 1), b1 = mix8(sh + golden * 2), b2 = mix8(sh + golden * 3);
        F32x8 f[5] = {unit8(b0, 0), unit8(b0, 32), unit8(b1, 0), unit8(b1, 32), unit8(b2, 0)};
        for (int k = 0; k < 5; ++k) __builtin_memcpy(out[k] + i, &f[k], sizeof(F32x8));
    }
    return i;
}
#endif

void start_draws(uint64_t seed, uint32_t view, const StartLanes &in, size_t n, uint64_t *pixel_hash,
                 uint64_t *sample_hash, float *const out[5]) {
    // Sampler::start's hash_ints(seed, view, px, py), then the sample index.
    const uint64_t h_view = hash_combine(mix_bits(seed + 0x9e3779b97f4a7c15ULL), view);
    size_t done = 0;
#if defined(__GNUC__) && defined(__x86_64__)
    if (has_avx512()) done = start_draws_avx512(h_view, in, n, pixel_hash, sample_hash, out);
#endif
    start_draws_scalar(h_view, in, done, n, pixel_hash, sample_hash, out);
}

} // namespace

void independent_start_draws(uint64_t seed, uint32_t view, const uint32_t *px, uint32_t py, uint32_t sample, size_t n,
                             uint64_t *pixel_hash, uint64_t *sample_hash, float *const out[5]) {
    start_draws(seed, view, StartLanes{px, nullptr, nullptr, py, sample}, n, pixel_hash, sample_hash, out);
}

void independent_start_draws(uint64_t seed, uint32_t view, const uint32_t *px, const uint32_t *py,
                             const uint32_t *sample, size_t n, uint64_t *pixel_hash, uint64_t *sample_hash,
                             float *const out[5]) {
    start_draws(seed, view, StartLanes{px, py, sample, 0, 0}, n, pixel_hash, sample_hash, out);
}

} // namespace mvpt
