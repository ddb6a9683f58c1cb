// Test probes for emitters (filled in with the emitter plugins).
#include <nanobind/nanobind.h>

namespace nb = nanobind;

void bind_light_probes(nb::module_ &) {}
