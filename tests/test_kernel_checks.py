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
    """An output shorter than n_dof (the issue's case) is refused, naming it."""
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


def _module_of(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    return ".".join(["flexarm", *(parts[:-1] if parts[-1] == "__init__" else parts)])


def _is_module(dotted: str) -> bool:
    """Whether ``dotted`` names one of flexarm's modules or packages."""
    if not dotted.startswith("flexarm."):
        return False
    path = Path(flexarm.__file__).parent.joinpath(*dotted.split(".")[1:])
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _imports(tree: ast.Module, module: str, is_package: bool) -> dict[str, tuple[str, str]]:
    """What the top-level imports of ``module`` bind: local name -> (module, name), with
    ``name`` empty where the local name is a module."""
    package = module if is_package else module.rpartition(".")[0]
    bound: dict[str, tuple[str, str]] = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            base = package.split(".")[: len(package.split(".")) - max(node.level - 1, 0)]
            source = ".".join([*base, node.module] if node.module else base)
            if node.level == 0:
                source = node.module or ""
            for alias in node.names:
                local = alias.asname or alias.name
                sub = f"{source}.{alias.name}"
                if _is_module(sub):
                    bound[local] = (sub, "")  # a module
                else:
                    bound[local] = (source, alias.name)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                bound[alias.asname or alias.name.split(".")[0]] = (alias.name, "")
    return bound


def test_internal_compiled_code_calls_the_bare_kernels():
    """flexarm's own compiled loops call the bare kernels, not the checked public faces:
    inside compiled code a public face is an overload that is not inlined, and one
    compiled with the refcount runtime pays an incref/decref pair for each of the
    model's ~30 arrays at every call (the closed loop ran 1.5x slower that way).
    The runtime-free overloads (``compiled_as(..., runtime_free=True)``) are calls
    by design. A bare kernel may share its face's name in an internal module: a call
    is resolved to the module the name is bound from."""
    root = Path(flexarm.__file__).parent
    trees = {path: ast.parse(path.read_text()) for path in root.rglob("*.py")}
    costly = set()  # (module, name) of the public faces with costly overloads
    for path, tree in trees.items():
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef):
                for dec in node.decorator_list:
                    if (
                        isinstance(dec, ast.Call)
                        and _decorator_name(dec) == "compiled_as"
                        and not any(k.arg == "runtime_free" for k in dec.keywords)
                    ):
                        costly.add((_module_of(path, root), ast.unparse(dec.args[0])))
    assert {"rk4_step", "diverged", "sense", "point_kinematics"} <= {n for _, n in costly}
    offenders = []
    for path, tree in trees.items():
        module = _module_of(path, root)
        bound = _imports(tree, module, path.name == "__init__.py")
        for node in ast.walk(tree):
            if not isinstance(node, ast.FunctionDef):
                continue
            names = {_decorator_name(d) for d in node.decorator_list}
            if not names & {"nb.njit", "njit_runtime_free", "numba.njit", "njit"}:
                continue
            for call in ast.walk(node):
                if not isinstance(call, ast.Call):
                    continue
                f = call.func
                if isinstance(f, ast.Name):
                    target = bound.get(f.id, (module, f.id))
                elif isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name):
                    source, name = bound.get(f.value.id, ("", "?"))
                    target = (source, f.attr) if not name else ("", "")
                else:
                    continue
                if target in costly:
                    offenders.append(f"{path.relative_to(root)}:{call.lineno} {node.name}")
    assert not offenders, offenders


def test_the_guard_resolves_names_to_their_modules():
    """The guard's resolution itself: a face imported by name, a module's attribute."""
    tree = ast.parse(
        "from ..sensing import _channels\nfrom ..sensing.channels import sense\n"
        "from .integrator import rk4_step\n"
    )
    bound = _imports(tree, "flexarm.sim.loop", False)
    assert bound["_channels"] == ("flexarm.sensing._channels", "")
    assert bound["sense"] == ("flexarm.sensing.channels", "sense")
    assert bound["rk4_step"] == ("flexarm.sim.integrator", "rk4_step")
