"""`python -m mvpt ...` runs the command line (same as the `mvpt` entry point)."""
import sys

from .cli import command

sys.exit(command())
