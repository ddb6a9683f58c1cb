"""The `mvpt` program's entry point (`mvpt`, `python -m mvpt`): the signal handlers come first,
then the libraries (NumPy and the native core take a tenth of a second or more), so that
SIGINT, SIGTERM and SIGHUP are handled from the start (stop_signals): one that comes while
they load is recorded and stops the command as soon as it begins."""
from __future__ import annotations


def run() -> int:
    from . import stop_signals
    stop_signals.install()
    stop_signals.interruptible = False  # (recorded only: an import is not to be interrupted)
    from .cli import command
    return command()
