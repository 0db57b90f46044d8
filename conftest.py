"""Test-session set-up shared by tests/ and the doctests in src/."""

import matplotlib

matplotlib.use("Agg")

# Importing __main__ would run the command line.
collect_ignore = ["src/flexarm/__main__.py"]
