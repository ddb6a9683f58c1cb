// simd::gather and simd::compress (core/simd_gather.*) against the records and lanes
// themselves, word for word: on this CPU (its AVX-512 loops where it has them), one word at a
// time, and the AVX-512 loops compiled once more against the portable stand-ins of their
// intrinsics below (simd::emulated), so that those loops are checked on every CPU.
#include "mvpt/core/simd_gather.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

// Intel's definitions of the intrinsics the AVX-512 loops use, one lane at a time. Masked-off
// lanes are neither read nor written, as the instructions suppress their faults.
namespace mvpt::simd::emulated {

using __mmask16 = uint16_t;
struct __m512 {
    uint32_t w[16];
};
struct __m512i {
    uint32_t w[16];
};
#ifndef _CMP_GT_OQ
#define _CMP_GT_OQ 0x1e
#endif

inline bool on(__mmask16 k, int i) { return (k >> i) & 1; }
inline __m512 _mm512_setzero_ps() { return {}; }
inline __m512i _mm512_set1_epi32(int x) {
    __m512i r;
    for (uint32_t &w : r.w) w = uint32_t(x);
    return r;
}
inline __m512i _mm512_mullo_epi32(__m512i a, __m512i b) {
    for (int i = 0; i < 16; ++i) a.w[i] *= b.w[i]; // the low 32 bits of the product
    return a;
}
inline __m512i _mm512_maskz_loadu_epi32(__mmask16 k, const void *p) {
    __m512i r{};
    for (int i = 0; i < 16; ++i)
        if (on(k, i)) std::memcpy(&r.w[i], static_cast<const char *>(p) + 4 * i, 4);
    return r;
}
inline __m512 _mm512_maskz_loadu_ps(__mmask16 k, const void *p) {
    const __m512i r = _mm512_maskz_loadu_epi32(k, p);
    return std::bit_cast<__m512>(r);
}
inline __m512 _mm512_mask_i32gather_ps(__m512 src, __mmask16 k, __m512i index, const void *base, int scale) {
    for (int i = 0; i < 16; ++i) // the index is a signed 32-bit number
        if (on(k, i)) std::memcpy(&src.w[i], static_cast<const char *>(base) + int64_t(int32_t(index.w[i])) * scale, 4);
    return src;
}
inline void _mm512_mask_storeu_ps(void *p, __mmask16 k, __m512 v) {
    for (int i = 0; i < 16; ++i)
        if (on(k, i)) std::memcpy(static_cast<char *>(p) + 4 * i, &v.w[i], 4);
}
inline void _mm512_storeu_ps(void *p, __m512 v) { _mm512_mask_storeu_ps(p, 0xffff, v); }
inline __mmask16 _mm512_mask_cmp_ps_mask(__mmask16 k, __m512 a, __m512 b, int predicate) {
    EXPECT_EQ(predicate, _CMP_GT_OQ); // the only comparison the loops make
    __mmask16 r = 0;
    for (int i = 0; i < 16; ++i) // ordered: false where either is a NaN
        if (on(k, i) && std::bit_cast<float>(a.w[i]) > std::bit_cast<float>(b.w[i])) r |= __mmask16(1u << i);
    return r;
}
inline __m512 _mm512_maskz_compress_ps(__mmask16 k, __m512 v) {
    __m512 r{};
    int o = 0;
    for (int i = 0; i < 16; ++i)
        if (on(k, i)) r.w[o++] = v.w[i];
    return r;
}

} // namespace mvpt::simd::emulated

#define MVPT_SIMD_EMULATED 1
#include "mvpt/core/simd_gather.cpp"

using namespace mvpt;

namespace {

uint32_t next_word(uint32_t &state) {
    state = state * 1664525u + 1013904223u;
    return state;
}

/// Words whose bits a float copy could change: signalling and quiet NaNs, infinities, -0.
constexpr uint32_t Special[] = {0x7f800001u, 0xffc00000u, 0x7f800000u, 0x80000000u, 0x00000001u};

/// Fields in any order, a column left out (column 4).
constexpr simd::FieldList Fields = simd::FieldList().add(3, 0).add(0, 12 * 4).add(5, 7 * 4).add(1, 4).add(2, 8);

/// The three ways to run a call: this CPU's loop, the scalar loop, the emulated AVX-512 loop.
enum class Way { Cpu, Scalar, Emulated };
constexpr Way Ways[] = {Way::Cpu, Way::Scalar, Way::Emulated};

} // namespace

