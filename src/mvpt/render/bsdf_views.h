// A block of sharing views' directions as arrays, for the BSDFs' vector loops over views
// (Bsdf::eval_pdf_views): the incident directions are transposed in, the lobe runs over the
// whole block (the unused lanes hold +z, a valid direction), and the values are copied out.
#pragma once

#include "../core/math.h"

#include <algorithm>
#include <cstddef>

namespace mvpt {

struct ViewBlock {
    static constexpr size_t Size = 16;
    float x[Size], y[Size], z[Size];
    float fr[Size], fg[Size], fb[Size], pdf[Size];

    /// Loads wi[0..min(n, Size)) and returns that count.
    [[gnu::always_inline]] size_t load(const Vec3f *wi, size_t n) {
        const size_t m = std::min(n, Size);
        for (size_t c = 0; c < Size; ++c) {
            const Vec3f w = c < m ? wi[c] : Vec3f(0.f, 0.f, 1.f);
            x[c] = w.x, y[c] = w.y, z[c] = w.z;
        }
        return m;
    }
    [[gnu::always_inline]] Vec3f wi(size_t c) const { return {x[c], y[c], z[c]}; }
    [[gnu::always_inline]] void set(size_t c, const Color3f &f, float p) { fr[c] = f.r, fg[c] = f.g, fb[c] = f.b, pdf[c] = p; }
    /// Stores the first m lanes' values.
    [[gnu::always_inline]] void store(Color3f *f, float *p, size_t m) const {
        for (size_t c = 0; c < m; ++c) f[c] = Color3f(fr[c], fg[c], fb[c]), p[c] = pdf[c];
    }
};

/// lobe(wi, f, pdf) for the directions wi[0..n), block by block, into f and pdf. Called from a
/// function compiled per instruction set (MVPT_MULTI_ISA), with an always-inline `lobe`: a
/// lambda that is not inlined would be compiled for the baseline instruction set alone.
template <typename Lobe>
[[gnu::always_inline]] inline void lobe_over_views(const Vec3f *wi, size_t n, Color3f *f, float *pdf, Lobe &&lobe) {
    for (size_t c0 = 0; c0 < n; c0 += ViewBlock::Size) {
        ViewBlock b;
        const size_t m = b.load(wi + c0, n - c0);
        for (size_t c = 0; c < ViewBlock::Size; ++c) {
            Color3f fc;
            float pc;
            lobe(b.wi(c), fc, pc);
            b.set(c, fc, pc);
        }
        b.store(f + c0, pdf + c0, m);
    }
}

} // namespace mvpt
