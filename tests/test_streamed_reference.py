"""The reference computed in the loop, instant by instant (paths of straight
segments), against the reference precomputed by the pipeline: the same runs bit
for bit, the same errors, and the tip recorded in the loop equal to the arm's
own kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from flexarm import FlexibleArm, simulate
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.trajectories import Circle, Line, Square, Waypoints, straight_segments
from flexarm.errors import InvalidValueError
from flexarm.model.arm import Link
from flexarm.sensing.delays import DelayModel
from flexarm.sensing.sensors import JointSensor, PointSensor
from flexarm.sim import loop
from flexarm.sim._reference_kernels import no_stream, reference_stream, stream_rows
from flexarm.sim.references import ReferencePipeline
from flexarm.sim.results import SimulationError

SERIES = ("t", "q", "dq", "tau", "measurement", "reference", "desired", "tip")
ARM = FlexibleArm.paper()
ARM_LAW = JacobianTransposePD.from_arm(ARM)


class Precomputed(JacobianTransposePD):
    """The paper's law, with a design that may read the reference: the simulator
    then precomputes it (the path the streamed one must reproduce)."""

    def design(self, arm, sensor, dt, reference):  # type: ignore[no-untyped-def]
        assert reference.shape[0] > 1
        return super().design(arm, sensor, dt, reference)


def _both(**kwargs):
    law = JacobianTransposePD.from_arm(ARM)
    streamed = simulate(ARM, law, **kwargs)
    precomputed = simulate(ARM, Precomputed(kp=law.kp, kd=law.kd), **kwargs)
    return streamed, precomputed


def _assert_same(a, b):
    for name in SERIES:
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape, name
        assert np.array_equal(x, y, equal_nan=True), name


SHORT = {"duration": 0.6}
CASES = {
    "square": {"trajectory": Square(time_per_side=0.15), **SHORT},
    "square, cw, dwell, third corner": {
        "trajectory": Square(time_per_side=0.12, direction="cw", dwell=0.03, start_corner=2),
        **SHORT,
    },
    "line": {"trajectory": Line((4.0, -1.0), (6.0, 1.5), 0.4, timing="constant"), **SHORT},
    "waypoints": {
        "trajectory": Waypoints([[4, 0], [5, 1], [6, 1], [6, 1], [4, 0]], [0, 0.1, 0.2, 0.3, 0.5]),
        **SHORT,
    },
    "delayed reference": {
        "trajectory": Square(time_per_side=0.15),
        "delay": DelayModel(4e-4),
        "delay_reference": True,
        **SHORT,
    },
    "record every 7th, noise": {
        "trajectory": Square(time_per_side=0.15),
        "record_every": 7,
        "sensor": JointSensor(noise_std=1e-4),
        "rng": 3,
        **SHORT,
    },
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_streamed_runs_equal_precomputed_ones_bit_for_bit(case):
    streamed, precomputed = _both(**CASES[case])
    assert ARM.n_links == 2 and straight_segments(CASES[case]["trajectory"]) is not None
    _assert_same(streamed, precomputed)


def test_quintic_timing_streamed_is_the_compiled_path():
    """Quintic timing: the stream evaluates the compiled path's formulas at every
    length, the pipeline NumPy's below 4096 instants (whose tau**3 may round
    differently); the references agree to rounding, and bit for bit with the
    pipeline's compiled blocks (runs of 4096 instants or more)."""
    traj = Square(time_per_side=0.25, timing="quintic", dwell=0.05)
    short, short_pre = _both(trajectory=traj, duration=0.6)
    np.testing.assert_allclose(short.reference, short_pre.reference, rtol=1e-13, atol=1e-13)
    long, long_pre = _both(trajectory=traj, duration=0.9)  # 4501 instants: compiled blocks
    _assert_same(long, long_pre)


def test_a_long_streamed_run_equals_the_block_by_block_one():
    """More instants than the reference computed at once (4 x 2**15): the blocks'
    run in chunks against the streamed run in chunks."""
    kwargs = {"trajectory": Square(time_per_side=0.04), "duration": 0.16, "dt": 1e-6}
    kwargs.update(record_every=97, check_sampling=False)
    arm = FlexibleArm([Link(4.5, 1676.0, 0.335, n_modes=1, hub_inertia=1.0)] * 2)
    law = JacobianTransposePD.from_arm(arm)
    a = simulate(arm, law, **kwargs)
    b = simulate(arm, Precomputed(kp=law.kp, kd=law.kd), **kwargs)
    assert a.t.shape[0] > 1600
    _assert_same(a, b)


def test_the_stream_is_the_pipelines_rows():
    """The compiled rows of the stream equal the pipeline's block rows (NumPy glue,
    the path's own evaluate) at every instant of the paper's run."""
    pipeline = ReferencePipeline(ARM, Square(), 2e-4, 100_000)
    stream = pipeline.stream()
    assert stream is not None
    r, d = np.zeros((100_001, pipeline.size)), np.empty((100_001, 2))
    status, _, _ = stream_rows(stream, np.arange(100_001), 2e-4, r, d)
    want_r, want_d = pipeline.rows(0, 100_001)
    assert status == 0
    assert np.array_equal(r, want_r) and np.array_equal(d, want_d)


