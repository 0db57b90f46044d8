"""The documentation builds with warnings as errors and documents every public name.

One Sphinx build (a copy of ``docs/`` in a temporary directory, so that nothing is left
in the tree and every gallery example runs afresh) serves the tests below: any Sphinx or
docutils warning, a cross-reference that does not resolve or a gallery example that
raises fails the first; the others read what the build wrote.
"""

from __future__ import annotations

import importlib
import pkgutil
import shutil
import zlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
GALLERY = sorted((DOCS / "gallery").glob("plot_*.py"))
# what a build writes into its source tree (absent from a clean checkout)
GENERATED = ("_build", "generated", "auto_examples", "sg_execution_times.rst", "__pycache__")


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> tuple[int, str, Path]:
    pytest.importorskip("sphinx", reason="the docs extra is not installed (.[docs])")
    from sphinx.cmd.build import build_main

    work = tmp_path_factory.mktemp("docs")
    source = work / "docs"
    shutil.copytree(DOCS, source, ignore=shutil.ignore_patterns(*GENERATED))
    shutil.copytree(ROOT / "examples", work / "examples")  # the guide includes its files
    html, log = work / "html", work / "warnings.log"
    args = ["-W", "--keep-going", "-q", "-w", str(log), "-b", "html"]
    status = build_main([*args, "-d", str(work / "doctrees"), str(source), str(html)])
    return status, log.read_text() if log.exists() else "", html


def test_the_documentation_builds_without_a_warning(built):
    status, warnings, _ = built
    assert status == 0 and not warnings.strip(), f"sphinx-build exit {status}:\n{warnings}"


def test_every_gallery_example_ran_and_drew(built):
    _, _, html = built
    assert len(GALLERY) >= 5
    for script in GALLERY:
        page = html / "auto_examples" / f"{script.stem}.html"
        assert page.exists(), f"{script.name}: no page"
        figures = list((html / "_images").glob(f"sphx_glr_{script.stem}_*.png"))
        figures = [f for f in figures if "thumb" not in f.name]
        assert figures, f"{script.name}: no figure"


def _public_modules(name: str = "flexarm") -> list[str]:
    found = [name]
    module = importlib.import_module(name)
    for info in pkgutil.iter_modules(getattr(module, "__path__", [])):
        if not info.name.startswith("_"):
            found += _public_modules(f"{name}.{info.name}")
    return found


def _documented(inventory: Path) -> set[str]:
    """Python names in a Sphinx ``objects.inv`` (version 2: four header lines, then
    zlib-compressed lines ``name domain:role priority uri display``)."""
    raw = inventory.read_bytes()
    header_end = 0
    for _ in range(4):
        header_end = raw.index(b"\n", header_end) + 1
    lines = zlib.decompress(raw[header_end:]).decode().splitlines()
    return {ln.split(" ", 1)[0] for ln in lines if " py:" in ln}


def test_every_public_name_is_in_the_api_reference(built):
    """A new public module or a new name in an ``__all__`` cannot go undocumented: each
    ``module.name`` is in the reference (where defined, or as an alias of that entry)."""
    _, _, html = built
    documented = _documented(html / "objects.inv")
    modules = _public_modules()
    missing = [m for m in modules if m not in documented]
    for module in modules:
        for name in getattr(importlib.import_module(module), "__all__", []):
            if f"{module}.{name}" not in documented:
                missing.append(f"{module}.{name}")
    assert len(modules) > 100 and not missing, f"not in the API reference: {missing}"


def test_the_inventory_reader_sees_what_it_should(built):
    """The check above is not vacuous: it reads the names a reader would look up."""
    _, _, html = built
    documented = _documented(html / "objects.inv")
    for name in (
        "flexarm.FlexibleArm",
        "flexarm.model.arm.FlexibleArm.paper",
        "flexarm.simulate",
        "flexarm.ident.SemiRecursiveKernelRegression.fit",
    ):
        assert name in documented
    assert "flexarm._lazy" not in documented and "flexarm.ident._setup" not in documented
