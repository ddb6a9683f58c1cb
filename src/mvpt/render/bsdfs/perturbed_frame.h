// The adapters that evaluate a nested BSDF in a perturbed shading frame (Mitsuba 3.9's
// `normalmap` and `bumpmap`): a normal n' and a tangent hint in the coordinates of the
// surface's own shading frame give the frame (n' normalised, the hint projected off it);
// directions are rotated into it and back, and a direction must lie on the same side of both
// frames' surfaces, else nothing is scattered. A normal that faces away from the viewer is
// mirrored through the shading normal (`flip_invalid_normals`, Schüssler et al. 2017), and the
// value is attenuated by Estevez et al. 2019's shadowing term against the bump terminator
// (`use_shadowing_function`).
#pragma once

#include "../bsdf.h"

#include <algorithm>

namespace mvpt {

class PerturbedFrameBsdf : public Bsdf {
public:
    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const final {
        const Frame f = frame(perturbation(si), wi);
        auto [bs, weight] = m_nested->sample(ctx, perturbed(si, f), f.to_local(wi), u1, u2);
        const Vec3f wo = f.to_world(bs.wo);
        if (!(bs.wo.z * wo.z > 0.f)) return {BsdfSample{}, Spectrum(0.f)};
        bs.wo = wo;
        return {bs, weight * shadowing(f.n, wo)};
    }

    Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const final {
        const Frame f = frame(perturbation(si), wi);
        const Vec3f pwo = f.to_local(wo);
        if (!(wo.z * pwo.z > 0.f)) return Spectrum(0.f);
        return m_nested->eval(ctx, perturbed(si, f), f.to_local(wi), pwo) * shadowing(f.n, wo);
    }

    float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const final {
        const Frame f = frame(perturbation(si), wi);
        const Vec3f pwo = f.to_local(wo);
        if (!(wo.z * pwo.z > 0.f)) return 0.f;
        return m_nested->pdf(ctx, perturbed(si, f), f.to_local(wi), pwo);
    }

    std::pair<Spectrum, float> eval_pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const final {
        const Frame f = frame(perturbation(si), wi);
        const Vec3f pwo = f.to_local(wo);
        if (!(wo.z * pwo.z > 0.f)) return {Spectrum(0.f), 0.f};
        auto [value, p] = m_nested->eval_pdf(ctx, perturbed(si, f), f.to_local(wi), pwo);
        return {value * shadowing(f.n, wo), p};
    }

    /// The perturbation found once; the views in runs that share a frame (the normal is
    /// mirrored for the views it faces away from), each run rotated into it and passed to the
    /// nested BSDF's vector loop.
    void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const final {
        const Perturbation p = perturbation(si);
        constexpr size_t Chunk = 64;
        Vec3f pwi[Chunk];
        for (size_t c = 0; c < n;) {
            const bool flip = flips(p.n, wi[c]);
            size_t end = c + 1;
            while (end < n && end - c < Chunk && flips(p.n, wi[end]) == flip) ++end;
            const Frame fr = frame(p, flip);
            const Vec3f pwo = fr.to_local(wo);
            if (wo.z * pwo.z > 0.f) {
                for (size_t k = c; k < end; ++k) pwi[k - c] = fr.to_local(wi[k]);
                m_nested->eval_pdf_views(ctx, perturbed(si, fr), pwi, end - c, pwo, f + c, pdf + c);
                const float g = shadowing(fr.n, wo);
                for (size_t k = c; k < end; ++k) f[k] = f[k] * g;
            } else {
                std::fill(f + c, f + end, Spectrum(0.f));
                std::fill(pdf + c, pdf + end, 0.f);
            }
            c = end;
        }
    }

    std::optional<float> delta_probability(const SurfaceInteraction &si, Vec3f wi) const final {
        const Frame f = frame(perturbation(si), wi);
        return m_nested->delta_probability(perturbed(si, f), f.to_local(wi));
    }

    float roughness(const SurfaceInteraction &si) const final { return m_nested->roughness(si); }

protected:
    /// The nested BSDF (the only bsdf child) and the two switches; `kind` names the plugin.
    PerturbedFrameBsdf(const Properties &props, const char *kind) {
        const auto children = props.children_of_kind("bsdf");
        if (children.empty()) throw SceneError(props.loc(), std::string(kind) + " needs a nested bsdf");
        if (children.size() > 1) throw SceneError(children[1]->loc, std::string(kind) + " accepts one nested bsdf");
        m_nested = std::static_pointer_cast<Bsdf>(children[0]->object);
        m_flip_invalid = props.get_bool("flip_invalid_normals", true);
        m_shadowing = props.get_bool("use_shadowing_function", true);
        m_flags = m_nested->flags();
    }

    /// The perturbed normal (any length; zero or not finite: none) and the tangent hint, in the
    /// coordinates of the surface's shading frame.
    struct Perturbation {
        Vec3f n{0.f, 0.f, 1.f}, s{1.f, 0.f, 0.f};
    };
    virtual Perturbation perturbation(const SurfaceInteraction &si) const = 0;

private:
    bool flips(Vec3f n, Vec3f wi) const { return m_flip_invalid && wi.z * dot(wi, n) <= 0.f; }
    Frame frame(const Perturbation &p, Vec3f wi) const { return frame(p, flips(p.n, wi)); }
    /// The frame of p (its normal mirrored if `flip`); the unperturbed one where p has no normal.
    static Frame frame(const Perturbation &p, bool flip) {
        const Vec3f v = flip ? Vec3f(-p.n.x, -p.n.y, p.n.z) : p.n;
        const float l2 = squared_norm(v);
        if (!(l2 > 0.f) || !std::isfinite(l2)) return Frame();
        const Vec3f n = v * (1.f / std::sqrt(l2));
        const Vec3f s = p.s - n * dot(n, p.s);
        const float ls2 = squared_norm(s);
        if (!(ls2 > 0.f) || !std::isfinite(ls2)) return Frame(n);
        const Vec3f su = s * (1.f / std::sqrt(ls2));
        return Frame(su, cross(n, su), n);
    }
    /// The shadowing term for the perturbed normal n and wo (both in the surface's shading
    /// frame): 2 / (1 + sqrt(1 + a^2 tan^2 wo)), a^2 = min(tan^2 n / 8, 1).
    float shadowing(Vec3f n, Vec3f wo) const {
        if (!m_shadowing) return 1.f;
        const float a2 = std::min(0.125f * Frame::tan2_theta(n), 1.f);
        return 2.f / (1.f + std::sqrt(1.f + a2 * Frame::tan2_theta(wo)));
    }
    /// `si` as the nested BSDF sees it: the perturbed shading frame (world space), wi in it.
    static SurfaceInteraction perturbed(const SurfaceInteraction &si, const Frame &f) {
        SurfaceInteraction p = si;
        p.sh_frame = Frame(si.to_world(f.s), si.to_world(f.t), si.to_world(f.n));
        p.wi = f.to_local(si.wi);
        return p;
    }

    std::shared_ptr<Bsdf> m_nested;
    bool m_flip_invalid = true, m_shadowing = true;
};

} // namespace mvpt
