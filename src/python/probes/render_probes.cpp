// Test probes for multi-view path tracing's passes cut short or thinned: render a scene given
// as XML and stop it at the first chunk boundary of its first pass (pass_loop.cpp), a cut that
// the render's thread count alone decides, or thin its last pass to a given share, for the
// statistical tests of those passes' estimates.
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

/// For each seed: the images of every view of a multi-view render of `passes` passes whose last
/// `thinned` are thinned to `share` of their native samples, the render's native samples per view
/// and the share of the last pass.
nb::list render_thinned_last_pass(const std::string &xml, const std::vector<uint32_t> &seeds, int passes, double share,
                                  int thinned) {
    std::unique_ptr<Scene> scene = mvpt_py::scene_errors_as_value_errors([&] { return load_scene_string(xml, "."); });
    nb::list out;
    for (uint32_t seed : seeds) {
        RenderOptions o;
        o.method = RenderMethod::MultiView;
        o.pass_count = passes, o.seed = seed, o.threads = 1, o.thin_last_pass = share;
        o.thin_passes = thinned;
        Renderer r(*scene, o);
        std::atomic<bool> cancel{false};
        {
            nb::gil_scoped_release release;
            r.render(cancel);
        }
        nb::list images, samples;
        for (const ViewResult &v : r.results()) {
            OutArray a = out_array(v.rgb.size() / 3, 3);
            std::copy(v.rgb.begin(), v.rgb.end(), a.data());
            images.append(a);
            samples.append(v.samples);
        }
        out.append(nb::make_tuple(images, samples, r.stats().thinned_pass_share));
    }
    return out;
}

} // namespace

void bind_render_probes(nb::module_ &m) {
    m.def("render_cut_first_pass", &render_cut_first_pass, "xml"_a, "seeds"_a, "threads"_a);
    m.def("render_thinned_last_pass", &render_thinned_last_pass, "xml"_a, "seeds"_a, "passes"_a, "share"_a,
          "thinned"_a = 1);
}
