// <immintrin.h> for the loops compiled for AVX-512 with a target attribute and picked at run
// time (cpu_has_avx512f), where GCC's auto-vectorisation cannot express them: gathers,
// compresses and transposes of the wavefront's records.
#pragma once

#if defined(__GNUC__) && defined(__x86_64__)
#define MVPT_X86_SIMD 1
// GCC 12's AVX-512 headers start masked, gathered and compressed results from an "undefined"
// vector that -Wuninitialized reports (GCC bug 105593); every lane it leaves is masked off.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#pragma GCC diagnostic pop

namespace mvpt {
/// Whether the CPU runs AVX-512F (asked once).
inline bool cpu_has_avx512f() {
    static const bool yes = __builtin_cpu_supports("avx512f");
    return yes;
}
} // namespace mvpt
#endif
