"""The public compiled kernels check their arguments when called from Python (a
wrong shape would write past an array's end) and are the bare kernels inside a
user's own Numba loop."""

from __future__ import annotations

import ast
from pathlib import Path

import numba as nb
import numpy as np
import pytest

import flexarm
from flexarm import FlexibleArm
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.fuzzy import evaluate, evaluate_into, evaluate_many, paper_system, workspace_size
from flexarm.fuzzy.compiled import pack_system, unpack_system
from flexarm.model import dynamics
from flexarm.model.arrays import make_workspace
from flexarm.sensing.channels import sense, sensor_arrays
from flexarm.sim import integrator

ARM = FlexibleArm.paper()
N = ARM.n_dof
GOOD = {
    "q": np.full(N, 0.1),
    "dq": np.full(N, 0.2),
    "tau": np.ones(2),
    "ws": make_workspace(N),
    "ddq": np.empty(N),
}


def _call(**changes):
    args = {**GOOD, **changes}
    dynamics.forward_dynamics(
        args["q"], args["dq"], args["tau"], args.get("model", ARM.arrays), args["ws"], args["ddq"]
    )


def test_the_reported_heap_corruption_is_an_error():
    """An output shorter than n_dof (which corrupted the heap before the checks) is
    refused, naming it."""
    with pytest.raises(InvalidValueError, match=r"'ddq' parameter of forward_dynamics.*\(4,\)"):
        dynamics.forward_dynamics(
            np.zeros(4), np.zeros(4), np.zeros(2), ARM.arrays, make_workspace(4), np.empty(2)
        )


@pytest.mark.parametrize(
    "changes, error, name",
    [
        ({"q": np.zeros(3)}, InvalidValueError, "q"),
        ({"q": np.zeros(N, dtype=np.float32)}, InvalidTypeError, "q"),
        ({"q": np.zeros(N, dtype=np.int64)}, InvalidTypeError, "q"),
        ({"q": [0.0] * N}, InvalidTypeError, "q"),
        ({"dq": np.zeros(2 * N)[::2]}, InvalidValueError, "dq"),
        ({"tau": np.zeros(3)}, InvalidValueError, "tau"),
        ({"ws": make_workspace(N + 1)}, InvalidValueError, "ws.mass"),
        ({"ws": None}, InvalidTypeError, "ws"),
        ({"ddq": np.empty(N + 1)}, InvalidValueError, "ddq"),
        ({"ddq": np.zeros(N).view()}, None, None),  # a writable view is fine
        ({"model": ARM.arrays._replace(modal_mass=np.zeros((3, 3)))}, InvalidValueError, "model"),
        (
            {"model": ARM.arrays._replace(mode_start=np.array([2, 9, 9]))},
            InvalidValueError,
            "model",
        ),
        ({"model": tuple(ARM.arrays)}, InvalidTypeError, "model"),
    ],
)
def test_forward_dynamics_checks_every_argument(changes, error, name):
    if error is None:
        _call(**changes)
        return
    with pytest.raises(error, match=rf"'{name}"):
        _call(**changes)


def test_a_read_only_output_is_refused():
    out = np.empty(N)
    out.flags.writeable = False
    with pytest.raises(InvalidValueError, match=r"'ddq'.*writable"):
        _call(ddq=out)


@nb.njit
def _users_loop(q, dq, tau, model, ws, ddq, out):
    """What a user writes: the public names inside a compiled loop."""
    for k in range(out.shape[0]):
        dynamics.forward_dynamics(q, dq, tau, model, ws, ddq)
        out[k] = ddq[k % ddq.shape[0]]
        q[0] += 1e-3


@pytest.mark.parametrize("arm", [ARM, FlexibleArm.paper(n_modes=2)], ids=["paper", "two modes"])
def test_inside_compiled_code_the_names_are_the_kernels(arm):
    """The same accelerations from a compiled loop as from checked Python calls."""
    n = arm.n_dof
    q, dq, tau = np.full(n, 0.1), np.full(n, 0.2), np.ones(2)
    out = np.empty(5)
    _users_loop(q.copy(), dq, tau, arm.arrays, make_workspace(n), np.empty(n), out)
    want = []
    qq = q.copy()
    for k in range(5):
        ddq = np.empty(n)
        dynamics.forward_dynamics(qq, dq, tau, arm.arrays, make_workspace(n), ddq)
        want.append(ddq[k % n])
        qq[0] += 1e-3
    np.testing.assert_array_equal(out, want)


