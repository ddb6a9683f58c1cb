// The `mvpt._core` extension: scene loading, a background render job that
// Python polls (GIL released while waiting), NumPy images out, image writers.
#include "mvpt/io/image_io.h"
#include "mvpt/io/multiview_exr.h"
#include "mvpt/renderer/render_state.h"
#include "mvpt/renderer/renderer.h"
#include "mvpt/loader/load_scene.h"
#include "mvpt/integrators/multiview/mv_candidates.h"
#include "mvpt/integrators/multiview/mvpath.h"
#include "mvpt/integrators/path/path.h"
#include "mvpt/integrators/path/volpath.h"
#include "mvpt/render/camera_projection.h"
#include "load_job.h"
#include "signals_at_exit.h"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/map.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <condition_variable>
#include <mutex>
#include <thread>

namespace nb = nanobind;
using namespace nb::literals;
using namespace mvpt;

namespace {

using FloatArray = nb::ndarray<nb::numpy, float>;

FloatArray make_array(std::vector<float> data, std::initializer_list<size_t> shape) {
    auto *heap = new std::vector<float>(std::move(data));
    nb::capsule owner(heap, [](void *p) noexcept { delete static_cast<std::vector<float> *>(p); });
    std::vector<size_t> sh(shape);
    return FloatArray(heap->data(), sh.size(), sh.data(), owner);
}

/// Multi-view statistics (design doc §9) as a dict; rejections are keyed by test.
nb::dict mv_stats_dict(const MvViewStats &m) {
    nb::dict d;
    d["native_samples"] = m.native;
    d["contributions"] = m.received;
    d["shifts_tried"] = m.tried;
    static const char *names[] = {"time", "orientation", "image", "bsdf", "visibility", "selection"};
    nb::dict rej;
    for (int i = 0; i < int(ShiftTest::Count); ++i) rej[names[i]] = m.rejected[i];
    d["rejected"] = rej;
    d["mean_sharing"] = m.native ? double(m.sharing) / double(m.native) : 0.0;
    d["rays_per_native_sample"] = m.native ? double(m.rays) / double(m.native) : 0.0;
    return d;
}

/// A render running on its own thread; Python polls it so that Ctrl-C and
/// progress bars stay responsive.
class RenderJob {
public:
    RenderJob(std::shared_ptr<Scene> scene, RenderOptions opts)
        : m_scene(std::move(scene)), m_renderer(*m_scene, std::move(opts)) {}
    ~RenderJob() { m_cancel = true; } // (m_job, the last member, then joins the thread)

    void start() {
        m_job.start([this] {
            try {
                m_renderer.render(m_cancel, [this](const RenderProgress &p) {
                    std::lock_guard<std::mutex> lock(m_mutex);
                    m_progress = p;
                });
            } catch (const StateError &e) {
                std::lock_guard<std::mutex> lock(m_mutex);
                m_error = e.what();
                m_state_error = true;
            } catch (const std::exception &e) {
                std::lock_guard<std::mutex> lock(m_mutex);
                m_error = e.what();
            }
        }, "render job");
    }

    /// Wait up to `timeout` seconds; true when finished.
    bool wait(double timeout) { return m_job.wait(timeout); }

    void cancel() { m_cancel = true; }

    /// Instead of start(): merges the state files of disjoint ranges (Renderer::merge).
    void merge(const std::vector<std::string> &paths, bool develop) {
        if (m_job.started()) throw std::runtime_error("render job already started");
        m_renderer.merge(paths, develop);
        m_job.finish();
    }

    nb::dict progress() {
        std::lock_guard<std::mutex> lock(m_mutex);
        nb::dict d;
        d["pass"] = m_progress.pass;
        d["fraction"] = m_progress.fraction;
        d["elapsed"] = m_progress.elapsed;
        d["samples"] = m_progress.samples;
        return d;
    }

