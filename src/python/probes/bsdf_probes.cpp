// Test probes: evaluate and sample single plugins (BSDFs) from Python, for
// the chi-square and energy tests.
#include "mvpt/core/sampler.h"
#include "mvpt/integrators/multiview/mv_mixture.h"
#include "mvpt/integrators/multiview/mv_selection.h"
#include "mvpt/render/bsdf.h"
#include "mvpt/render/phase.h"
#include "mvpt/loader/xml_parser.h"

#include "arrays.h"
#include "object_xml.h"
#include "scene_errors.h"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/array.h>

#include <array>
#include <vector>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

std::shared_ptr<Object> mvpt_py::object_from_xml(const std::string &xml, const std::string &kind, const std::string &base_dir) {
    XmlNode root = parse_scene_string("<scene version=\"3.0.0\">" + xml + "</scene>", base_dir, {});
    SceneTree tree = instantiate_scene(root, base_dir);
    for (auto &c : tree.props.children())
        if (c.kind == kind) return c.object;
    throw std::invalid_argument("the XML snippet declares no " + kind);
}

namespace {

using mvpt_py::object_from_xml;
using mvpt_py::OutArray;
using mvpt_py::scene_errors_as_value_errors;
using mvpt_py::out_array;
using mvpt_py::Vec3Array;

struct BsdfProbe {
    std::shared_ptr<Bsdf> bsdf;
    SurfaceInteraction si;

    BsdfProbe(const std::string &xml, float u, float v, const std::string &base_dir) {
        bsdf = std::static_pointer_cast<Bsdf>(
            scene_errors_as_value_errors([&] { return object_from_xml(xml, "bsdf", base_dir); }));
        si.uv = {u, v};
        si.n = {0, 0, 1};
        si.sh_frame = Frame();
    }

    /// n samples for direction wi: (wo, weight, pdf, sampled_type) arrays (importance: adjoint transport mode).
    nb::tuple sample(float wx, float wy, float wz, size_t n, uint32_t seed, bool importance) {
        Vec3f wi(wx, wy, wz);
        OutArray wo = out_array(n, 3), w = out_array(n, 3), pdf = out_array(n, 1), type = out_array(n, 1);
        Sampler s(SamplerKind::Independent, seed);
        BsdfContext ctx;
        if (importance) ctx.mode = TransportMode::Importance;
        for (size_t i = 0; i < n; ++i) {
            s.start(0, 0, 0, uint32_t(i));
            float u1 = s.next_1d();
            Vec2f u2 = s.next_2d();
            auto [bs, weight] = bsdf->sample(ctx, si, wi, u1, u2);
            for (int c = 0; c < 3; ++c) {
                wo.data()[3 * i + c] = bs.wo[c];
                w.data()[3 * i + c] = weight[c];
            }
            pdf.data()[i] = bs.pdf;
            type.data()[i] = float(bs.sampled_type);
        }
        return nb::make_tuple(wo, w, pdf, type);
    }

    /// Samples with given random numbers u (n, 3) = (u1, u2.x, u2.y): (wo, weight, pdf, sampled_type).
    nb::tuple sample_u(float wx, float wy, float wz, Vec3Array u) {
        size_t n = u.shape(0);
        Vec3f wi(wx, wy, wz);
        OutArray wo = out_array(n, 3), w = out_array(n, 3), pdf = out_array(n, 1), type = out_array(n, 1);
        BsdfContext ctx;
        for (size_t i = 0; i < n; ++i) {
            auto [bs, weight] = bsdf->sample(ctx, si, wi, u(i, 0), Vec2f(u(i, 1), u(i, 2)));
            for (int c = 0; c < 3; ++c) {
                wo.data()[3 * i + c] = bs.wo[c];
                w.data()[3 * i + c] = weight[c];
            }
            pdf.data()[i] = bs.pdf;
            type.data()[i] = float(bs.sampled_type);
        }
        return nb::make_tuple(wo, w, pdf, type);
    }

    /// The probability that sampling draws a delta lobe for wi (-1: the BSDF cannot tell).
    float delta_probability(float wx, float wy, float wz) {
        return bsdf->delta_probability(si, Vec3f(wx, wy, wz)).value_or(-1.f);
    }

