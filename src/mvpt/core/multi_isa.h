// Functions compiled once per x86-64 instruction-set level (AVX-512, AVX2, baseline) and
// picked when the library loads (GCC target_clones), for the loops over many views. The
// build turns off FMA contraction, so every clone rounds exactly like the baseline one and
// images do not depend on the CPU.
#pragma once

#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
#define MVPT_MULTI_ISA __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define MVPT_MULTI_ISA
#endif
