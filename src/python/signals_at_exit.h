// The last stretch of the `mvpt` program: from the moment its exit code is known to the end of
// the process (Python's shutdown included, which would set a Python signal handler back to the
// default action, death by the signal), SIGINT, SIGTERM and SIGHUP are caught by a handler of
// the operating system's own that records the first; when the process exits, one that came
// turns a success into 128 + its number. (python/mvpt/stop_signals.py, `end`.)
#pragma once

#include <nanobind/nanobind.h>

namespace mvpt_py {

/// `_core.catch_signals_to_exit(signals, code)`.
void bind_signals_at_exit(nanobind::module_ &m);

} // namespace mvpt_py
