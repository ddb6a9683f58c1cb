// Mitsuba 3's `direct` integrator: emitters seen directly, plus light that reaches the first
// surface straight from an emitter, estimated with `emitter_samples` emitter samples and
// `bsdf_samples` BSDF samples (`shading_samples` sets both) combined by the power heuristic
// over the two techniques' sample counts [Veach 1997, §9.2]. No indirect light.
#include "path.h"

#include "../../render/bsdf.h"
#include "../../render/light.h"
#include "../../render/shape.h"
#include "../../core/plugin.h"
#include "../../accel/scene.h"

namespace mvpt {

namespace {

class DirectIntegrator final : public Integrator {
public:
    DirectIntegrator(int emitter_samples, int bsdf_samples, bool hide_emitters)
        : m_emitter_samples(emitter_samples), m_bsdf_samples(bsdf_samples), m_hide_emitters(hide_emitters) {
        const float sum = float(emitter_samples + bsdf_samples);
        m_frac_lum = float(emitter_samples) / sum, m_frac_bsdf = float(bsdf_samples) / sum;
    }

    Spectrum li(const Scene &scene, const Ray &ray, Sampler &sampler, RayCounters &counters) const override {
        sampler.set_dimension(DimCameraEnd);
        SurfaceInteraction si;
        ++counters.rays;
        const bool hit = scene.intersect(ray, si);
        Spectrum result(0.f);
        if (const Light *emitter = hit ? si.shape->emitter.get() : scene.environment(); emitter && !m_hide_emitters)
            result += hit ? emitter->eval(si, -ray.d) : emitter->eval_environment_pdf(ray.o, si, ray.d, nullptr);
        if (!hit) return result;
        const Bsdf &bsdf = *si.shape->bsdf;
        si.wi = si.to_local(-ray.d);
        if (bsdf.has_smooth())
            for (int i = 0; i < m_emitter_samples; ++i) result += emitter_sample(scene, si, bsdf, sampler, counters);
        for (int i = 0; i < m_bsdf_samples; ++i) result += bsdf_sample(scene, si, bsdf, sampler, counters);
        return result;
    }

    std::string name() const override { return "direct"; }

private:
    /// One emitter sample, weighted against the BSDF technique.
    Spectrum emitter_sample(const Scene &scene, const SurfaceInteraction &si, const Bsdf &bsdf, Sampler &sampler,
                            RayCounters &counters) const {
        const auto &lights = scene.lights();
        const float u_select = sampler.next_1d();
        const Vec2f u_light = sampler.next_2d();
        if (lights.empty()) return Spectrum(0.f);
        const Light &light = *lights[uniform_emitter_index(u_select, lights.size())];
        auto [ls, weight] = light.sample_li(si.p, u_light, si.time);
        if (weight.is_black()) return Spectrum(0.f);
        auto [f, pdf] = bsdf.eval_pdf({}, si, si.wi, si.to_local(ls.d));
        if (f.is_black()) return Spectrum(0.f);
        Ray shadow = std::isinf(ls.dist) ? si.spawn_ray(ls.d) : si.spawn_ray_to(ls.p);
        ++counters.shadow_rays;
        if (scene.occluded(shadow)) return Spectrum(0.f);
        const float mis = ls.delta ? 1.f
                                   : mis_power(emitter_pdf_from(scene, &light, ls.pdf) * m_frac_lum, pdf * m_frac_bsdf) /
                                         float(m_emitter_samples);
        return f * weight * (float(lights.size()) * mis);
    }

    /// One BSDF sample that finds an emitter, weighted against the emitter technique.
    Spectrum bsdf_sample(const Scene &scene, const SurfaceInteraction &si, const Bsdf &bsdf, Sampler &sampler,
                         RayCounters &counters) const {
        const float u_lobe = sampler.next_1d();
        auto [bs, weight] = bsdf.sample({}, si, si.wi, u_lobe, sampler.next_2d());
        if (weight.is_black()) return Spectrum(0.f);
        const Ray ray = si.spawn_ray(si.to_world(bs.wo));
        SurfaceInteraction hit_si;
        ++counters.rays;
        const bool hit = scene.intersect(ray, hit_si);
        const Light *emitter = hit ? hit_si.shape->emitter.get() : scene.environment();
        if (!emitter) return Spectrum(0.f);
        const bool delta = (bs.sampled_type & BsdfDelta) != 0;
        float env_pdf = 0.f;
        const Spectrum le = hit ? emitter->eval(hit_si, -ray.d)
                                : emitter->eval_environment_pdf(si.p, hit_si, ray.d, delta ? nullptr : &env_pdf);
        if (le.is_black()) return Spectrum(0.f);
        float w = 1.f;
        if (!delta) {
            const float em_pdf = hit ? emitter_pdf(scene, emitter, si.p, hit_si, ray.d) : emitter_pdf_from(scene, emitter, env_pdf);
            w = mis_power(bs.pdf * m_frac_bsdf, em_pdf * m_frac_lum);
        }
        return weight * le * (w / float(m_bsdf_samples));
    }

    int m_emitter_samples, m_bsdf_samples;
    bool m_hide_emitters;
    float m_frac_lum = 0.5f, m_frac_bsdf = 0.5f;
};

std::shared_ptr<Object> make_direct(const Properties &props, const LoadContext &) {
    if (props.has("shading_samples") && (props.has("emitter_samples") || props.has("bsdf_samples")))
        props.fail("shading_samples", "give shading_samples or emitter_samples/bsdf_samples, not both");
    const int shading = int(props.get_int_in("shading_samples", 1, 0, 1 << 16));
    const int emitter = int(props.get_int_in("emitter_samples", shading, 0, 1 << 16));
    const int bsdf = int(props.get_int_in("bsdf_samples", shading, 0, 1 << 16));
    if (emitter + bsdf == 0) props.fail("emitter_samples", "the direct integrator needs at least one emitter or BSDF sample");
    return std::make_shared<DirectIntegrator>(emitter, bsdf, props.get_bool("hide_emitters", false));
}

} // namespace

MVPT_REGISTER_PLUGIN("integrator", "direct", make_direct);

} // namespace mvpt
