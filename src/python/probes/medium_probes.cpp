// Test probes of media and volumes: a medium's free flights, transmittance and forced
// scattering along one ray; a volume's values, its majorant grid's bound at points, and the
// majorant pieces along a ray (MajorantWalk).
#include "mvpt/core/sampler.h"
#include "mvpt/render/majorant_walk.h"
#include "mvpt/render/medium.h"
#include "mvpt/render/volume.h"

#include "arrays.h"
#include "object_xml.h"
#include "scene_errors.h"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

namespace {

using mvpt_py::object_from_xml;
using mvpt_py::OutArray;
using mvpt_py::out_array;
using mvpt_py::scene_errors_as_value_errors;
using mvpt_py::Vec3Array;

Ray ray_of(Vec3Array o, Vec3Array d, size_t i, float t_max) {
    return Ray{Point3f(o(i, 0), o(i, 1), o(i, 2)), normalize(Vec3f(d(i, 0), d(i, 1), d(i, 2))), 0.f, t_max, 0.f};
}

/// A medium from a `<medium>` snippet (paths relative to the working directory).
struct MediumProbe {
    std::shared_ptr<Medium> medium;

    explicit MediumProbe(const std::string &xml) {
        medium = std::static_pointer_cast<Medium>(
            scene_errors_as_value_errors([&] { return object_from_xml(xml, "medium", "."); }));
    }

    /// n draws of sample_within over [0, t_end) along +z: rows (t, weight r, g, b); t = inf
    /// where no scattering was drawn. Raises where the medium cannot force scattering.
    OutArray sample_within(float t_end, size_t n, uint32_t seed) {
        OutArray out = out_array(n, 4);
        Sampler s(SamplerKind::Independent, seed);
        const Ray ray{Point3f(0.f), Vec3f(0.f, 0.f, 1.f), 0.f, t_end, 0.f};
        for (size_t i = 0; i < n; ++i) {
            s.start(0, 0, 0, uint32_t(i));
            MediumSample ms;
            if (!medium->sample_within(ray, t_end, s.next_1d(), ms))
                throw std::invalid_argument("this medium cannot force scattering");
            float *row = out.data() + 4 * i;
            row[0] = ms.scattered ? ms.t : INFINITY;
            for (int c = 0; c < 3; ++c) row[1 + c] = ms.scattered ? ms.weight[c] : 0.f;
        }
        return out;
    }

    /// Free flights along rays (o[i], d[i]) before a surface at t_surface, `n` per ray: rows
    /// (ray, scattered, t, weight r, g, b).
    OutArray sample(Vec3Array o, Vec3Array d, float t_surface, size_t n, uint32_t seed) {
        const size_t rays = o.shape(0);
        OutArray out = out_array(rays * n, 6);
        Sampler s(SamplerKind::Independent, seed);
        for (size_t r = 0; r < rays; ++r)
            for (size_t i = 0; i < n; ++i) {
                s.start(0, uint32_t(r), 0, uint32_t(i));
                RandomStream rs(uint64_t(seed) << 40 ^ uint64_t(r) << 24 ^ uint64_t(i));
                const MediumSample ms = medium->sample(ray_of(o, d, r, t_surface), t_surface, s.next_1d(), rs);
                float *row = out.data() + 6 * (r * n + i);
                row[0] = float(r), row[1] = ms.scattered ? 1.f : 0.f, row[2] = ms.t;
                for (int c = 0; c < 3; ++c) row[3 + c] = ms.weight[c];
            }
        return out;
    }

    /// Transmittance estimates along rays (o[i], d[i]) over [0, t), `n` per ray: (rays * n, 3).
    OutArray transmittance(Vec3Array o, Vec3Array d, float t, size_t n, uint32_t seed) {
        const size_t rays = o.shape(0);
        OutArray out = out_array(rays * n, 3);
        for (size_t r = 0; r < rays; ++r)
            for (size_t i = 0; i < n; ++i) {
                RandomStream rs(uint64_t(seed) << 40 ^ uint64_t(r) << 24 ^ uint64_t(i));
                const Spectrum tr = medium->transmittance(ray_of(o, d, r, t), t, rs);
                for (int c = 0; c < 3; ++c) out.data()[3 * (r * n + i) + c] = tr[c];
            }
        return out;
    }
};

/// A volume from a `<volume>` snippet: values, majorant grid and majorant pieces.
struct VolumeProbe {
    std::shared_ptr<Volume> volume;
    MajorantGrid grid;

