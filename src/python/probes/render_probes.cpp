// Test probe for multi-view path tracing's first pass cut short: renders a scene given as XML
// and stops it at the first chunk boundary of its first pass (pass_loop.cpp), a cut that the
// render's thread count alone decides, for the statistical test of the cut pass's estimate.
#include "mvpt/loader/load_scene.h"
#include "mvpt/renderer/renderer.h"

#include "arrays.h"
#include "scene_errors.h"

#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <atomic>
#include <memory>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

namespace {

using mvpt_py::OutArray;
using mvpt_py::out_array;

/// For each seed: the images of every view (as (pixels, 3) arrays) of a multi-view render cut
/// after its first chunk of `threads` threads, and the share of the pass's regions it kept.
nb::list render_cut_first_pass(const std::string &xml, const std::vector<uint32_t> &seeds, int threads) {
    std::unique_ptr<Scene> scene = mvpt_py::scene_errors_as_value_errors([&] { return load_scene_string(xml, "."); });
    nb::list out;
    for (uint32_t seed : seeds) {
        RenderOptions o;
        o.method = RenderMethod::MultiView;
        o.spp = 64, o.seed = seed, o.threads = threads;
        Renderer r(*scene, o);
        std::atomic<bool> cancel{false};
        {
            nb::gil_scoped_release release;
            r.render(cancel, [&](const RenderProgress &) { cancel = true; });
        }
        nb::list images;
        for (const ViewResult &v : r.results()) {
            OutArray a = out_array(v.rgb.size() / 3, 3);
            std::copy(v.rgb.begin(), v.rgb.end(), a.data());
            images.append(a);
        }
        out.append(nb::make_tuple(images, r.stats().cut_pass_share));
    }
    return out;
}

} // namespace

void bind_render_probes(nb::module_ &m) {
    m.def("render_cut_first_pass", &render_cut_first_pass, "xml"_a, "seeds"_a, "threads"_a);
}