def test_the_other_model_kernels_check_too():
    ws, s = make_workspace(N), np.zeros((6, N))
    with pytest.raises(InvalidValueError, match="'rhs'"):
        dynamics.joint_forces(GOOD["q"], GOOD["dq"], GOOD["tau"], ARM.arrays, np.empty(1))
    with pytest.raises(InvalidValueError, match="'ws"):
        dynamics.mass_and_bias(GOOD["q"], GOOD["dq"], ARM.arrays, make_workspace(2))
    with pytest.raises(InvalidValueError, match="'out'"):
        dynamics.point_kinematics(
            GOOD["q"], GOOD["dq"], ARM.arrays, 1, 4.5, np.ones(1), np.empty(3)
        )
    with pytest.raises(InvalidValueError, match="'link'"):
        dynamics.point_kinematics(
            GOOD["q"], GOOD["dq"], ARM.arrays, 2, 4.5, np.ones(1), np.empty(4)
        )
    with pytest.raises(InvalidValueError, match="'s'"):
        integrator.rk4_step(
            GOOD["q"].copy(),
            GOOD["dq"].copy(),
            GOOD["tau"],
            GOOD["tau"],
            GOOD["tau"],
            1e-3,
            ARM.arrays,
            ws,
            np.zeros((5, N)),
        )
    with pytest.raises(InvalidValueError, match="two links with one mode"):
        arm3 = FlexibleArm.paper(n_modes=2)
        integrator.rk4_step_two_links_one_mode(
            np.zeros(6), np.zeros(6), GOOD["tau"], GOOD["tau"], GOOD["tau"], 1e-3, arm3.arrays
        )
    q = GOOD["q"].copy()
    integrator.rk4_step(
        q, GOOD["dq"].copy(), GOOD["tau"], GOOD["tau"], GOOD["tau"], 1e-3, ARM.arrays, ws, s
    )
    assert np.all(np.isfinite(q))
    sensed = sensor_arrays(
        link=-1,
        rigid=False,
        distance=0.0,
        phi=np.zeros(0),
        levers=np.array([4.5, 4.5]),
        delay_steps=0,
        pade=None,
        levels=np.zeros(4),
        resolution=np.zeros(4),
    )
    with pytest.raises(InvalidValueError, match="'out'"):
        sense(GOOD["q"], GOOD["dq"], ARM.arrays, sensed, np.empty(2))


def test_the_fuzzy_kernels_check_their_scratch():
    system = paper_system().compiled()
    need = workspace_size(system)
    x = np.array([0.1, -0.2])
    value = evaluate_into(system, x, np.empty(need))
    assert value == evaluate(system, x) == evaluate_many(system, x[None, :])[0]
    with pytest.raises(InvalidValueError, match=r"'buf'.*at least"):
        evaluate_into(system, x, np.empty(need - 1))
    with pytest.raises(InvalidValueError, match="'x'"):
        evaluate(system, np.zeros(3))
    with pytest.raises(InvalidValueError, match="'x'"):
        evaluate_many(system, np.zeros((4, 3)))
    with pytest.raises(InvalidValueError, match="'system'"):
        evaluate(system._replace(rule_cons=system.rule_cons + 99), x)
    with pytest.raises(InvalidTypeError, match="'system'"):
        evaluate(tuple(system), x)
    packed = pack_system(system)
    assert evaluate(unpack_system(packed, 0), x) == value
    with pytest.raises(InvalidValueError, match="'p'"):
        unpack_system(packed[:10], 0)


def _decorator_name(node: ast.expr) -> str:
    target = node.func if isinstance(node, ast.Call) else node
    return ast.unparse(target)


ROOT = Path(flexarm.__file__).parent
COMPILED = {"nb.njit", "njit_runtime_free", "numba.njit", "njit"}