    /// The images as NumPy arrays that take over the renderer's buffers (no copies: a render of
    /// many large views needs its memory once); callable once.
    nb::list results() {
        check_finished();
        if (m_taken) throw std::runtime_error("the results of this render job were already taken");
        m_taken = true;
        nb::list out;
        std::vector<ViewResult> results = m_renderer.take_results();
        for (ViewResult &r : results) {
            nb::dict d;
            d["id"] = r.id;
            size_t h = r.height, w = r.width;
            d["image"] = make_array(std::move(r.rgb), {h, w, 3});
            d["variance"] = make_array(std::move(r.variance), {h, w, 3});
            std::vector<float> count(r.sample_count.begin(), r.sample_count.end());
            r.sample_count = std::vector<uint32_t>();
            d["sample_count"] = make_array(std::move(count), {h, w});
            d["samples"] = r.samples;
            d["mean"] = nb::make_tuple(r.mean[0], r.mean[1], r.mean[2]);
            d["nonfinite"] = r.nonfinite;
            if (!r.contributions.empty()) {
                d["contributions"] = make_array(std::move(r.contributions), {h, w});
                d["contributions_total"] = r.contributions_total;
                d["weight_sum"] = make_array(std::move(r.weight_sum), {h, w});
                d["multiview"] = mv_stats_dict(r.mv);
            }
            d["width"] = r.width;
            d["height"] = r.height;
            out.append(d);
        }
        return out;
    }

    nb::dict stats() {
        check_finished();
        const RenderStats &s = m_renderer.stats();
        nb::dict d;
        d["seconds"] = s.seconds;
        d["max_pass_seconds"] = s.max_pass_seconds;
        d["max_chunk_seconds"] = s.max_chunk_seconds;
        d["between_passes_seconds"] = s.between_passes_seconds;
        d["estimated_bytes"] = s.estimated_bytes;
        d["passes"] = s.passes;
        d["cut_pass_share"] = s.cut_pass_share;
        d["thinned_pass_share"] = s.thinned_pass_share;
        d["thinned_passes"] = s.thinned_passes;
        d["thinned_shares"] = s.thinned_shares;
        d["first_pass"] = s.first_pass;
        d["cancelled"] = s.cancelled;
        d["samples"] = s.samples;
        d["camera_rays"] = s.counters.camera_rays;
        d["rays"] = s.counters.rays;
        d["shadow_rays"] = s.counters.shadow_rays;
        d["nonfinite_samples"] = s.counters.nonfinite;
        d["threads"] = s.threads;
        d["method"] = s.method;
        if (s.method == "mvpt") {
            d["estimator"] = s.estimator;
            d["splits"] = s.splits;
            d["delta_splits"] = s.delta_splits;
            d["predicted_gain"] = s.predicted_gain;
            if (s.split_pilot[3] > 0.0) {
                nb::dict pilot;
                pilot["a"] = s.split_pilot[0];
                pilot["r"] = s.split_pilot[1];
                pilot["c0"] = s.split_pilot[2];
                pilot["c1"] = s.split_pilot[3];
                d["split_pilot"] = pilot;
            }
            d["multiview"] = mv_stats_dict(s.mv);
        }
        nb::list notes;
        for (const std::string &n : s.notes) notes.append(n);
        d["notes"] = notes;
        d["warnings"] = nb::list(nb::cast(s.warnings));
        d["state_error"] = s.state_error;
        if (s.nonfinite_view >= 0) {
            nb::dict f;
            f["view"] = s.nonfinite_view; f["x"] = s.nonfinite_x; f["y"] = s.nonfinite_y; f["sample"] = s.nonfinite_sample;
            d["first_nonfinite"] = f;
        }
        return d;
    }

private:
    void check_finished() {
        if (!m_job.done()) throw std::runtime_error("render job has not finished");
        std::lock_guard<std::mutex> lock(m_mutex);
        if (m_state_error) throw StateError(m_error);
        if (!m_error.empty()) throw std::runtime_error(m_error);
    }

