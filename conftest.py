"""Test-session set-up shared by tests/ and the doctests in src/."""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")

# Importing __main__ would run the command line.
collect_ignore = ["src/flexarm/__main__.py"]

# Helper modules of the tests (e.g. exudyn_models, the Exudyn oracle) import by name.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "tests"))
