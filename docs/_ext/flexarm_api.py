"""The map of flexarm's public API that the reference is generated from.

Every public module (no leading underscore anywhere in its dotted name) gets one page.
A name in a module's ``__all__`` is documented in full on exactly one page, its *home*:
the public module that defines it, or, for a name defined in a private module, the
public module closest to that definition that exports it. Every other module that
exports the name lists it with a link to its home, and the name is registered as an
alias of the home's entry (with its members), so ``:func:`flexarm.simulate``` and
``:class:`flexarm.model.FlexibleArm``` resolve to the one description.

A cross-reference that the Python domain cannot find is looked up as Python would look
the name up from where the reference is written (the module and class in context), and
resolved to the documented home of the object found. What is still unresolved is a
broken reference: Sphinx warns (``nitpicky``), and the warning fails the build.
"""

from __future__ import annotations

import ast
import functools
import importlib
import importlib.util
import inspect
import pkgutil
import types
from dataclasses import dataclass, field
from typing import Any

from flexarm._lazy import declared_names

ROOT = "flexarm"

#: Section titles of a module page, in order, by kind of object.
KINDS = {
    "class": "Classes",
    "exception": "Exceptions",
    "function": "Functions",
    "data": "Constants and data",
}


def public_modules(root: str = ROOT) -> list[str]:
    """Every public module under ``root`` (itself included), parents before children."""
    found = [root]
    module = importlib.import_module(root)
    for info in pkgutil.iter_modules(getattr(module, "__path__", [])):
        if info.name.startswith("_"):
            continue
        found += public_modules(f"{root}.{info.name}")
    return found


def _module_source(modname: str) -> ast.Module | None:
    try:
        return ast.parse(inspect.getsource(importlib.import_module(modname)))
    except (OSError, TypeError):
        return None


@functools.cache
def _bindings(modname: str) -> dict[str, tuple[str, str] | None]:
    """Top-level names of a module: ``None`` if bound there, else ``(module, name)`` of
    the import it comes from (statements under ``if TYPE_CHECKING`` are not run)."""
    tree = _module_source(modname)
    module = importlib.import_module(modname)
    package = modname if hasattr(module, "__path__") else modname.rpartition(".")[0]
    found: dict[str, tuple[str, str] | None] = {}
    lazy = getattr(module, "_NAMES", None)
    if lazy is None and tree is not None and hasattr(module, "__path__"):
        lazy = declared_names(inspect.getsource(module), modname)  # what attach reads
    if isinstance(lazy, dict):  # flexarm._lazy.attach: name -> relative module
        for name, rel in lazy.items():
            found[name] = (f"{modname}.{rel}", name)
    for node in tree.body if tree else []:
        if isinstance(node, ast.ImportFrom):
            source = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
            for alias in node.names:
                found[alias.asname or alias.name] = (source, alias.name)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            found[node.name] = None
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                for sub in ast.walk(target):
                    if isinstance(sub, ast.Name):
                        found[sub.id] = None
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            found[node.target.id] = None
    return found


def origin(modname: str, name: str) -> str:
    """The module that defines ``modname.name`` (following imports)."""
    seen = set()
    while (modname, name) not in seen:
        seen.add((modname, name))
        binding = _bindings(modname).get(name, None)
        if binding is None:
            if name not in _bindings(modname):  # neither bound nor imported: ask the object
                obj = getattr(importlib.import_module(modname), name)
                return str(getattr(obj, "__module__", None) or modname)
            return modname
        source, name = binding
        if importlib.util.find_spec(source) is None:  # pragma: no cover - broken import
            return source
        mod = importlib.import_module(source)
        if isinstance(getattr(mod, name, None), types.ModuleType) and name not in _bindings(source):
            return f"{source}.{name}"  # `from . import x`: the module itself
        modname = source
    return modname


def _kind(obj: Any) -> str:
    if isinstance(obj, types.GenericAlias) or type(obj).__module__ == "typing":
        return "data"  # type aliases: dict[str, float], Callable[...]
    if isinstance(obj, type):
        return "exception" if issubclass(obj, BaseException) else "class"
    if callable(obj) and (inspect.isroutine(obj) or hasattr(obj, "py_func")):
        return "function"  # plain functions and Numba dispatchers
    return "data"


def _public(modname: str) -> bool:
    return not any(part.startswith("_") for part in modname.split("."))


