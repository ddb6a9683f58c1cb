#include "signals_at_exit.h"

#include <nanobind/stl/vector.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace nb = nanobind;
using namespace nb::literals;

namespace mvpt_py {

namespace {

volatile std::sig_atomic_t g_signal = 0; // the first that came (0: none)
int g_code = 0;                          // the exit code the program chose
bool g_registered = false;

extern "C" void record_signal(int s) {
    if (g_signal == 0) g_signal = s;
}

void catch_with_recorder(const std::vector<int> &signals) {
    struct sigaction action = {};
    action.sa_handler = record_signal;
    sigemptyset(&action.sa_mask);
    for (int s : signals) sigaction(s, &action, nullptr);
}

/// At exit: a signal that came turns a success into its exit code, unless someone has set its
/// handler back since (an embedding process that went on after the program's end).
void exit_with_signal_code() {
    if (g_signal == 0 || g_code != 0) return;
    struct sigaction now = {};
    if (sigaction(g_signal, nullptr, &now) != 0 || now.sa_handler != record_signal) return;
    std::fflush(nullptr);
    std::_Exit(128 + g_signal);
}

void catch_signals_to_exit(const std::vector<int> &signals, int code) {
    g_signal = 0;
    g_code = code;
    catch_with_recorder(signals); // no Python handler can be tripped from here on
    if (PyErr_CheckSignals() != 0) throw nb::python_error(); // those tripped before run (they record)
    // Python's table must say "ignored", or its shutdown resets the signals to their default;
    // setting it sets the operating system's handler too, so the recorder is put back after.
    nb::module_ signal = nb::module_::import_("signal");
    for (int s : signals) signal.attr("signal")(s, signal.attr("SIG_IGN"));
    catch_with_recorder(signals);
    if (!g_registered) g_registered = std::atexit(exit_with_signal_code) == 0;
}

} // namespace

void bind_signals_at_exit(nb::module_ &m) {
    m.def("catch_signals_to_exit", &catch_signals_to_exit, "signals"_a, "code"_a,
          "From now to the process's exit, `signals` are recorded, never raised or fatal; the first "
          "that came turns an exit `code` of 0 into 128 + its number (signals_at_exit.h).");
}

} // namespace mvpt_py
