// Test probes for camera segments through media: the free flight of multi-view path tracing's
// medium vertices (transmittance.h), in a small scene given as XML, for its chi-square test.
#include "mvpt/core/sampler.h"
#include "mvpt/integrators/path/transmittance.h"
#include "mvpt/render/camera.h"
#include "mvpt/loader/load_scene.h"

#include "arrays.h"
#include "scene_errors.h"

#include <nanobind/nanobind.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/string.h>

#include <memory>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

namespace {

using mvpt_py::OutArray;
using mvpt_py::out_array;

struct SegmentProbe {
    std::unique_ptr<Scene> scene;

    /// `xml`: a whole scene; flights start in its first sensor's medium.
    explicit SegmentProbe(const std::string &xml) {
        scene = mvpt_py::scene_errors_as_value_errors([&] { return load_scene_string(xml, "."); });
    }

    /// n flights along the segment from `o` in direction `d` (unit) of length `t_max`: rows
    /// (t, density per unit length, transmittance r, g, b); t = inf where none scattered.
    OutArray flights(std::array<float, 3> o, std::array<float, 3> d, float t_max, size_t n, uint32_t seed) const {
        OutArray out = out_array(n, 5);
        Sampler s(SamplerKind::Independent, seed);
        const Ray ray{Point3f(o[0], o[1], o[2]), Vec3f(d[0], d[1], d[2]), 0.f, t_max, 0.f};
        const Medium *medium = scene->cameras().front()->medium.get();
        RayCounters counters;
        for (size_t i = 0; i < n; ++i) {
            s.start(0, 0, 0, uint32_t(i));
            const SegmentFlight f = flight_along_segment(*scene, ray, medium, s.next_1d(), counters);
            float *row = out.data() + 5 * i;
            row[0] = f.scattered ? dot(f.p - ray.o, ray.d) : INFINITY;
            row[1] = f.pdf;
            for (int c = 0; c < 3; ++c) row[2 + c] = f.tr[c];
        }
        return out;
    }
};

} // namespace

void bind_segment_probes(nb::module_ &m) {
    nb::class_<SegmentProbe>(m, "SegmentProbe")
        .def(nb::init<const std::string &>(), "xml"_a)
        .def("flights", &SegmentProbe::flights, "o"_a, "d"_a, "t_max"_a, "n"_a, "seed"_a = 0);
}