@dataclass
class ModulePage:
    """What one module's page holds."""

    name: str
    own: dict[str, list[str]] = field(default_factory=lambda: {k: [] for k in KINDS})
    reexports: list[tuple[str, str, str]] = field(default_factory=list)  # (name, home, kind)
    submodules: list[str] = field(default_factory=list)

    def as_context(self) -> dict[str, Any]:
        return {
            "sections": [(KINDS[k], k, names) for k, names in self.own.items() if names],
            # autosummary wants names below the page's module relative; it cannot
            # summarise type aliases, so data is listed apart
            "reexports": [
                home.removeprefix(self.name + ".")
                for _, home, kind in self.reexports
                if kind != "data"
            ],
            "reexported_data": [home for _, home, kind in self.reexports if kind == "data"],
            "submodules": self.submodules,
        }


@dataclass
class ApiMap:
    """The pages, and every public full name mapped to its documented full name."""

    pages: dict[str, ModulePage]
    homes: dict[str, str]  # e.g. "flexarm.simulate" -> "flexarm.sim.closed_loop.simulate"
    by_origin: dict[tuple[str, str], str]  # (defining module, name) -> documented full name

    def context(self) -> dict[str, Any]:
        return {name: page.as_context() for name, page in self.pages.items()}


def _common(a: str, b: str) -> int:
    n = 0
    for x, y in zip(a.split("."), b.split("."), strict=False):
        if x != y:
            break
        n += 1
    return n


@functools.cache
def api_map(root: str = ROOT) -> ApiMap:
    modules = public_modules(root)
    pages = {m: ModulePage(m) for m in modules}
    for m in modules:
        parent = m.rpartition(".")[0]
        if parent in pages:
            pages[parent].submodules.append(m)
    exported: dict[tuple[str, str], list[str]] = {}  # (origin module, name) -> exporters
    for m in modules:
        for name in getattr(importlib.import_module(m), "__all__", []):
            exported.setdefault((origin(m, name), name), []).append(m)
    homes: dict[str, str] = {}
    by_origin: dict[tuple[str, str], str] = {}
    for (src, name), exporters in exported.items():
        if src in exporters:
            home = src
        else:  # defined privately: the exporter nearest the definition, then the deepest
            home = max(exporters, key=lambda e: (_common(e, src), e.count("."), e))
        obj = getattr(importlib.import_module(home), name)
        kind = _kind(obj)
        pages[home].own[kind].append(name)
        by_origin[(src, name)] = f"{home}.{name}"
        for e in exporters:
            homes[f"{e}.{name}"] = f"{home}.{name}"
            if e != home:
                pages[e].reexports.append((name, f"{home}.{name}", kind))
    for page in pages.values():
        for names in page.own.values():
            names.sort()
        page.reexports.sort()
    return ApiMap(pages, homes, by_origin)


# --- Sphinx -----------------------------------------------------------------------------


def _add_aliases(app: Any, env: Any) -> None:
    """Register every re-exported name (and its members) as an alias of its home."""
    domain = env.get_domain("py")
    objects = domain.objects
    homes = api_map().homes
    by_prefix: dict[str, list[str]] = {}
    for full in list(objects):
        by_prefix.setdefault(full.split(".", 1)[0], []).append(full)
    for alias, home in homes.items():
        if alias == home or home not in objects:
            continue
        for full in by_prefix.get(home.split(".", 1)[0], []):
            if full == home or full.startswith(home + "."):
                new = alias + full[len(home) :]
                if new not in objects:
                    entry = objects[full]
                    objects[new] = entry._replace(aliased=True)


def _lookup(path: str) -> Any:
    """The object Python finds at dotted ``path`` (longest importable module first)."""
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        modname = ".".join(parts[:i])
        try:
            obj: Any = importlib.import_module(modname)
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


@functools.cache
def _documented_objects() -> dict[int, str]:
    found: dict[int, str] = {}
    for page in api_map().pages.values():
        module = importlib.import_module(page.name)
        for kind, names in page.own.items():
            if kind == "data":
                continue  # values may be shared (small ints, strings): no identity
            for name in names:
                found[id(getattr(module, name))] = f"{page.name}.{name}"
    for m in api_map().pages:
        found[id(importlib.import_module(m))] = m
    return found


def _documented_name(path: str) -> str | None:
    """The documented full name of what Python finds at ``path``, if any."""
    parts = path.split(".")
    known = _documented_objects()
    for i in range(len(parts), 0, -1):  # the longest prefix that is a documented object
        obj = _lookup(".".join(parts[:i]))
        if obj is not None and id(obj) in known:
            if i == len(parts) - 1 and isinstance(obj, type):  # a member: maybe inherited,
                for base in obj.__mro__:  # documented on this class (inherited-members)
                    if parts[-1] in vars(base) and id(base) in known:
                        if base.__name__.startswith("_") or base is obj:
                            break
                        return f"{known[id(base)]}.{parts[-1]}"
            return ".".join([known[id(obj)], *parts[i:]])
    modname, _, name = path.rpartition(".")  # data: where the module's name comes from
    if isinstance(_lookup(modname), types.ModuleType) and modname in api_map().pages:
        try:
            return api_map().by_origin.get((origin(modname, name), name))
        except AttributeError:
            return None
    return None


