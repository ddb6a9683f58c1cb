// The probes' bad input as Python ValueErrors. The module registers no exception translator:
// nanobind's translators are shared by every module built against it, and one for this module's
// copy of SceneError would also catch `mvpt._core`'s and hide its mvpt.SceneError.
#pragma once

#include "mvpt/core/error.h"

#include <nanobind/nanobind.h>

namespace mvpt_py {

/// f(), with a SceneError it throws raised as a ValueError carrying the same message.
template <typename F> auto scene_errors_as_value_errors(F &&f) {
    try {
        return f();
    } catch (const mvpt::SceneError &e) {
        throw nanobind::value_error(e.what());
    }
}

} // namespace mvpt_py
