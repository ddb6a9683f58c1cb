// The `mvpt._probes` extension, for the tests only: single BSDFs, emitters, media and phase
// functions built from XML snippets and sampled or evaluated from Python (the chi-square,
// energy and agreement tests), free flights along camera segments, and the loader's spectrum
// conversion, and a multi-view render cut short after its first chunk. It links its own copy
// of the library and shares no objects with `mvpt._core`.
#include <nanobind/nanobind.h>

namespace nb = nanobind;

void bind_probes(nb::module_ &m);
void bind_light_probes(nb::module_ &m);
void bind_spectrum(nb::module_ &m);
void bind_segment_probes(nb::module_ &m);
void bind_render_probes(nb::module_ &m);
void bind_medium_probes(nb::module_ &m);

NB_MODULE(_probes, m) {
    m.doc() = "mvpt test probes"; // bad input: ValueError (scene_errors.h)
    bind_probes(m);
    bind_light_probes(m);
    bind_spectrum(m);
    bind_segment_probes(m);
    bind_render_probes(m);
    bind_medium_probes(m);
}
