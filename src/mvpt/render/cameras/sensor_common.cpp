#include "sensor_common.h"

#include "../../core/plugin.h"
#include "../medium.h"

namespace mvpt {

namespace {

/// A film without an rfilter takes Mitsuba's: a gaussian of stddev 0.5 (Mitsuba 0.6's too).
std::shared_ptr<ReconstructionFilter> default_filter() {
    Properties p("rfilter", "gaussian");
    return std::static_pointer_cast<ReconstructionFilter>((*PluginRegistry::find("rfilter", "gaussian"))(p, {}));
}

std::shared_ptr<Object> make_hdrfilm(const Properties &props, const LoadContext &) {
    auto f = std::make_shared<FilmObject>();
    FilmDesc &d = f->desc;
    int64_t w = props.get_int("width", 768), h = props.get_int("height", 576);
    if (w <= 0 || h <= 0 || w > 65536 || h > 65536)
        props.fail(w <= 0 || w > 65536 ? "width" : "height",
                   "film resolution must be between 1 and 65536, got " + std::to_string(w) + "x" + std::to_string(h));
    d.width = int(w);
    d.height = int(h);
    int64_t cx = props.get_int("crop_offset_x", 0), cy = props.get_int("crop_offset_y", 0);
    int64_t cw = props.get_int("crop_width", w - cx), ch = props.get_int("crop_height", h - cy);
    // (Compared without sums: offsets near 2^63 once wrapped around.)
    if (cx < 0 || cy < 0 || cx >= w || cy >= h || cw <= 0 || ch <= 0 || cw > w - cx || ch > h - cy)
        props.fail("crop_width", "crop window (" + std::to_string(cx) + ", " + std::to_string(cy) + ") + " +
                                     std::to_string(cw) + "x" + std::to_string(ch) + " does not fit in the " +
                                     std::to_string(w) + "x" + std::to_string(h) + " film");
    d.crop_x = int(cx); d.crop_y = int(cy); d.crop_width = int(cw); d.crop_height = int(ch);
    std::string pf = props.get_string("pixel_format", "rgb");
    if (pf != "rgb" && pf != "rgba" && pf != "luminance")
        props.fail("pixel_format", "pixel_format must be rgb, rgba or luminance, got '" + pf + "'");
    std::string cf = props.get_string("component_format", "float16");
    if (cf != "float16" && cf != "float32" && cf != "uint32")
        props.fail("component_format", "component_format must be float16, float32 or uint32, got '" + cf + "'");
    std::string ff = props.get_string("file_format", "openexr");
    if (ff != "openexr" && ff != "exr") props.fail("file_format", "file_format must be openexr, got '" + ff + "'");
    props.get_bool("sample_border", false);
    if (const ChildObject *rf = props.child_of_kind("rfilter"))
        d.filter = std::static_pointer_cast<ReconstructionFilter>(rf->object);
    else
        d.filter = default_filter();
    return f;
}

std::shared_ptr<Object> make_sampler(const Properties &props, SamplerKind kind) {
    auto s = std::make_shared<SamplerObject>();
    s->kind = kind;
    s->sample_count = int(props.get_int_in("sample_count", 4, 1, INT32_MAX));
    s->seed = uint32_t(props.get_int_in("seed", 0, 0, UINT32_MAX));
    // Jittered/stratified samplers of Mitsuba map to our one low-discrepancy sampler.
    props.get_bool("jitter", true);
    props.get_float("strength", 0.f);
    return s;
}

} // namespace

void read_sensor_common(Camera &cam, const Properties &props) {
    cam.id = props.id;
    if (const ChildObject *f = props.child_of_kind("film")) cam.film = std::static_pointer_cast<FilmObject>(f->object)->desc;
    else {
        Properties fp("film", "hdrfilm", props.loc());
        cam.film = std::static_pointer_cast<FilmObject>(make_hdrfilm(fp, {}))->desc;
    }
    if (const ChildObject *s = props.child_of_kind("sampler")) {
        auto so = std::static_pointer_cast<SamplerObject>(s->object);
        cam.sampler_kind = so->kind;
        cam.sample_count = so->sample_count;
        cam.seed = so->seed;
    }
    if (const ChildObject *m = props.child_of_kind("medium")) cam.medium = std::static_pointer_cast<Medium>(m->object);
    cam.shutter_open = props.get_float("shutter_open", 0.f);
    cam.shutter_close = props.get_float("shutter_close", cam.shutter_open);
    if (!(cam.shutter_close >= cam.shutter_open))
        props.fail("shutter_close", "shutter_close must not be before shutter_open");
}

MVPT_REGISTER_PLUGIN("film", "hdrfilm", make_hdrfilm);
MVPT_REGISTER_PLUGIN("sampler", "independent", [](const Properties &p, const LoadContext &) {
    return make_sampler(p, SamplerKind::Independent);
});
MVPT_REGISTER_PLUGIN("sampler", "ldsampler", [](const Properties &p, const LoadContext &) {
    return make_sampler(p, SamplerKind::Sobol);
});
MVPT_REGISTER_PLUGIN("sampler", "stratified", [](const Properties &p, const LoadContext &) {
    return make_sampler(p, SamplerKind::Sobol);
});
MVPT_REGISTER_PLUGIN("sampler", "multijitter", [](const Properties &p, const LoadContext &) {
    return make_sampler(p, SamplerKind::Sobol);
});
MVPT_REGISTER_PLUGIN("sampler", "orthogonal", [](const Properties &p, const LoadContext &) {
    return make_sampler(p, SamplerKind::Sobol);
});

} // namespace mvpt
