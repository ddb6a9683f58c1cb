// Moving 32-bit words between records and columns: gathers of record fields into the
// columns of a vector loop, and compresses of the lanes that count. 16 lanes per AVX-512
// gather or compress where the CPU has it (simd_gather.cpp: mvpt's only intrinsics; every
// other vector loop is written with the vector types of simd.h), else one word at a time
// by the loops below, which the compiler unrolls over fields and columns known at compile
// time. Pure copies: the results are the same bits on every CPU.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>

namespace mvpt::simd {

/// Where a gathered word goes: output column `column`, from byte `offset` of a record (a
/// multiple of 4).
struct Field {
    uint32_t column;
    uint32_t offset;
};

/// The fields a gather copies, built at compile time: `add(column, offset, words)` appends
/// `words` consecutive words from byte `offset` to consecutive columns from `column`.
struct FieldList {
    Field field[32]{};
    size_t size = 0;
    constexpr FieldList &add(size_t column, size_t offset, size_t words = 1) {
        for (size_t w = 0; w < words; ++w) field[size++] = {uint32_t(column + w), uint32_t(offset + w * 4)};
        return *this;
    }
};

/// Whether the CPU runs AVX-512F (asked once).
inline bool cpu_has_avx512f() {
#if defined(__GNUC__) && defined(__x86_64__)
    static const bool yes = __builtin_cpu_supports("avx512f");
    return yes;
#else
    return false;
#endif
}

/// The AVX-512 loops of gather and compress (simd_gather.cpp), for CPUs with AVX-512 only.
void gather_avx512(void *cols, size_t stride, size_t n, const uint32_t *index, const void *records,
                   size_t record_bytes, std::span<const Field> fields);
size_t compress_avx512(const void *const *in, void *const *out, size_t columns, const float *keep, size_t n);

/// For each field f of `Fields` (a constexpr FieldList) and lane m < n: word m of column
/// f.column (columns `stride` words apart from `cols`) gets the 32-bit word at byte f.offset
/// of record index[m] of `records` (records `record_bytes` apart, a multiple of 4;
/// index[m] * record_bytes < 2^33). Lanes from n on are not written. `vector` = false copies
/// one word at a time on any CPU.
template <const FieldList &Fields>
void gather(void *cols, size_t stride, size_t n, const uint32_t *index, const void *records, size_t record_bytes,
            bool vector = true) {
    if (vector && cpu_has_avx512f())
        return gather_avx512(cols, stride, n, index, records, record_bytes, {Fields.field, Fields.size});
    for (size_t m = 0; m < n; ++m) {
        const char *const record = static_cast<const char *>(records) + size_t(index[m]) * record_bytes;
        float *const lane = static_cast<float *>(cols) + m;
#pragma GCC unroll 32
        for (size_t i = 0; i < Fields.size; ++i)
            std::memcpy(lane + Fields.field[i].column * stride, record + Fields.field[i].offset, sizeof(float));
    }
}

/// The lanes m < n with keep[m] > 0 (a NaN does not count), in lane order: word m of column
/// in[c] to out[c][0, 1, ...) for each c < Columns. Returns how many lanes count. The AVX-512
/// loop stores whole 16-lane steps: each out[c] needs 16 words to spare past the last one used.
template <size_t Columns>
size_t compress(const void *const (&in)[Columns], void *const (&out)[Columns], const float *keep, size_t n,
                bool vector = true) {
    if (vector && cpu_has_avx512f()) return compress_avx512(in, out, Columns, keep, n);
    size_t count = 0;
    for (size_t m = 0; m < n; ++m) {
        if (!(keep[m] > 0.f)) continue;
#pragma GCC unroll 16
        for (size_t c = 0; c < Columns; ++c)
            std::memcpy(static_cast<float *>(out[c]) + count, static_cast<const float *>(in[c]) + m, sizeof(float));
        ++count;
    }
    return count;
}

} // namespace mvpt::simd