def _resolve_missing(app: Any, env: Any, node: Any, contnode: Any) -> Any:
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"]
    modname, classname = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if modname:
        if classname:
            candidates.insert(0, f"{modname}.{classname}.{target}")
        candidates.insert(-1, f"{modname}.{target}")
    domain = env.get_domain("py")
    names = [n for c in candidates if c.startswith(ROOT) and (n := _documented_name(c))]
    # last: a name written short (``Scenario.from_dict``) that one description ends with
    suffix = "." + target
    unique = {full for full, entry in domain.objects.items() if full.endswith(suffix)}
    unique = {full for full in unique if not domain.objects[full].aliased}
    if len(unique) == 1:
        names.append(unique.pop())
    for name in names:
        if name == target:
            continue
        found = domain.resolve_xref(
            env, node["refdoc"], app.builder, node["reftype"], name, node, contnode
        )
        if found is not None:
            return found
    return None


def _member_owner(obj: Any) -> str:
    """The module that defines a class member ("" if it cannot be told)."""
    if isinstance(obj, property):
        obj = obj.fget
    owner = getattr(obj, "__objclass__", None)  # methods of built-in types
    return str(getattr(owner or obj, "__module__", None) or "")


def _skip_member(app: Any, what: str, name: str, obj: Any, skip: bool, options: Any) -> Any:
    """Classes show their inherited members (``fit`` of an estimator built on a private
    base), but not those of Python's own types (``tuple.count``, ``Exception.args``)
    nor the field accessors of a NamedTuple (its Attributes section describes them)."""
    if what not in ("class", "exception"):
        return None
    if type(obj).__name__ == "_tuplegetter":
        return True
    owner = _member_owner(obj)
    if owner and not owner.startswith(ROOT):
        return True
    return None


def _no_data_signature(
    app: Any, what: str, name: str, obj: Any, options: Any, args: Any, retann: Any
) -> tuple[None, None] | None:
    """Data has no signature. (numpydoc offers one for callable data such as the type
    alias ``dict[str, float]``, which Sphinx 9 fails to store; a result whose first
    item is not a string is ignored by Sphinx and ends the handler chain.)"""
    return (None, None) if what == "data" else None


def _plain_module_docstrings(app: Any) -> None:
    """Module docstrings are reST prose with sections of their own ("Designers",
    "Residual vibration"); numpydoc would drop those as unknown sections, so it
    formats only classes, functions and methods."""
    listeners = app.events.listeners["autodoc-process-docstring"]
    for i, listener in enumerate(listeners):
        handler = listener.handler
        if getattr(handler, "__module__", "").startswith("numpydoc"):

            def skip_modules(app: Any, what: str, *args: Any, _h: Any = handler) -> None:
                if what != "module":
                    _h(app, what, *args)

            listeners[i] = listener._replace(handler=skip_modules)


def _numpydoc_one_template() -> None:
    """numpydoc compiles its Jinja template anew for every docstring (a third of the
    build); compile it once. numpydoc's own hook for this is its module-level
    ``get_doc_object`` (``numpydoc.setup(app, get_doc_object_=...)``)."""
    import os

    from jinja2 import FileSystemLoader
    from jinja2.sandbox import SandboxedEnvironment
    from numpydoc import docscrape, docscrape_sphinx
    from numpydoc import numpydoc as extension

    folder = os.path.join(os.path.dirname(docscrape_sphinx.__file__), "templates")
    env = SandboxedEnvironment(loader=FileSystemLoader([folder]))
    template = env.get_template("numpydoc_docstring.rst")

    def get_doc_object(
        obj: Any, what: Any = None, doc: Any = None, config: Any = None, builder: Any = None
    ) -> Any:
        config = {**(config or {}), "template": template}
        return docscrape.get_doc_object(
            obj,
            what=what,
            doc=doc,
            config=config,
            class_doc=docscrape_sphinx.SphinxClassDoc,
            func_doc=docscrape_sphinx.SphinxFunctionDoc,
            obj_doc=docscrape_sphinx.SphinxObjDoc,
        )

    extension.get_doc_object = get_doc_object  # type: ignore[assignment]


def setup(app: Any) -> dict[str, Any]:
    app.setup_extension("numpydoc")
    _numpydoc_one_template()
    _plain_module_docstrings(app)
    app.connect("autodoc-process-signature", _no_data_signature, priority=100)
    app.connect("autodoc-skip-member", _skip_member)
    app.connect("env-updated", _add_aliases)
    app.connect("missing-reference", _resolve_missing)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