def _module_of(path: Path) -> str:
    """Dotted name of a flexarm source file: "flexarm.model.dynamics._points"."""
    parts = ["flexarm", *path.relative_to(ROOT).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(module: str, tree: ast.Module, is_package: bool) -> dict[str, str]:
    """Local name -> the dotted object it stands for, from the module's imports
    ("point_kinematics" -> "flexarm.model.dynamics._points.point_kinematics")."""
    package = module if is_package else module.rpartition(".")[0]
    found = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")
            if node.level:
                base = base[: len(base) - (node.level - 1)]
                source = ".".join([*base, node.module] if node.module else base)
            else:
                source = node.module or ""
            for alias in node.names:
                found[alias.asname or alias.name] = f"{source}.{alias.name}"
        elif isinstance(node, ast.Import):
            for alias in node.names:
                found[alias.asname or alias.name] = alias.name
    return found


def _costly_calls(sources: dict[str, tuple[ast.Module, bool]]) -> tuple[set[str], list[str]]:
    """The checked public faces whose compiled overload is a costly call (compiled
    with the refcount runtime), as dotted names, and the calls of them from
    flexarm's own compiled functions ("module:line function")."""
    imports = {m: _imports(m, tree, pkg) for m, (tree, pkg) in sources.items()}

    def resolve(dotted: str) -> str:
        """Follow re-exports: the dotted name of where the object is defined."""
        for _ in range(10):
            module, _, name = dotted.rpartition(".")
            if module not in imports or name not in imports[module]:
                return dotted
            dotted = imports[module][name]
        return dotted

    costly = set()
    for module, (tree, _) in sources.items():
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef):
                for dec in node.decorator_list:
                    if (
                        isinstance(dec, ast.Call)
                        and _decorator_name(dec) == "compiled_as"
                        and not any(k.arg == "runtime_free" for k in dec.keywords)
                    ):
                        face = ast.unparse(dec.args[0])
                        costly.add(resolve(imports[module].get(face, f"{module}.{face}")))
    offenders = []
    for module, (tree, _) in sources.items():
        local = {n.name for n in tree.body if isinstance(n, ast.FunctionDef | ast.ClassDef)}
        for node in ast.walk(tree):
            if not isinstance(node, ast.FunctionDef):
                continue
            if not {_decorator_name(d) for d in node.decorator_list} & COMPILED:
                continue
            for call in ast.walk(node):
                if not isinstance(call, ast.Call):
                    continue
                head, _, rest = ast.unparse(call.func).partition(".")
                if head in imports[module]:
                    target = imports[module][head]
                elif head in local:
                    target = f"{module}.{head}"
                else:
                    continue
                if resolve(".".join(filter(None, [target, rest]))) in costly:
                    offenders.append(f"{module}:{call.lineno} {node.name}")
    return costly, offenders


def test_internal_compiled_code_calls_the_bare_kernels():
    """flexarm's own compiled loops call the bare kernels of the internal modules, not
    the checked public faces: inside compiled code a public name is an overload that
    is not inlined, and one compiled with the refcount runtime pays an incref/decref
    pair for each of the model's ~30 arrays at every call (the closed loop ran 1.5x
    slower that way). The runtime-free overloads (``compiled_as(...,
    runtime_free=True)``) are calls by design. A name is what the module imports it
    as, followed through re-exports: a bare kernel may share its checked face's name."""
    sources = {
        _module_of(path): (ast.parse(path.read_text()), path.name == "__init__.py")
        for path in ROOT.rglob("*.py")
    }
    costly, offenders = _costly_calls(sources)
    assert {
        "flexarm.sim.integrator.rk4_step",
        "flexarm.sim.integrator.diverged",
        "flexarm.sensing.channels.sense",
        "flexarm.model.dynamics.point_kinematics",
    } <= costly
    assert not offenders, offenders


def test_the_guard_tells_a_checked_face_from_its_bare_kernel():
    """The guard above reports a call of a public face, under its own name or a
    module's, and not the bare kernel of the same name."""
    sources = {
        "flexarm.lib": (ast.parse("@compiled_as(face)\ndef _(x):\n    return None\n"), False),
        "flexarm._bare": (ast.parse("def face(x):\n    return x\n"), False),
        "flexarm.user": (
            ast.parse(
                "from . import lib\nfrom .lib import face\nfrom ._bare import face as bare\n"
                "@nb.njit\ndef f(x):\n    face(x)\n    lib.face(x)\n    bare(x)\n"
            ),
            False,
        ),
    }
    costly, offenders = _costly_calls(sources)
    assert costly == {"flexarm.lib.face"}
    assert offenders == ["flexarm.user:6 f", "flexarm.user:7 f"]
