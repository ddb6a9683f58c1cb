"""`python -m mvpt ...` runs the command line (same as the `mvpt` entry point)."""
import sys

from .program import run

sys.exit(run())
