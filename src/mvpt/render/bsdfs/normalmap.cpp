// Normal-map adapter (Mitsuba 3's `normalmap`): the nested BSDF is evaluated in a shading
// frame whose normal the texture gives, n' = normalize(2 rgb - 1) in the coordinates of the
// surface's own shading frame (tangent space). Directions are rotated into that frame and back;
// a direction must lie on the same side of both frames' surfaces, else nothing is scattered.
// The tangent is the shading frame's s projected off n'. As in Mitsuba 3.9, a normal that
// faces away from the viewer is mirrored (`flip_invalid_normals`), and the value is attenuated
// by a microfacet shadowing term against the bump terminator (`use_shadowing_function`).
#include "../../core/plugin.h"
#include "../bsdf.h"
#include "../texture.h"

#include <algorithm>

namespace mvpt {

class NormalMapBsdf final : public Bsdf {
public:
    explicit NormalMapBsdf(const Properties &props) {
        const auto children = props.children_of_kind("bsdf");
        if (children.empty()) props.fail("", "normalmap needs a nested bsdf");
        if (children.size() > 1) throw SceneError(children[1]->loc, "normalmap accepts one nested bsdf");
        m_nested = std::static_pointer_cast<Bsdf>(children[0]->object);
        if (!props.has_texture("normalmap")) props.fail("normalmap", "normalmap needs a 'normalmap' texture");
        m_normalmap = get_texture(props, "normalmap", 0.5f, SpectrumUse::Unbounded);
        m_flip_invalid = props.get_bool("flip_invalid_normals", true);
        m_shadowing = props.get_bool("use_shadowing_function", true);
        m_flags = m_nested->flags();
    }

    std::pair<BsdfSample, Spectrum> sample(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, float u1,
                                           Vec2f u2) const override {
        const Frame f = frame(normal(si), wi);
        auto [bs, weight] = m_nested->sample(ctx, perturbed(si, f), f.to_local(wi), u1, u2);
        const Vec3f wo = f.to_world(bs.wo);
        if (!(bs.wo.z * wo.z > 0.f)) return {BsdfSample{}, Spectrum(0.f)};
        bs.wo = wo;
        return {bs, weight * shadowing(f.n, wo)};
    }

    Spectrum eval(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        const Frame f = frame(normal(si), wi);
        const Vec3f pwo = f.to_local(wo);
        if (!(wo.z * pwo.z > 0.f)) return Spectrum(0.f);
        return m_nested->eval(ctx, perturbed(si, f), f.to_local(wi), pwo) * shadowing(f.n, wo);
    }

    float pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi, Vec3f wo) const override {
        const Frame f = frame(normal(si), wi);
        const Vec3f pwo = f.to_local(wo);
        if (!(wo.z * pwo.z > 0.f)) return 0.f;
        return m_nested->pdf(ctx, perturbed(si, f), f.to_local(wi), pwo);
    }

    std::pair<Spectrum, float> eval_pdf(const BsdfContext &ctx, const SurfaceInteraction &si, Vec3f wi,
                                        Vec3f wo) const override {
        const Frame f = frame(normal(si), wi);
        const Vec3f pwo = f.to_local(wo);
        if (!(wo.z * pwo.z > 0.f)) return {Spectrum(0.f), 0.f};
        auto [value, p] = m_nested->eval_pdf(ctx, perturbed(si, f), f.to_local(wi), pwo);
        return {value * shadowing(f.n, wo), p};
    }

    /// The texture read once; the views in runs that share a frame (the normal is mirrored for
    /// the views it faces away from), each run rotated into it and passed to the nested BSDF's
    /// vector loop.
    void eval_pdf_views(const BsdfContext &ctx, const SurfaceInteraction &si, const Vec3f *wi, size_t n, Vec3f wo,
                        Spectrum *f, float *pdf) const override {
        const Vec3f v = normal(si);
        constexpr size_t Chunk = 64;
        Vec3f pwi[Chunk];
        for (size_t c = 0; c < n;) {
            const bool flip = flips(v, wi[c]);
            size_t end = c + 1;
            while (end < n && end - c < Chunk && flips(v, wi[end]) == flip) ++end;
            const Frame fr = frame(v, flip);
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

    float roughness(const SurfaceInteraction &si) const override { return m_nested->roughness(si); }

private:
    /// The texture's normal, 2 rgb - 1, not normalised (tangent space).
    Vec3f normal(const SurfaceInteraction &si) const {
        const Color3f c = m_normalmap->eval(si.uv);
        return {2.f * c.r - 1.f, 2.f * c.g - 1.f, 2.f * c.b - 1.f};
    }
    /// Whether the normal v faces away from the viewer wi (then it is mirrored through the
    /// shading normal, Schüssler et al. 2017's flip).
    bool flips(Vec3f v, Vec3f wi) const { return m_flip_invalid && wi.z * dot(wi, v) <= 0.f; }
    Frame frame(Vec3f v, Vec3f wi) const { return frame(v, flips(v, wi)); }
    /// The perturbed frame in the coordinates of the surface's shading frame: the normal v
    /// (mirrored if `flip`), normalised, and (1, 0, 0) projected off it as its tangent.
    static Frame frame(Vec3f v, bool flip) {
        if (flip) v = {-v.x, -v.y, v.z};
        const float l2 = squared_norm(v);
        if (!(l2 > 0.f) || !std::isfinite(l2)) return Frame();
        const Vec3f n = v * (1.f / std::sqrt(l2));
        const Vec3f s = Vec3f(1.f, 0.f, 0.f) - n * n.x;
        const float ls2 = squared_norm(s);
        if (!(ls2 > 0.f)) return Frame(n);
        const Vec3f su = s * (1.f / std::sqrt(ls2));
        return Frame(su, cross(n, su), n);
    }
    /// Estevez et al. 2019's shadowing term for the perturbed normal n and wo (both in the
    /// surface's shading frame): 2 / (1 + sqrt(1 + a^2 tan^2 wo)), a^2 = min(tan^2 n / 8, 1).
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
    std::shared_ptr<Texture> m_normalmap;
    bool m_flip_invalid = true, m_shadowing = true;
};

MVPT_REGISTER_PLUGIN("bsdf", "normalmap", [](const Properties &p, const LoadContext &) {
    return std::make_shared<NormalMapBsdf>(p);
});

} // namespace mvpt
