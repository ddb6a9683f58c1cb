// BSDFs written as one function that gives a pair of directions' value, density or both, whose
// lobes share the half vector, the Fresnel term and the distribution: eval, pdf, eval_pdf and
// eval_pdf_views (its textures read once for all the views) derived from it once.
#pragma once

#include "../bsdf.h"

namespace mvpt {

/// Derived provides params(si), its parameters at a hit (textures read), and
/// lobes(params, ctx, wi, wo, value, pdf), which sets *value and *pdf where they are not null.
template <class Derived> class JointLobesBsdf : public Bsdf {
public:
    Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        Spectrum value;
        self().lobes(self().params(si), ctx, wi, wo, &value, nullptr);
        return value;
    }

    float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        float p;
        self().lobes(self().params(si), ctx, wi, wo, nullptr, &p);
        return p;
    }

    std::pair<Spectrum, float> eval_pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const override {
        std::pair<Spectrum, float> out;
        self().lobes(self().params(si), ctx, wi, wo, &out.first, &out.second);
        return out;
    }

    void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        const auto q = self().params(si);
        for (size_t c = 0; c < n; ++c) self().lobes(q, ctx, wi[c], wo, &f[c], &pdf[c]);
    }

private:
    const Derived &self() const { return static_cast<const Derived &>(*this); }
};

} // namespace mvpt