@pytest.mark.parametrize(
    "options",
    [
        {"trajectory": Circle(), "duration": 0.1},
        {"trajectory": Square(), "smoothing": 0.05, "duration": 0.1},
        {"trajectory": Square(), "feedforward": True, "duration": 0.1},
        {"trajectory": Square(), "sensor": PointSensor(link=1, distance=2.0), "duration": 0.1},
    ],
    ids=["circle", "smoothing", "feedforward", "point short of the tip"],
)
def test_what_cannot_stream_is_precomputed(options):
    options = dict(options)  # (the parameter is shared between runs)
    sensor = options.pop("sensor", None)
    pipeline = ReferencePipeline(
        ARM,
        options["trajectory"],
        2e-4,
        500,
        smoothing=options.get("smoothing", 0.0),
        point=(1, 2.0) if sensor is not None else None,
        feedforward=(lambda th, dth, ddth: np.zeros_like(th)) if "feedforward" in options else None,
    )
    assert pipeline.stream() is None
    res = simulate(ARM, sensor=sensor, **options)  # and the run still works
    assert np.all(np.isfinite(res.reference))


def test_a_streamed_path_out_of_reach_fails_as_the_precomputed_one():
    """Leaving the workspace halfway: the same error, with the same time and point."""
    out = Line((5.0, 0.0), (9.6, 0.0), 0.2)  # reach 9 m
    messages = []
    for law in (ARM_LAW, Precomputed(kp=ARM_LAW.kp, kd=ARM_LAW.kd)):
        with pytest.raises(InvalidValueError, match="workspace") as err:
            simulate(ARM, law, trajectory=out, duration=0.3)
        messages.append(str(err.value))
    assert messages[0] == messages[1]
    assert "t = 0.1" in messages[0]


def test_a_diverged_streamed_run_is_the_precomputed_one():
    kwargs = {"trajectory": Square(time_per_side=0.1), "duration": 0.4, "dt": 2e-3}
    kwargs["check_sampling"] = False  # 500 Hz: the hubless arm's loop diverges
    partial = []
    for law in (ARM_LAW, Precomputed(kp=ARM_LAW.kp, kd=ARM_LAW.kd)):
        with pytest.raises(SimulationError) as err:
            simulate(ARM, law, **kwargs)
        partial.append(err.value.result)
    _assert_same(*partial)
    assert np.all(np.isfinite(partial[0].tip))  # the partial result ends where it diverged


@pytest.mark.parametrize(
    "arm",
    [
        ARM,
        FlexibleArm(
            [Link(2.0, 1676.0, 0.335, n_modes=3, hub_inertia=1.0)] * 2
        ),  # stiffening, 3 modes
    ],
    ids=["paper", "three modes, stiffened"],
)
def test_the_tip_recorded_in_the_loop_is_the_arms_kinematics(arm):
    traj = Square(center=(2.5, 0.0), side=1.0, time_per_side=0.05) if arm is not ARM else None
    res = simulate(arm, trajectory=traj, duration=0.2, record_every=3, dt=5e-5)
    assert np.array_equal(res.tip, arm.tip_position(res.q))


def test_the_loop_refuses_a_bad_stream_or_tip_basis():
    good, law = _loop_inputs()

    def run(**changes):
        outputs = {k[4:]: changes.pop(k) for k in list(changes) if k.startswith("out_")}
        inputs = good._replace(**changes, out=good.out._replace(**outputs))
        return loop.run(inputs, law.cfunc, np.zeros((0, 14)), np.zeros((0, 4)), 0, 2)

    with pytest.raises(InvalidValueError, match="'stream' parameter of run"):
        run(stream="square")
    bad_spec = no_stream()._replace(spec=np.zeros(6))
    with pytest.raises(InvalidValueError, match=r"stream\.spec"):
        run(stream=bad_spec)
    with pytest.raises(InvalidValueError, match="'tip_phi' parameter of run"):
        run(tip_phi=np.zeros(5), out_tip=np.empty((3, 2)))
    with pytest.raises(InvalidValueError, match=r"'out\.r' parameter of run"):
        run(out_r=np.empty((1, 14)))
    with pytest.raises(InvalidValueError, match="'loop' parameter of run"):
        loop.run(tuple(good), law.cfunc, np.zeros((0, 14)), np.zeros((0, 4)), 0, 2)
    with pytest.raises(InvalidValueError, match="'noise' parameter of run"):
        loop.run(good, law.cfunc, np.zeros((0, 14)), np.zeros((1, 4)), 0, 2)
    status, k = run()
    assert (status, k) == (loop.OK, 2)


def _loop_inputs():
    """A streamed two-instant run of the paper's arm: its Loop, and the law."""
    from flexarm.sensing.channels import sensor_arrays

    sensor = sensor_arrays(
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
    law = JacobianTransposePD.from_arm(ARM)
    knot_t, knot_p, quintic = straight_segments(Square())  # type: ignore[misc]
    stream = reference_stream(
        knot_t,
        knot_p,
        quintic=quintic,
        delay=0.0,
        lengths=(4.5, 4.5),
        sign=1.0,
        singularity_tol=1e-6,
    )
    inputs = loop.loop_inputs(
        model=ARM.arrays,
        params=law.parameters(ARM),
        sensor=sensor,
        stream=stream,
        dt=2e-4,
        substeps=1,
        n_steps=1,
        every=1,
        torque_limit=np.full(2, np.inf),
        max_deflection=np.full(2, 4.5),
        q=np.zeros(4),
        dq=np.zeros(4),
        controller_state=np.zeros(0),
        tip_phi=ARM.point_basis(1, 4.5),
        reference=None,
        recorded=2,
    )
    return inputs, law
