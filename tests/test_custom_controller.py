"""Your own controller by name ("module:factory") in scenario files and on the command
line: the example runs, the options reach the factory, every failure is one line."""

from __future__ import annotations

import os
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest

import flexarm as fa
from flexarm.cli import main
from flexarm.control.controllers import CompiledController, wrap_control_function
from flexarm.control.custom import call_factory, is_factory_spec, load_factory
from flexarm.errors import InvalidTypeError, ScenarioError
from flexarm.sim.scenario import Scenario, load_scenario

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "my_controller.toml"

MODULE = """
import flexarm.control.controllers as c
from my_controller import make

not_callable = 3

def wrong_type(arm):
    return {"kp": 1.0}

def boom(arm):
    raise RuntimeError("no controller today")

def strict(arm, gain):
    return make(arm, kp=gain)
"""


@pytest.fixture
def mods(tmp_path, monkeypatch):
    """``flexarm_test_factories`` beside a scenario file in ``tmp_path``; the example's
    directory on sys.path (the module imports ``my_controller``)."""
    (tmp_path / "flexarm_test_factories.py").write_text(MODULE)
    scenario = tmp_path / "scenario.toml"
    scenario.write_text("")
    monkeypatch.syspath_prepend(str(ROOT / "examples"))
    yield scenario
    for name in ("flexarm_test_factories", "my_controller"):
        sys.modules.pop(name, None)


def test_the_example_scenario_builds_and_runs():
    s = load_scenario(EXAMPLE)  # my_controller.py is found beside the file
    assert isinstance(s.controller, CompiledController)
    assert s.description["controller"] == {
        "kind": "my_controller:make",
        "name": "pd+strain",
        "kp": 200.0,
        "kd": 40.0,
        "strain_gain": 0.0,
    }
    res = fa.simulate(s.arm, **{**s.simulate_kwargs(), "duration": 0.05})
    assert res.info["controller"] == "pd+strain" and np.all(np.isfinite(res.q))
    sys.modules.pop("my_controller", None)


def test_the_options_reach_the_factory(mods):
    data = {"controller": {"kind": "flexarm_test_factories:strict", "gain": 321.0}}
    s = Scenario.from_dict(data, source=str(mods))
    assert s.controller.parameters(s.arm)[0] == 321.0


def test_the_command_line_runs_a_factory(capsys, monkeypatch):
    monkeypatch.chdir(ROOT / "examples")  # found in the current directory
    status = main(["simulate", "--controller", "my_controller:make", "--duration", "0.02"])
    out, err = capsys.readouterr()
    assert status == 0 and "controller my_controller:make" in out and not err
    sys.modules.pop("my_controller", None)


@pytest.mark.parametrize(
    ("kind", "extra", "match"),
    [
        ("flexarm_nonesuch_mod:make", {}, "cannot import module 'flexarm_nonesuch_mod'"),
        ("flexarm_test_factories:missing", {}, "has no attribute 'missing'"),
        ("flexarm_test_factories:not_callable", {}, "is not callable. Got int"),
        ("flexarm_test_factories:wrong_type", {}, "must return a flexarm Controller .*Got dict"),
        ("flexarm_test_factories:boom", {}, "failed: RuntimeError: no controller today"),
        ("flexarm_test_factories:strict", {"gian": 1.0}, "rejected its arguments"),
    ],
)
def test_failures_name_the_key(mods, kind, extra, match):
    key = "controller" if kind.endswith(("strict", "wrong_type", "boom")) else "controller.kind"
    with pytest.raises(ScenarioError, match=match) as info:
        Scenario.from_dict({"controller": {"kind": kind, **extra}}, source=str(mods))
    assert info.value.key == key
    assert str(info.value).startswith(f"{mods}: {key}: ")


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("flexarm_nonesuch_mod:make", "argument --controller: cannot import module"),
        ("not a spec", "argument --controller: must be one of pd, .* or MODULE:FACTORY"),
    ],
)
def test_command_line_failures_are_one_line_with_status_2(capsys, value, match):
    status = main(["simulate", "--controller", value, "--duration", "0.02"])
    out, err = capsys.readouterr()
    assert status == 2 and not out
    assert len(err.strip().splitlines()) == 1 and re.search(match, err)


def test_the_spec_and_the_loader():
    assert is_factory_spec("a.b_c:make") and not is_factory_spec("a:b:c")
    with pytest.raises(ValueError, match="must be 'module:factory'"):
        load_factory("pd")
    joint_pd = load_factory("flexarm.control.controllers:JointPD")
    ctrl = call_factory(lambda arm, kp: joint_pd(kp=kp), "pd", fa.FlexibleArm.paper(), {"kp": 5.0})
    assert ctrl.kp == 5.0


# ------------------------------------------------------------------ the compiled callback
LAWS = """
import numba as nb
from flexarm.control.controllers import wrap_control_function

@nb.njit(cache=True)
def double(t, y, r, p, s, tau):
    tau[0] = 2.0 * p[0]

@nb.njit(cache=True)
def triple(t, y, r, p, s, tau):
    tau[0] = 3.0 * p[0]

callbacks = [wrap_control_function(f, cache=True) for f in (double, triple)]
"""

RUN = """
import ctypes, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import laws

p, tau, empty = np.array([1.5]), np.zeros(1), np.zeros(1)
ptr = lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
out = []
for cf in laws.callbacks:
    cf.ctypes(0.0, ptr(empty), 0, ptr(empty), 0, ptr(p), 1, ptr(empty), 0, ptr(tau), 1)
    out.append(f"{tau[0]} {cf.cache_hits}")
print(";".join(out))
"""


def test_wrapped_laws_are_cached_apart_and_read_back_in_a_new_process(tmp_path):
    """Each law's callback has a cache entry of its own (two laws of one module do not
    share one) that a second process loads instead of compiling again."""
    (tmp_path / "laws.py").write_text(LAWS)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}

    def run():
        done = subprocess.run(
            [sys.executable, "-c", RUN, str(tmp_path)],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        return done.stdout.strip()

    assert run() == "3.0 0;4.5 0"  # compiled: 2 p and 3 p
    assert run() == "3.0 1;4.5 1"  # read back from the cache, each its own


def test_wrap_control_function_needs_a_compiled_law():
    def plain(t, y, r, p, s, tau):
        tau[0] = 0.0

    with pytest.raises(InvalidTypeError, match=r"'fn' parameter of wrap_control_function"):
        wrap_control_function(plain)
