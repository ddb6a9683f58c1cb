"""`python -m mvpt ...` runs the command line (same as the `mvpt` entry point)."""
import sys

from .cli import main

sys.exit(main())