    explicit VolumeProbe(const std::string &xml) {
        volume = std::static_pointer_cast<Volume>(
            scene_errors_as_value_errors([&] { return object_from_xml(xml, "volume", "."); }));
        grid = volume->majorant_grid();
    }

    /// The value at each point: (n, 3).
    OutArray eval(Vec3Array p) {
        OutArray out = out_array(p.shape(0), 3);
        for (size_t i = 0; i < p.shape(0); ++i) {
            const Spectrum v = volume->eval(Point3f(p(i, 0), p(i, 1), p(i, 2)));
            for (int c = 0; c < 3; ++c) out.data()[3 * i + c] = v[c];
        }
        return out;
    }

    /// The majorant grid's bound at each point (its cell's, or `outside`): (n,).
    OutArray cell_bound(Vec3Array p) {
        OutArray out = out_array(p.shape(0), 1);
        for (size_t i = 0; i < p.shape(0); ++i) {
            const Point3f g = grid.to_grid.point(Point3f(p(i, 0), p(i, 1), p(i, 2)));
            int c[3];
            bool inside = grid.has_cells();
            for (int a = 0; a < 3; ++a) {
                c[a] = int(std::floor(g[a]));
                inside &= c[a] >= 0 && c[a] < grid.res[a];
            }
            out.data()[i] = inside ? grid.at(c[0], c[1], c[2]) : grid.outside;
        }
        return out;
    }

    /// segment_bounds between points a and b: (lo, hi, tight).
    std::vector<float> segment_bounds(float ax, float ay, float az, float bx, float by, float bz) {
        const ValueBounds v = volume->segment_bounds(Point3f(ax, ay, az), Point3f(bx, by, bz));
        return {v.lo, v.hi, v.tight ? 1.f : 0.f};
    }

    /// The pieces along the ray (o, d) over [t0, t1): rows (t, length, bound, at).
    OutArray pieces(float ox, float oy, float oz, float dx, float dy, float dz, float t0, float t1) {
        const Ray ray{Point3f(ox, oy, oz), normalize(Vec3f(dx, dy, dz)), 0.f, t1, 0.f};
        std::vector<MajorantPiece> all;
        MajorantWalk walk(grid, *volume, 1.f, ray, t0, t1);
        for (MajorantPiece p; walk.next(p);) all.push_back(p);
        OutArray out = out_array(all.size(), 4);
        for (size_t i = 0; i < all.size(); ++i) {
            float *row = out.data() + 4 * i;
            row[0] = all[i].t, row[1] = all[i].length, row[2] = all[i].bound, row[3] = all[i].at;
        }
        return out;
    }
};

} // namespace

void bind_medium_probes(nb::module_ &m) {
    nb::class_<MediumProbe>(m, "MediumProbe")
        .def(nb::init<const std::string &>(), "xml"_a)
        .def("sample_within", &MediumProbe::sample_within, "t_end"_a, "n"_a, "seed"_a = 0)
        .def("sample", &MediumProbe::sample, "o"_a, "d"_a, "t_surface"_a, "n"_a, "seed"_a = 0)
        .def("transmittance", &MediumProbe::transmittance, "o"_a, "d"_a, "t"_a, "n"_a, "seed"_a = 0)
        .def_prop_ro("flights_given_up", [](const MediumProbe &p) { return p.medium->flights_given_up(); });
    nb::class_<VolumeProbe>(m, "VolumeProbe")
        .def(nb::init<const std::string &>(), "xml"_a)
        .def("eval", &VolumeProbe::eval, "p"_a)
        .def("cell_bound", &VolumeProbe::cell_bound, "p"_a)
        .def("segment_bounds", &VolumeProbe::segment_bounds, "ax"_a, "ay"_a, "az"_a, "bx"_a, "by"_a, "bz"_a)
        .def("pieces", &VolumeProbe::pieces, "ox"_a, "oy"_a, "oz"_a, "dx"_a, "dy"_a, "dz"_a, "t0"_a, "t1"_a)
        .def_prop_ro("resolution", [](const VolumeProbe &p) { return std::vector<int>(p.grid.res, p.grid.res + 3); });
}
