// Test probes: evaluate and sample single plugins (BSDFs) from Python, for
// the chi-square and energy tests.
#include "mvpt/core/sampler.h"
#include "mvpt/render/bsdf.h"
#include "mvpt/scene/xml_parser.h"

#include "arrays.h"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

namespace {

using mvpt_py::OutArray;
using mvpt_py::out_array;
using mvpt_py::Vec3Array;

/// Instantiate the one top-level object of `kind` declared in a scene snippet.
std::shared_ptr<Object> object_from_xml(const std::string &xml, const std::string &kind, const std::string &base_dir) {
    XmlNode root = parse_scene_string("<scene version=\"3.0.0\">" + xml + "</scene>", base_dir, {});
    SceneTree tree = instantiate_scene(root, base_dir);
    for (auto &c : tree.props.children())
        if (c.kind == kind) return c.object;
    throw std::invalid_argument("the XML snippet declares no " + kind);
}

struct BsdfProbe {
    std::shared_ptr<Bsdf> bsdf;
    SurfaceInteraction si;

    BsdfProbe(const std::string &xml, float u, float v, const std::string &base_dir) {
        bsdf = std::static_pointer_cast<Bsdf>(object_from_xml(xml, "bsdf", base_dir));
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

    OutArray pdf(float wx, float wy, float wz, Vec3Array wo) {
        size_t n = wo.shape(0);
        OutArray r = out_array(n, 1);
        for (size_t i = 0; i < n; ++i) r.data()[i] = bsdf->pdf({}, si, Vec3f(wx, wy, wz), Vec3f(wo(i, 0), wo(i, 1), wo(i, 2)));
        return r;
    }
};

} // namespace

void bind_probes(nb::module_ &m) {
    nb::class_<BsdfProbe>(m, "BsdfProbe")
        .def(nb::init<const std::string &, float, float, const std::string &>(), "xml"_a, "u"_a = 0.5f, "v"_a = 0.5f,
             "base_dir"_a = ".")
        .def("sample", &BsdfProbe::sample, "wx"_a, "wy"_a, "wz"_a, "n"_a, "seed"_a = 0, "importance"_a = false)
        .def("sample_u", &BsdfProbe::sample_u, "wx"_a, "wy"_a, "wz"_a, "u"_a)
        .def("roughness", &BsdfProbe::roughness, "wx"_a = 0.f, "wy"_a = 0.f, "wz"_a = 1.f)
        .def("eval", &BsdfProbe::eval, "wx"_a, "wy"_a, "wz"_a, "wo"_a)
        .def("pdf", &BsdfProbe::pdf, "wx"_a, "wy"_a, "wz"_a, "wo"_a)
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
