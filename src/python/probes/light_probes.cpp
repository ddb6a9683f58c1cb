// Test probes for emitters: sample_li / pdf_li / eval of one light of a small
// scene given as XML, for the chi-square and orientation tests in Python.
#include "mvpt/core/sampler.h"
#include "mvpt/render/light.h"
#include "mvpt/render/shape.h"
#include "mvpt/loader/load_scene.h"

#include "arrays.h"
#include "scene_errors.h"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/string.h>

#include <memory>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

namespace {

using mvpt_py::OutArray;
using mvpt_py::out_array;
using mvpt_py::Vec3Array;

struct LightProbe {
    std::unique_ptr<Scene> scene;
    const Light *light = nullptr;

    /// `xml`: scene elements (shapes, emitters) without the <scene> root; a
    /// sensor is added. `index` picks one of the scene's lights (scene order,
    /// area lights after the others).
    LightProbe(const std::string &xml, size_t index, const std::string &base_dir) {
        std::string doc = "<scene version=\"3.0.0\">" + xml +
                          "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"4\"/>"
                          "<integer name=\"height\" value=\"4\"/></film></sensor></scene>";
        scene = mvpt_py::scene_errors_as_value_errors([&] { return load_scene_string(doc, base_dir); });
        if (index >= scene->lights().size())
            throw std::invalid_argument("light index " + std::to_string(index) + " out of range: the snippet has " +
                                        std::to_string(scene->lights().size()) + " light(s)");
        light = scene->lights()[index].get();
    }

    /// n samples from `ref`: (directions (n,3), weights L/pdf (n,3), pdfs (n,), distances (n,)).
    nb::tuple sample_li(std::array<float, 3> ref, size_t n, uint32_t seed, float time) const {
        Point3f p(ref[0], ref[1], ref[2]);
        OutArray d = out_array(n, 3), w = out_array(n, 3), pdf = out_array(n, 1), dist = out_array(n, 1);
        Sampler s(SamplerKind::Independent, seed);
        for (size_t i = 0; i < n; ++i) {
            s.start(0, 0, 0, uint32_t(i));
            auto [ls, weight] = light->sample_li(p, s.next_2d(), time);
            for (int c = 0; c < 3; ++c) {
                d.data()[3 * i + c] = ls.d[c];
                w.data()[3 * i + c] = weight[c];
            }
            pdf.data()[i] = ls.pdf;
            dist.data()[i] = ls.dist;
        }
        return nb::make_tuple(d, w, pdf, dist);
    }

    /// Solid-angle density of `sample_li` at `ref` for each direction: for an
    /// area light the sum over every crossing of its shape along the ray
    /// (sample_li ignores occlusion); for an environment the direction's density.
    OutArray pdf_li(std::array<float, 3> ref, Vec3Array dirs) const {
        Point3f p(ref[0], ref[1], ref[2]);
        size_t n = dirs.shape(0);
        OutArray r = out_array(n, 1);
        for (size_t i = 0; i < n; ++i) {
            Vec3f d = normalize(Vec3f(dirs(i, 0), dirs(i, 1), dirs(i, 2)));
            float sum = 0.f;
            if (light->is_area()) {
                for_each_hit(p, d, [&](const SurfaceInteraction &si) { sum += light->pdf_li(p, si, d); });
            } else if (!light->is_delta()) {
                sum = light->pdf_li(p, SurfaceInteraction(), d);
            }
            r.data()[i] = sum;
        }
        return r;
    }

    /// Radiance arriving at `ref` from each direction: the first crossing of
    /// an area light's shape (ignoring other shapes), or the environment.
    OutArray eval(std::array<float, 3> ref, Vec3Array dirs) const {
        Point3f p(ref[0], ref[1], ref[2]);
        size_t n = dirs.shape(0);
        OutArray r = out_array(n, 3);
        for (size_t i = 0; i < n; ++i) {
            Vec3f d = normalize(Vec3f(dirs(i, 0), dirs(i, 1), dirs(i, 2)));
            Spectrum L;
            if (light->is_area()) {
                bool first = true;
                for_each_hit(p, d, [&](const SurfaceInteraction &si) {
                    if (first) L = light->eval(si, -d);
                    first = false;
                });
            } else {
                L = light->eval_environment(d);
            }
            for (int c = 0; c < 3; ++c) r.data()[3 * i + c] = L[c];
        }
        return r;
    }

    /// Calls `f` for every intersection of the ray (p, d) with the light's shape.
    template <typename F> void for_each_hit(Point3f p, Vec3f d, F f) const {
        Ray ray{p, d, 0.f, Infinity, 0.f};
        for (int guard = 0; guard < 1024; ++guard) {
            SurfaceInteraction si;
            if (!scene->intersect(ray, si)) return;
            if (si.shape == light->shape()) f(si);
            ray.o = si.offset_p(d);
        }
    }
};

} // namespace

void bind_light_probes(nb::module_ &m) {
    nb::class_<LightProbe>(m, "LightProbe", "One light of a scene snippet (shapes/emitters XML), for tests")
        .def(nb::init<const std::string &, size_t, const std::string &>(), "xml"_a, "index"_a = 0, "base_dir"_a = ".")
        .def("sample_li", &LightProbe::sample_li, "ref"_a, "n"_a, "seed"_a = 0, "time"_a = 0.f,
             "n samples of sample_li at point ref: (directions (n,3), weights L/pdf (n,3), pdfs (n,), distances (n,))")
        .def("pdf_li", &LightProbe::pdf_li, "ref"_a, "dirs"_a,
             "Solid-angle density of sample_li at ref for unit directions dirs (m,3), occlusion ignored")
        .def("eval", &LightProbe::eval, "ref"_a, "dirs"_a, "Radiance arriving at ref from each direction (m,3)")
        .def_prop_ro("flags", [](const LightProbe &p) { return p.light->flags(); })
        .def_prop_ro("light_count", [](const LightProbe &p) { return p.scene->lights().size(); })
        .def_prop_ro("is_delta", [](const LightProbe &p) { return p.light->is_delta(); })
        .def_prop_ro("is_environment", [](const LightProbe &p) { return p.light->is_environment(); });
}
