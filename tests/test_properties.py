"""Property-based tests (Hypothesis) of the validators and parsers: whatever comes in,
the answer is a valid object or a ``ValueError``/``TypeError`` naming what is wrong —
never another exception."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from flexarm import FlexibleArm, Link
from flexarm._budget import MEMORY_ENV, memory_limit
from flexarm._validation import check_array, check_int, check_real
from flexarm.cli._common import number
from flexarm.control.controllers import JacobianTransposePD, JointPD
from flexarm.control.trajectories import Circle, Square
from flexarm.errors import FlexarmError, InvalidTypeError, InvalidValueError
from flexarm.model.beam import BeamModes
from flexarm.sensing.sensors import JointSensor, PointSensor, parse_sensor
from flexarm.sim.results import SimulationError
from flexarm.sim.scenario import Scenario
from flexarm.sim.scenario_schema import SECTIONS, ScenarioError

# Anything a user might pass where a number is expected.
ANYTHING = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.complex_numbers(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=3),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
)
SLOW = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _named(exc: BaseException, *names: str) -> bool:
    text = str(exc)
    return any(f"'{n}'" in text or n in text for n in names)


# ------------------------------------------------------------------ the checks themselves
@given(value=ANYTHING)
def test_check_real_validates_or_names_the_parameter(value):
    try:
        out = check_real(value, "length", "Owner", positive=True)
    except (InvalidValueError, InvalidTypeError) as exc:
        assert "'length' parameter of Owner" in str(exc)
    else:
        assert isinstance(out, float) and math.isfinite(out) and out > 0


@given(value=ANYTHING)
def test_check_int_validates_or_names_the_parameter(value):
    try:
        out = check_int(value, "n_modes", "Owner", minimum=1)
    except (InvalidValueError, InvalidTypeError) as exc:
        assert "'n_modes' parameter of Owner" in str(exc)
    else:
        assert isinstance(out, int) and out >= 1


@given(value=ANYTHING)
def test_check_array_validates_or_names_the_parameter(value):
    try:
        out = check_array(value, "q", "Owner", shape=(2,))
    except (InvalidValueError, InvalidTypeError) as exc:
        assert "'q' parameter of Owner" in str(exc)
    else:
        assert out.shape == (2,) and np.all(np.isfinite(out))


# ------------------------------------------------------------------ constructors
CONSTRUCTORS = {
    "Link.length": (lambda v: Link(v, 1676.0, 0.335), ("length",)),
    "Link.flexural_rigidity": (lambda v: Link(4.5, v, 0.335), ("flexural_rigidity",)),
    "Link.linear_density": (lambda v: Link(4.5, 1676.0, v), ("linear_density",)),
    "Link.n_modes": (lambda v: Link(4.5, 1676.0, 0.335, n_modes=v), ("n_modes",)),
    "Link.hub_inertia": (lambda v: Link(4.5, 1676.0, 0.335, hub_inertia=v), ("hub_inertia",)),
    "BeamModes.tip_mass": (lambda v: BeamModes(4.5, 1676.0, 0.335, tip_mass=v), ("tip_mass",)),
    "BeamModes.length": (
        lambda v: BeamModes(v, 1676.0, 0.335),
        ("length", "flexural_rigidity"),
    ),
    "Square.side": (lambda v: Square(side=v), ("side",)),
    "Square.center": (lambda v: Square(center=v), ("center",)),
    "Circle.radius": (lambda v: Circle(radius=v), ("radius",)),
    "JointSensor.noise_std": (lambda v: JointSensor(noise_std=v), ("noise_std",)),
    "PointSensor.distance": (lambda v: PointSensor(1, v), ("distance",)),
    "PointSensor.link": (lambda v: PointSensor(v, 0.5), ("link",)),
    "JointPD.kp": (lambda v: JointPD(kp=v).parameters(FlexibleArm.paper()), ("kp",)),
    "JacobianTransposePD.kd": (lambda v: JacobianTransposePD(kd=v), ("kd",)),
}


@pytest.mark.parametrize("name", sorted(CONSTRUCTORS))
@SLOW
@given(value=ANYTHING)
@example(value=2.2034940565285207e307)  # found on a fresh database: a tip mass overflowed
def test_constructors_validate_or_name_the_parameter(name, value):
    build, names = CONSTRUCTORS[name]
    try:
        build(value)
    except (InvalidValueError, InvalidTypeError) as exc:
        assert _named(exc, *names), str(exc)


@given(spec=st.one_of(st.text(max_size=20), st.from_regex(r"point:-?\d{0,2}:[-\d.e]{0,6}")))
def test_sensor_specs_parse_or_are_named(spec):
    try:
        sensor = parse_sensor(spec)
    except (InvalidValueError, InvalidTypeError) as exc:
        assert "sensor" in str(exc).lower() or "spec" in str(exc)
    else:
        assert sensor.name in ("joint", "tip", "point")


@given(text=st.text(max_size=12))
def test_command_line_numbers_parse_or_explain(text):
    import argparse

    for parse in (number(positive=True), number(nonnegative=True), number(integer=True)):
        try:
            value = parse(text)
        except argparse.ArgumentTypeError as exc:
            assert "must be" in str(exc) and "Got" in str(exc)
        else:
            assert math.isfinite(value)


@given(text=st.text(max_size=10).filter(lambda t: "\x00" not in t))
def test_memory_limits_parse_or_name_the_variable(text):
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(MEMORY_ENV, text)
        try:
            limit = memory_limit()
        except InvalidValueError as exc:
            assert MEMORY_ENV in str(exc)
        else:
            assert limit > 0


# ------------------------------------------------------------------ scenario files
KEYS = {
    "arm": [
        "preset",
        "n_modes",
        "boundary",
        "payload_mass",
        "payload_inertia",
        "links",
        "joints",
        "mode_amplitude",
    ],
    "trajectory": ["kind", "side", "center", "time_per_side", "radius", "period", "dwell"],
    "sensor": ["kind", "link", "distance", "noise_std", "model", "quantization"],
    "controller": ["kind", "kp", "kd", "zeta", "ks", "law", "alpha"],
    "delay": ["delay", "method", "order", "reference"],
    "shaper": ["kind", "modes", "damping"],
    "simulation": [
        "duration",
        "dt",
        "substeps",
        "torque_limit",
        "seed",
        "elbow",
        "max_deflection",
        "smoothing",
        "record_every",
        "check_sampling",
    ],
}
WORDS = st.sampled_from(
    [
        "square",
        "circle",
        "joint",
        "tip",
        "point",
        "pd",
        "jt-pd",
        "joint-pd",
        "fuzzy",
        "lqg",
        "reflected",
        "exact",
        "pade",
        "zv",
        "ei",
        "none",
        "first",
        "all",
        "paper",
        "physical",
        "positive",
        "negative",
        "clamped-mass",
        "seed",
        "dispersive",
        "bogus",
    ]
)
VALUES = st.one_of(
    WORDS,
    st.booleans(),
    st.integers(min_value=-3, max_value=6),
    st.floats(min_value=-10.0, max_value=10.0),
    st.sampled_from([0.0, 1e-9, 1e9, 1e300, math.inf, -math.inf, math.nan]),
    st.lists(st.floats(min_value=-5, max_value=5), max_size=3),
    st.text(max_size=4),
)


@st.composite
def scenarios(draw):
    data = {}
    for section in draw(st.lists(st.sampled_from([*SECTIONS, "bogus"]), max_size=4, unique=True)):
        if section == "bogus":
            data[section] = {"x": 1}
            continue
        keys = draw(
            st.lists(st.sampled_from([*KEYS[section], "bogus_key"]), max_size=3, unique=True)
        )
        data[section] = {k: draw(VALUES) for k in keys}
    return data


@SLOW
@given(data=scenarios())
# found by Hypothesis on a fresh example database: an overflow warning, a key not given
# blamed, a singular mass matrix from NumPy
@example(data={"trajectory": {"time_per_side": 1e300}})
@example(data={"trajectory": {"time_per_side": 1e-9}})
@example(data={"arm": {"payload_inertia": 1e300}})
def test_any_scenario_loads_or_is_refused_naming_its_key(data):
    """A mapping either builds a scenario (which then runs, or is refused by the
    simulator with a flexarm error) or is refused with a ScenarioError naming a
    section or key of the mapping."""
    try:
        scenario = Scenario.from_dict(data, source="prop")
    except ScenarioError as exc:
        named = {f"{s}.{k}" for s, t in data.items() if isinstance(t, dict) for k in t}
        named |= set(data)
        assert exc.key is None or exc.key in named or exc.key.split(".")[0] in data, exc
        assert str(exc).startswith("prop")
        return
    duration = min(float(scenario.simulation.duration), 0.004)
    try:
        result = scenario.simulate(duration=duration)
    except (SimulationError, FlexarmError):
        return
    assert result.info["status"] == "ok"


# ------------------------------------------------------------------ data files
@settings(max_examples=80, deadline=None)
@given(content=st.binary(max_size=200), suffix=st.sampled_from([".csv", ".txt", ".npz"]))
def test_any_data_file_reads_or_is_refused_in_one_line(content, suffix, tmp_path_factory):
    from flexarm.ident.data import DataError, read_xy

    path = tmp_path_factory.mktemp("data") / f"d{suffix}"
    path.write_bytes(content)
    try:
        x, y, _ = read_xy(path)
    except DataError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc)
    else:
        assert x.shape == y.shape and x.shape[0] >= 2


@settings(max_examples=60, deadline=None)
@given(
    rows=st.lists(
        st.tuples(st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True)),
        min_size=0,
        max_size=6,
    ),
    sep=st.sampled_from([",", ";", "\t"]),
)
def test_delimited_numbers_read_back(rows, sep, tmp_path_factory):
    from flexarm.ident.data import DataError, read_xy

    path = tmp_path_factory.mktemp("data") / "d.csv"
    path.write_text("x" + sep + "y\n" + "".join(f"{a!r}{sep}{b!r}\n" for a, b in rows))
    try:
        x, y, _ = read_xy(path, delimiter=sep)
    except DataError as exc:
        assert re.search(r"NaN|infinite|at least 2|no data|holds no", str(exc)), str(exc)
        assume(False)
    else:
        np.testing.assert_array_equal(np.c_[x, y], np.array(rows, dtype=float))
