"""SIGINT (Ctrl-C), SIGTERM (batch schedulers, `kill`) and SIGHUP (a closed terminal) in the
command line, from the start of its work to the end of the process: the first one stops what
can stop, and the exit code says which came (128 + its number); later ones (people press
Ctrl-C twice) are reported and do not abandon what the first is saving. None kills the
process, and none interrupts the writing of outputs.

Where `interruptible` is set (commands whose work is all or nothing) the first signal raises
KeyboardInterrupt wherever the main thread is. A render clears it and polls `stop_requested()`
between its steps instead (the load, the passes), so that a signal never lands between the end
of the render and its outputs. When the program ends (`end`) they are caught natively to the
last instant: Python's shutdown would otherwise restore their default action, death by the
signal."""
from __future__ import annotations

import contextlib
import signal
import sys
import threading

STOPS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

# The first signal that came; None until one did.
stopped_by = None
# Whether the first signal raises KeyboardInterrupt (else it is only recorded).
interruptible = True
# What is being finished while signals wait ("writing the outputs"), for the message.
busy = None


def on_signal(signum, frame):
    global stopped_by
    first = stopped_by is None
    if first:
        stopped_by = signal.Signals(signum)
        if interruptible:
            raise KeyboardInterrupt
    if busy is not None or not first:
        print(f"\nmvpt: {signal.Signals(signum).name}: finishing {busy or 'what was started'}", file=sys.stderr)


def stop_requested() -> bool:
    return stopped_by is not None


def exit_code() -> int:
    """The exit code of a command stopped by a signal (Ctrl-C's when none was recorded)."""
    return 128 + int(stopped_by or signal.SIGINT)


def final_code(code: int) -> int:
    """A command's exit code once a signal may have come: a signal's code replaces success."""
    return exit_code() if code == 0 and stopped_by is not None else code


def install() -> dict:
    """on_signal for the three signals (in the main thread; elsewhere Python delivers none);
    the handlers it replaced. A new command forgets the signal of an earlier one in this
    process, but not one that came since the program installed the handlers at its start."""
    global stopped_by, interruptible, busy
    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {s: signal.signal(s, on_signal) for s in STOPS}
    if any(h is not on_signal for h in previous.values()):
        stopped_by = None
    interruptible, busy = True, None
    return previous


def restore(previous: dict) -> None:
    for s, handler in previous.items():
        signal.signal(s, handler if handler is not None else signal.SIG_DFL)


def end(code: int) -> int:
    """The program's end: its exit code, a signal's replacing success. From here to the end of
    the process (Python's shutdown included, which would set these handlers back to the default
    action, death by the signal) the three signals are recorded natively and a late one still
    gives its code (src/python/signals_at_exit.h)."""
    global interruptible
    interruptible = False
    code = final_code(code)
    if threading.current_thread() is threading.main_thread():
        from . import _core
        _core.catch_signals_to_exit([int(s) for s in STOPS], code)  # (runs the handlers of any that came)
    return final_code(code)


@contextlib.contextmanager
def finishing(what: str):
    """Signals while inside are recorded and reported, never raised: `what` (e.g. "writing the
    outputs") is finished. After it a signal that came raises KeyboardInterrupt where the
    command is interruptible."""
    global busy, interruptible
    was = interruptible
    outer, busy, interruptible = busy, what, False
    try:
        yield
    finally:
        busy, interruptible = outer, was
    if was and outer is None and stopped_by is not None:
        raise KeyboardInterrupt


def reset() -> None:
    """Forget the signal of an earlier command (main() runs more than once in one process)."""
    global stopped_by, interruptible, busy
    stopped_by, interruptible, busy = None, True, None