    std::shared_ptr<Scene> m_scene;
    Renderer m_renderer;
    std::atomic<bool> m_cancel{false};
    bool m_taken = false;
    std::mutex m_mutex; ///< of the fields below, which the render's thread writes
    std::string m_error;
    bool m_state_error = false;
    RenderProgress m_progress;
    mvpt_py::JobThread m_job;
};

using Vec2 = std::array<float, 2>;
using Vec3 = std::array<float, 3>;

const Camera &camera_at(const Scene &s, size_t view) {
    if (view >= s.cameras().size())
        throw nb::index_error(("view " + std::to_string(view) + " out of range (the scene has " +
                               std::to_string(s.cameras().size()) + " sensors)").c_str());
    return *s.cameras()[view];
}

nb::list view_info(const Scene &s) {
    nb::list l;
    for (auto &c : s.cameras()) {
        nb::dict d;
        d["id"] = c->id;
        d["width"] = c->film.crop_width;
        d["height"] = c->film.crop_height;
        d["film_width"] = c->film.width;
        d["film_height"] = c->film.height;
        d["spp"] = c->sample_count;
        d["shutter"] = nb::make_tuple(c->shutter_open, c->shutter_close);
        l.append(d);
    }
    return l;
}

/// One view's camera as plain data for backends that trace outside this library
/// (python/mvpt/mitsuba_backend): the 32 scalars of its projection in `flatten`'s order
/// (render/camera_projection.h; None for a camera that moves), its crop window, the margin
/// of its sample window and its reconstruction filter (radius and 1-D table; box: no table).
nb::dict camera_model(const Scene &s, size_t view) {
    const Camera &c = camera_at(s, view);
    nb::dict d;
    if (const CameraProjection *p = c.static_projection()) {
        float v[ProjectionFields];
        flatten(*p, v);
        d["projection"] = std::vector<float>(v, v + ProjectionFields);
    } else {
        d["projection"] = nb::none();
    }
    d["crop"] = nb::make_tuple(c.film.crop_x, c.film.crop_y, c.film.crop_width, c.film.crop_height);
    d["margin"] = SampleWindow(c.film).margin;
    const auto *tab = dynamic_cast<const TabulatedFilter *>(c.film.filter.get());
    const bool box = !c.film.filter || c.film.filter->is_box();
    d["filter_radius"] = box ? 0.5f : c.film.filter->radius();
    d["filter_table"] = box || !tab ? std::vector<float>{} : tab->table();
    d["seed"] = c.seed;
    return d;
}

/// max_depth, rr_depth and hide_emitters of the scene's path, volpath or mvpath integrator.
nb::dict path_settings(const Scene &s) {
    PathConfig cfg;
    if (auto *p = dynamic_cast<const PathIntegrator *>(&s.integrator())) cfg = p->config();
    else if (auto *m = dynamic_cast<const MultiViewPathIntegrator *>(&s.integrator())) cfg = m->path().config();
    else if (auto *v = dynamic_cast<const VolPathIntegrator *>(&s.integrator())) cfg = v->config();
    nb::dict d;
    d["max_depth"] = cfg.max_depth, d["rr_depth"] = cfg.rr_depth, d["hide_emitters"] = cfg.hide_emitters;
    return d;
}

/// SceneError (a ValueError) carries the location as attributes: file, line, column, message.
void bind_errors(nb::module_ &m) {
    // (A plain PyObject*, deliberately never released: no destructor runs after interpreter shutdown.)
    static PyObject *scene_error = PyErr_NewExceptionWithDoc(
        "mvpt._core.SceneError", "Bad scene input; str() is 'file:line:col: message'.", PyExc_ValueError, nullptr);
    m.attr("SceneError") = nb::borrow(scene_error);
    nb::register_exception_translator([](const std::exception_ptr &p, void *) {
        try {
            std::rethrow_exception(p);
        } catch (const SceneError &e) {
            nb::object exc = nb::borrow(scene_error)(e.what());
            exc.attr("file") = e.loc().file;
            exc.attr("line") = e.loc().line;
            exc.attr("column") = e.loc().col;
            exc.attr("message") = e.message();
            PyErr_SetObject(scene_error, exc.ptr());
        }
    });
}

/// The loaded scene: its views, counts, sources, and the camera projection API (for tests and tools).
void bind_scene(nb::module_ &m) {
    nb::class_<Scene>(m, "Scene")
        .def_prop_ro("views", &view_info)
        .def_prop_ro("integrator", [](const Scene &s) { return s.integrator().name(); })
        .def_prop_ro("shape_count", [](const Scene &s) { return s.shapes().size(); })
        .def_prop_ro("light_count", [](const Scene &s) { return s.lights().size(); })
        .def_prop_ro("source_files", [](const Scene &s) {
            std::vector<std::string> files;
            for (const auto &f : s.source_files()) files.push_back(f.string());
            return files;
        }, "The files the scene was read from (XML, meshes, textures, ...), absolute.")
        .def_prop_ro("notes", &Scene::notes, "Notes on how the scene was read (a Mitsuba 0.6 file upgraded).")
        .def_prop_ro("warnings", &Scene::warnings, "What the scene lost while it was read (a mesh's degenerate triangles).")
        .def_prop_ro("defines", &Scene::defines, "The <default> overrides the scene was loaded with.")
        .def_prop_ro("rig", &Scene::rig, "The rig option the scene was loaded with (empty: none).")
        .def("camera_model", &camera_model, "view"_a,
             "The view's camera as data: projection (32 scalars or None), crop, margin, filter radius and table.")
        .def_prop_ro("path_settings", &path_settings, "max_depth, rr_depth and hide_emitters of the integrator.")
        .def_prop_ro("has_media", &Scene::has_media, "True when a participating medium is in the scene.")
        .def_prop_ro("has_moving_shapes", &Scene::is_animated, "True when some shape moves.")
        // Camera projection API (design doc §2-§4), for tests and tools: view is a scene index.
        .def("camera_generate_ray", [](const Scene &s, size_t view, Vec2 film, Vec2 lens, float time) {
            Ray r = camera_at(s, view).generate_ray({film[0], film[1]}, {lens[0], lens[1]}, time);
            return std::make_pair(Vec3{r.o.x, r.o.y, r.o.z}, Vec3{r.d.x, r.d.y, r.d.z});
        }, "view"_a, "film"_a, "lens"_a = Vec2{0.f, 0.f}, "time"_a = 0.f,
           "(origin, direction) of the ray through film position `film` (pixels), unit-disk lens point `lens`.")
        .def("camera_project", [](const Scene &s, size_t view, Vec3 y, float time, Vec2 lens) -> std::optional<Vec2> {
            Vec2f x;
            if (!camera_at(s, view).project({y[0], y[1], y[2]}, time, {lens[0], lens[1]}, &x)) return std::nullopt;
            return Vec2{x.x, x.y};
        }, "view"_a, "y"_a, "time"_a = 0.f, "lens"_a = Vec2{0.f, 0.f},
           "Film position (pixels) where the ray from the lens point to `y` lands, or None outside [near, far].")
        .def("camera_film_density", [](const Scene &s, size_t view, Vec3 y, Vec3 n, float time, Vec2 lens) {
            return camera_at(s, view).film_density({y[0], y[1], y[2]}, {n[0], n[1], n[2]}, time, {lens[0], lens[1]});
        }, "view"_a, "y"_a, "n"_a, "time"_a = 0.f, "lens"_a = Vec2{0.f, 0.f},
           "G(y): film area (pixels^2) per unit surface area at y with normal n (design doc §4).");

    m.def("load_file", [](const std::string &path, const std::map<std::string, std::string> &defines, const std::string &rig) {
        return std::shared_ptr<Scene>(load_scene_file(path, defines, rig));
    }, "path"_a, "defines"_a = std::map<std::string, std::string>{}, "rig"_a = "");
    m.def("load_string", [](const std::string &xml, const std::string &base_dir, const std::map<std::string, std::string> &defines,
                            const std::string &rig) {
        return std::shared_ptr<Scene>(load_scene_string(xml, base_dir, defines, rig));
    }, "xml"_a, "base_dir"_a = ".", "defines"_a = std::map<std::string, std::string>{}, "rig"_a = "");
    // The same loads on a thread of their own (load_job.h): start(), wait(timeout), cancel(), scene().
    nb::class_<mvpt_py::LoadJob>(m, "LoadJob")
        .def("__init__", [](mvpt_py::LoadJob *self, const std::string &source, bool is_file, const std::string &base_dir,
                            const std::map<std::string, std::string> &defines, const std::string &rig, bool every_view_rendered) {
            mvpt_py::LoadJob::Load load = [=]() {
                return is_file ? load_scene_file(source, defines, rig) : load_scene_string(source, base_dir, defines, rig);
            };
            new (self) mvpt_py::LoadJob(std::move(load), every_view_rendered);
        }, "source"_a, "is_file"_a, "base_dir"_a = ".", "defines"_a = std::map<std::string, std::string>{}, "rig"_a = "",
           "every_view_rendered"_a = false)
        .def("start", &mvpt_py::LoadJob::start)
        .def("wait", &mvpt_py::LoadJob::wait, "timeout"_a, nb::call_guard<nb::gil_scoped_release>())
        .def("cancel", &mvpt_py::LoadJob::cancel)
        .def("scene", &mvpt_py::LoadJob::scene);
}

/// A render in native threads, its state files and merges.
void bind_render(nb::module_ &m) {
    // A state file that cannot be used (docs/checkpoints.md): a ValueError.
    nb::exception<StateError>(m, "StateError", PyExc_ValueError);
    m.def("read_state_header", &read_state_header, "path"_a, "The header of a render's state file.");

    nb::class_<RenderJob>(m, "RenderJob")
        .def("__init__", [](RenderJob *self, std::shared_ptr<Scene> scene, int spp, double time, std::optional<uint32_t> seed,
                            int threads, std::vector<int> views, const std::string &method, const std::string &state_path,
                            const std::string &state_header, double checkpoint_interval, bool state_at_end,
                            const std::string &resume_path, int first_pass, int pass_count, int splits, bool pilot_only) {
            RenderOptions o;
            o.spp = spp; o.time_budget = time; o.seed = seed; o.threads = threads; o.views = std::move(views);
            o.state_path = state_path; o.state_header = state_header; o.checkpoint_interval = checkpoint_interval;
            o.state_at_end = state_at_end; o.resume_path = resume_path;
            o.first_pass = first_pass; o.pass_count = pass_count; o.splits = splits; o.pilot_only = pilot_only;
            if (method == "scene") o.method = RenderMethod::Scene;
            else if (method == "pt") o.method = RenderMethod::PathTracing;
            else if (method == "mvpt") o.method = RenderMethod::MultiView;
            else throw nb::value_error(("unknown method '" + method + "': expected 'pt', 'mvpt' or 'scene'").c_str());
            new (self) RenderJob(std::move(scene), std::move(o));
        }, "scene"_a, "spp"_a = 0, "time"_a = 0.0, "seed"_a = nb::none(), "threads"_a = 0, "views"_a = std::vector<int>{},
           "method"_a = "scene", "state_path"_a = "", "state_header"_a = "", "checkpoint_interval"_a = 0.0,
           "state_at_end"_a = false, "resume_path"_a = "", "first_pass"_a = 0, "pass_count"_a = 0, "splits"_a = -1,
           "pilot_only"_a = false)
        .def("start", &RenderJob::start)
        .def("wait", &RenderJob::wait, "timeout"_a, nb::call_guard<nb::gil_scoped_release>())
        .def("cancel", &RenderJob::cancel)
        .def("merge", &RenderJob::merge, "paths"_a, "develop"_a = true, nb::call_guard<nb::gil_scoped_release>())
        .def("progress", &RenderJob::progress)
        .def("results", &RenderJob::results)
        .def("stats", &RenderJob::stats);
}

/// Images in and out: EXR (single and multi-part), PNG.
void bind_images(nb::module_ &m) {
    m.def("write_exr", [](const std::string &path, std::map<std::string, nb::ndarray<float, nb::ndim<2>, nb::c_contig, nb::device::cpu>> channels) {
        std::vector<ExrChannel> ch;
        int w = -1, h = -1;
        for (auto &[name, arr] : channels) {
            if (w < 0) { h = int(arr.shape(0)); w = int(arr.shape(1)); }
            if (int(arr.shape(0)) != h || int(arr.shape(1)) != w) throw std::invalid_argument("EXR channels differ in size");
            ch.push_back({name, std::vector<float>(arr.data(), arr.data() + arr.size())});
        }
        if (ch.empty()) throw std::invalid_argument("no channels");
        write_exr(path, w, h, ch);
    }, "path"_a, "channels"_a);
    m.def("write_multiview_exr", [](const std::string &path,
                                    std::vector<std::pair<std::string, std::map<std::string, nb::ndarray<float, nb::ndim<2>, nb::c_contig, nb::device::cpu>>>> views) {
        std::vector<ExrView> out;
        for (auto &[name, channels] : views) {
            ExrView v;
            v.name = name;
            v.height = v.width = -1;
            for (auto &[cname, arr] : channels) {
                if (v.width < 0) { v.height = int(arr.shape(0)); v.width = int(arr.shape(1)); }
                if (int(arr.shape(0)) != v.height || int(arr.shape(1)) != v.width)
                    throw std::invalid_argument("the channels of view '" + name + "' differ in size");
                v.channels.push_back({cname, std::vector<float>(arr.data(), arr.data() + arr.size())});
            }
            out.push_back(std::move(v));
        }
        write_multiview_exr(path, out);
    }, "path"_a, "views"_a, "One multi-part EXR: a part per (name, {channel: HxW float32}) view; part name = view attribute = name.");
    m.def("read_multiview_exr", [](const std::string &path) {
        std::vector<std::pair<std::string, std::map<std::string, FloatArray>>> out;
        for (ExrView &v : read_multiview_exr(path)) {
            std::map<std::string, FloatArray> channels;
            for (ExrChannel &c : v.channels)
                channels.emplace(c.name, make_array(std::move(c.data), {size_t(v.height), size_t(v.width)}));
            out.emplace_back(v.name, std::move(channels));
        }
        return out;
    }, "path"_a, "Every part of an EXR as (name, {channel: HxW float32}); name = view attribute, else part name.");
    m.def("write_png", [](const std::string &path, nb::ndarray<float, nb::shape<-1, -1, 3>, nb::c_contig, nb::device::cpu> rgb) {
        write_png_srgb(path, int(rgb.shape(1)), int(rgb.shape(0)), rgb.data());
    }, "path"_a, "rgb"_a);
    m.def("read_image", [](const std::string &path) {
        ImageRGB img = read_image(path);
        size_t h = img.height, w = img.width;
        return make_array(std::move(img.rgb), {h, w, 3});
    }, "path"_a);
}

} // namespace

NB_MODULE(_core, m) {
    m.doc() = "mvpt native core";
    bind_errors(m);
    mvpt_py::bind_signals_at_exit(m);
    bind_scene(m);
    bind_render(m);
    bind_images(m);
}