TEST(SimdGather, GathersEveryFieldOfEveryLane) {
    constexpr size_t records = 300, record_words = 13, stride = 80, columns = 6;
    constexpr uint32_t sentinel = 0xdeadbeefu;
    std::vector<uint32_t> table(records * record_words);
    uint32_t state = 11u;
    for (size_t i = 0; i < table.size(); ++i) table[i] = i % 17 == 0 ? Special[i % 5] : next_word(state);
    const auto &fields = Fields.field;
    for (size_t n : {size_t(1), size_t(15), size_t(16), size_t(17), size_t(37), size_t(64), size_t(80)}) {
        std::vector<uint32_t> index(n);
        for (uint32_t &k : index) k = next_word(state) % records;
        index[0] = records - 1; // the last record: the gathers must not read past it
        for (Way way : Ways) {
            std::vector<uint32_t> cols(columns * stride, sentinel);
            if (way == Way::Emulated)
                simd::emulated::gather_avx512(cols.data(), stride, n, index.data(), table.data(), record_words * 4,
                                              {fields, Fields.size});
            else
                simd::gather<Fields>(cols.data(), stride, n, index.data(), table.data(), record_words * 4, way == Way::Cpu);
            for (size_t c = 0; c < columns; ++c) {
                const simd::Field *f = nullptr;
                for (size_t i = 0; i < Fields.size; ++i)
                    if (fields[i].column == c) f = &fields[i];
                for (size_t m = 0; m < stride; ++m) {
                    const uint32_t expect = f && m < n ? table[index[m] * record_words + f->offset / 4] : sentinel;
                    ASSERT_EQ(cols[c * stride + m], expect) << "way " << int(way) << " n " << n << " column " << c
                                                            << " lane " << m;
                }
            }
        }
    }
}

TEST(SimdGather, CompressesTheLanesThatCountInOrder) {
    constexpr size_t lanes = 70, columns = 3, spare = 16;
    constexpr uint32_t sentinel = 0xdeadbeefu;
    uint32_t state = 5u;
    std::vector<uint32_t> in[columns];
    for (size_t c = 0; c < columns; ++c) {
        in[c].resize(lanes);
        for (size_t m = 0; m < lanes; ++m) in[c][m] = m % 7 == c ? Special[m % 5] : next_word(state);
    }
    // Whether a lane counts: > 0 only (NaN, zeros and negative values do not).
    const float keep_values[] = {1.f, 0.f, std::nanf(""), -1.f, 1e-45f, -0.f, INFINITY, -INFINITY};
    std::vector<float> keep(lanes);
    for (size_t m = 0; m < lanes; ++m) keep[m] = keep_values[(m * 5 + m / 9) % 8];
    for (size_t m = 16; m < 32; ++m) keep[m] = 0.f; // a 16-lane step in which no lane counts
    for (size_t n : {size_t(1), size_t(16), size_t(31), size_t(32), size_t(53), size_t(70)}) {
        // The lanes that count; where the AVX-512 loop's last whole-step store ends.
        std::vector<size_t> counting;
        size_t stored_end = 0;
        for (size_t m = 0; m < n; ++m) {
            if (!(keep[m] > 0.f)) continue;
            if (counting.empty() || counting.back() / 16 != m / 16) stored_end = counting.size() + 16;
            counting.push_back(m);
        }
        for (Way way : Ways) {
            std::vector<uint32_t> out[columns];
            const void *in_ptr[columns];
            void *out_ptr[columns];
            for (size_t c = 0; c < columns; ++c) {
                out[c].assign(lanes + spare, sentinel);
                in_ptr[c] = in[c].data(), out_ptr[c] = out[c].data();
            }
            size_t count = 0;
            if (way == Way::Emulated)
                count = simd::emulated::compress_avx512(in_ptr, out_ptr, columns, keep.data(), n);
            else
                count = simd::compress(in_ptr, out_ptr, keep.data(), n, way == Way::Cpu);
            ASSERT_EQ(count, counting.size()) << "way " << int(way) << " n " << n;
            for (size_t c = 0; c < columns; ++c) {
                for (size_t i = 0; i < count; ++i)
                    ASSERT_EQ(out[c][i], in[c][counting[i]]) << "way " << int(way) << " n " << n << " entry " << i;
                // Past the count: zeros up to the end of the last 16-lane store, then untouched.
                const bool avx512 = way == Way::Emulated || (way == Way::Cpu && simd::cpu_has_avx512f());
                for (size_t i = count; i < out[c].size(); ++i)
                    ASSERT_EQ(out[c][i], avx512 && i < stored_end ? 0u : sentinel) << "way " << int(way) << " n " << n
                                                                                  << " entry " << i;
            }
        }
    }
}