    /// n directions from the lobe mixture of multi-view path tracing for views seen from
    /// `wis` (m, 3): (wo, mixture pdf, sampled_type, view, weight) arrays (weight: the
    /// MixtureSample's, f/pdf of the view's own lobe, or of its delta event over |S|).
    nb::tuple mixture_sample(Vec3Array wis, size_t n, uint32_t seed) {
        std::vector<Vec3f> wi(wis.shape(0));
        for (size_t c = 0; c < wi.size(); ++c) wi[c] = Vec3f(wis(c, 0), wis(c, 1), wis(c, 2));
        OutArray wo = out_array(n, 3), pdf = out_array(n, 1), type = out_array(n, 1), view = out_array(n, 1);
        OutArray w = out_array(n, 3);
        std::vector<float> p_delta(wi.size()), smooth_scale(wi.size());
        const LobeClasses classes = lobe_classes(*bsdf, si, wi.data(), wi.size(), p_delta.data(), smooth_scale.data());
        Sampler s(SamplerKind::Independent, seed);
        for (size_t i = 0; i < n; ++i) {
            s.start(0, 0, 0, uint32_t(i));
            float u_view = s.next_1d(), u1 = s.next_1d();
            Vec2f u2 = s.next_2d();
            MixtureSample ms = sample_lobe_mixture(*bsdf, si, wi.data(), wi.size(), classes, u_view, u1, u2);
            for (int c = 0; c < 3; ++c) wo.data()[3 * i + c] = ms.bs.wo[c], w.data()[3 * i + c] = ms.weight[c];
            pdf.data()[i] = ms.weight.is_black() ? 0.f : ms.pdf;
            type.data()[i] = float(ms.bs.sampled_type);
            view.data()[i] = float(ms.view);
        }
        return nb::make_tuple(wo, pdf, type, view, w);
    }

    /// The mixture density of directions `wo` (n, 3) for views seen from `wis` (m, 3).
    OutArray mixture_pdf(Vec3Array wis, Vec3Array wo) {
        std::vector<Vec3f> wi(wis.shape(0));
        for (size_t c = 0; c < wi.size(); ++c) wi[c] = Vec3f(wis(c, 0), wis(c, 1), wis(c, 2));
        std::vector<float> p_delta(wi.size()), smooth_scale(wi.size());
        const LobeClasses classes = lobe_classes(*bsdf, si, wi.data(), wi.size(), p_delta.data(), smooth_scale.data());
        size_t n = wo.shape(0);
        OutArray r = out_array(n, 1);
        for (size_t i = 0; i < n; ++i)
            r.data()[i] =
                lobe_mixture_pdf(*bsdf, si, wi.data(), wi.size(), classes, Vec3f(wo(i, 0), wo(i, 1), wo(i, 2)));
        return r;
    }

    /// Material similarity s_M of two views' lobes (design doc §6), peak-ratio or Monte Carlo TV.
    float material_similarity(std::array<float, 3> a, std::array<float, 3> b, bool monte_carlo) {
        ViewLobe la = view_lobe(*bsdf, si, Vec3f(a[0], a[1], a[2])), lb = view_lobe(*bsdf, si, Vec3f(b[0], b[1], b[2]));
        return mvpt::material_similarity(*bsdf, si, la, lb,
                                         monte_carlo ? MvTotalVariation::MonteCarlo : MvTotalVariation::PeakRatio);
    }

    /// Bsdf::roughness at the probe's uv, seen from direction wi.
    float roughness(float wx, float wy, float wz) {
        si.wi = Vec3f(wx, wy, wz);
        return bsdf->roughness(si);
    }

    OutArray eval(float wx, float wy, float wz, Vec3Array wo) {
        size_t n = wo.shape(0);
        OutArray r = out_array(n, 3);
        for (size_t i = 0; i < n; ++i) {
            Vec3f o(wo(i, 0), wo(i, 1), wo(i, 2));
            Spectrum f = bsdf->eval({}, si, Vec3f(wx, wy, wz), o);
            for (int c = 0; c < 3; ++c) r.data()[3 * i + c] = f[c];
        }
        return r;
    }

    /// Bsdf::eval_pdf: (f (n, 3), pdf (n, 1)).
    nb::tuple eval_pdf(float wx, float wy, float wz, Vec3Array wo) {
        size_t n = wo.shape(0);
        OutArray f = out_array(n, 3), p = out_array(n, 1);
        for (size_t i = 0; i < n; ++i) {
            auto [fi, pi] = bsdf->eval_pdf({}, si, Vec3f(wx, wy, wz), Vec3f(wo(i, 0), wo(i, 1), wo(i, 2)));
            for (int c = 0; c < 3; ++c) f.data()[3 * i + c] = fi[c];
            p.data()[i] = pi;
        }
        return nb::make_tuple(f, p);
    }

    /// Bsdf::eval_pdf_views for the viewers `wis` (m, 3) at each wo: (f (n, m, 3), pdf (n, m)).
    nb::tuple eval_pdf_views(Vec3Array wis, Vec3Array wo) {
        size_t n = wo.shape(0), m = wis.shape(0);
        std::vector<Vec3f> wi(m);
        for (size_t c = 0; c < m; ++c) wi[c] = Vec3f(wis(c, 0), wis(c, 1), wis(c, 2));
        OutArray f = out_array(n, m * 3), p = out_array(n, m);
        std::vector<Spectrum> fc(m);
        std::vector<float> pc(m);
        for (size_t i = 0; i < n; ++i) {
            bsdf->eval_pdf_views({}, si, wi.data(), m, Vec3f(wo(i, 0), wo(i, 1), wo(i, 2)), fc.data(), pc.data());
            for (size_t c = 0; c < m; ++c) {
                for (int k = 0; k < 3; ++k) f.data()[(i * m + c) * 3 + k] = fc[c][k];
                p.data()[i * m + c] = pc[c];
            }
        }
        return nb::make_tuple(f, p);
    }

    OutArray pdf(float wx, float wy, float wz, Vec3Array wo) {
        size_t n = wo.shape(0);
        OutArray r = out_array(n, 1);
        for (size_t i = 0; i < n; ++i) r.data()[i] = bsdf->pdf({}, si, Vec3f(wx, wy, wz), Vec3f(wo(i, 0), wo(i, 1), wo(i, 2)));
        return r;
    }
};

/// A phase function from a `<phase>` snippet: samples and densities for the chi-square tests.
struct PhaseProbe {
    std::shared_ptr<PhaseFunction> phase;

    explicit PhaseProbe(const std::string &xml) {
        phase = std::static_pointer_cast<PhaseFunction>(
            scene_errors_as_value_errors([&] { return object_from_xml(xml, "phase", "."); }));
    }

    /// n directions for wi (n, 3).
    OutArray sample(float wx, float wy, float wz, size_t n, uint32_t seed) {
        OutArray wo = out_array(n, 3);
        Sampler s(SamplerKind::Independent, seed);
        for (size_t i = 0; i < n; ++i) {
            s.start(0, 0, 0, uint32_t(i));
            Vec3f d = phase->sample(Vec3f(wx, wy, wz), s.next_2d());
            for (int c = 0; c < 3; ++c) wo.data()[3 * i + c] = d[c];
        }
        return wo;
    }

    OutArray eval(float wx, float wy, float wz, Vec3Array wo) {
        size_t n = wo.shape(0);
        OutArray r = out_array(n, 1);
        for (size_t i = 0; i < n; ++i) r.data()[i] = phase->eval(Vec3f(wx, wy, wz), Vec3f(wo(i, 0), wo(i, 1), wo(i, 2)));
        return r;
    }
};

} // namespace

void bind_probes(nb::module_ &m) {
    nb::class_<PhaseProbe>(m, "PhaseProbe")
        .def(nb::init<const std::string &>(), "xml"_a)
        .def("sample", &PhaseProbe::sample, "wx"_a, "wy"_a, "wz"_a, "n"_a, "seed"_a = 0)
        .def("eval", &PhaseProbe::eval, "wx"_a, "wy"_a, "wz"_a, "wo"_a);
    nb::class_<BsdfProbe>(m, "BsdfProbe")
        .def(nb::init<const std::string &, float, float, const std::string &>(), "xml"_a, "u"_a = 0.5f, "v"_a = 0.5f,
             "base_dir"_a = ".")
        .def("sample", &BsdfProbe::sample, "wx"_a, "wy"_a, "wz"_a, "n"_a, "seed"_a = 0, "importance"_a = false)
        .def("sample_u", &BsdfProbe::sample_u, "wx"_a, "wy"_a, "wz"_a, "u"_a)
        .def("roughness", &BsdfProbe::roughness, "wx"_a = 0.f, "wy"_a = 0.f, "wz"_a = 1.f)
        .def("eval", &BsdfProbe::eval, "wx"_a, "wy"_a, "wz"_a, "wo"_a)
        .def("pdf", &BsdfProbe::pdf, "wx"_a, "wy"_a, "wz"_a, "wo"_a)
        .def("eval_pdf", &BsdfProbe::eval_pdf, "wx"_a, "wy"_a, "wz"_a, "wo"_a)
        .def("eval_pdf_views", &BsdfProbe::eval_pdf_views, "wis"_a, "wo"_a)
        .def("mixture_sample", &BsdfProbe::mixture_sample, "wis"_a, "n"_a, "seed"_a = 0)
        .def("mixture_pdf", &BsdfProbe::mixture_pdf, "wis"_a, "wo"_a)
        .def("delta_probability", &BsdfProbe::delta_probability, "wx"_a, "wy"_a, "wz"_a)
        .def("material_similarity", &BsdfProbe::material_similarity, "wi_a"_a, "wi_b"_a, "monte_carlo"_a = false)
        .def_prop_ro("flags", [](const BsdfProbe &p) { return p.bsdf->flags(); })
        .def_prop_ro_static("flag_values", [](nb::handle) {
            nb::dict d;
            d["null"] = uint32_t(BsdfNull);
            d["diffuse_reflection"] = uint32_t(BsdfDiffuseReflection);
            d["diffuse_transmission"] = uint32_t(BsdfDiffuseTransmission);
            d["glossy_reflection"] = uint32_t(BsdfGlossyReflection);
            d["glossy_transmission"] = uint32_t(BsdfGlossyTransmission);
            d["delta_reflection"] = uint32_t(BsdfDeltaReflection);
            d["delta_transmission"] = uint32_t(BsdfDeltaTransmission);
            d["delta"] = uint32_t(BsdfDelta);
            return d;
        });
}
