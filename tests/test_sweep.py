"""Parameter sweeps (flexarm.sweeps): expansion, draws, per-run failures, the table,
the journal and resuming, and a Dask cluster that gives the local table bit for bit.

Every simulated run is a few hundredths of a second of the paper's arm.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

import flexarm
from flexarm.errors import InvalidTypeError, InvalidValueError, SweepError, SweepTypeError
from flexarm.sweeps import driver, execute
from flexarm.sweeps.distributions import Choice, Integers, LogUniform, Normal, Uniform, key_rng
from flexarm.sweeps.driver import SweepInterrupted, sweep
from flexarm.sweeps.execute import prefer_processes
from flexarm.sweeps.journal import JOURNAL_FILE, Journal, read_journal
from flexarm.sweeps.keys import KeyPathError, parse_key, run_id, with_changes
from flexarm.sweeps.spec import METRICS, SweepSpec
from flexarm.sweeps.table import SweepTable

SHORT = {"simulation": {"duration": 0.02}}


def spec_of(**sections):
    return SweepSpec.from_dict({"base": SHORT, **sections})


@pytest.fixture
def counted(monkeypatch):
    """Count the runs actually simulated (the function each pool thread calls); the
    count is kept in this process, so the sweeps run in threads."""
    calls = []
    real = execute.run_scenario

    def run(scenario):
        calls.append(scenario)
        return real(scenario)

    monkeypatch.setattr(execute, "run_scenario", run)
    monkeypatch.setattr(driver, "prefer_processes", lambda runs, workers: False)
    return calls


# ------------------------------------------------------------------ expansion
def test_grid_is_the_cartesian_product_with_the_last_key_fastest():
    spec = spec_of(grid={"controller.zeta": [0.5, 0.6, 0.7], "sensor": {"noise_std": [0.0, 1e-4]}})
    assert spec.n_runs == 6 == len(spec.runs)
    assert spec.parameters == ("controller.zeta", "sensor.noise_std")
    got = [(r.params["controller.zeta"], r.params["sensor.noise_std"]) for r in spec.runs]
    assert got == [(z, s) for z in (0.5, 0.6, 0.7) for s in (0.0, 1e-4)]
    assert [r.index for r in spec.runs] == list(range(6))
    assert len({r.run_id for r in spec.runs}) == 6


def test_several_grids_run_one_after_the_other():
    spec = spec_of(
        grid=[
            {"sensor.kind": ["joint"], "controller.zeta": [0.5, 0.7]},
            {"sensor.kind": ["point"], "sensor.distance": [0.5, 1.0, 2.0]},
        ]
    )
    assert spec.n_runs == 5 and spec.first_runs == (0, 2)
    assert spec.parameters == ("sensor.kind", "controller.zeta", "sensor.distance")
    assert [r.params.get("sensor.distance") for r in spec.runs] == [None, None, 0.5, 1.0, 2.0]


def test_grid_times_monte_carlo_uses_the_same_draws_at_every_point():
    mc = {"n": 3, "seed": 7, "simulation.seed": {"distribution": "integers", "low": 0, "high": 99}}
    spec = spec_of(grid={"controller.zeta": [0.5, 0.7]}, monte_carlo=mc)
    assert spec.n_runs == 6
    seeds = [r.params["simulation.seed"] for r in spec.runs]
    assert seeds[:3] == seeds[3:]
    assert [r.params["controller.zeta"] for r in spec.runs] == [0.5] * 3 + [0.7] * 3


def test_monte_carlo_is_reproducible_from_its_seed():
    def draws(seed, keys=("controller.zeta", "sensor.noise_std"), n=5):
        dists = {
            "controller.zeta": {"distribution": "uniform", "low": 0.4, "high": 0.9},
            "sensor.noise_std": {"distribution": "loguniform", "low": 1e-6, "high": 1e-3},
        }
        mc = {"n": n, "seed": seed, **{k: dists[k] for k in keys}}
        return [r.params for r in spec_of(monte_carlo=mc).runs]

    a = draws(3)
    assert a == draws(3)  # the same seed, the same runs
    assert a != draws(4)
    # a key's draws depend neither on the other keys nor on their order nor on n
    assert [p["controller.zeta"] for p in a] == [
        p["controller.zeta"] for p in draws(3, keys=("controller.zeta",))
    ]
    assert [p["controller.zeta"] for p in a] == [
        p["controller.zeta"] for p in draws(3, keys=("sensor.noise_std", "controller.zeta"))
    ]
    assert draws(3, n=8)[:5] == a
    # and the run ids too: a grown sweep reuses the runs it had
    ids = [
        r.run_id
        for r in spec_of(
            monte_carlo={
                "n": 5,
                "seed": 3,
                "arm.payload_mass": {"distribution": "uniform", "low": 0.0, "high": 1.0},
            }
        ).runs
    ]
    assert len(set(ids)) == 5


@pytest.mark.parametrize(
    ("dist", "check"),
    [
        (Uniform(0.5, 0.9), lambda x: 0.5 <= x < 0.9),
        (LogUniform(1e-6, 1e-3), lambda x: 1e-6 <= x < 1e-3),
        (Integers(3, 6), lambda x: isinstance(x, int) and 3 <= x < 6),
        (Choice(("a", "b", "c"), (1.0, 0.0, 1.0)), lambda x: x in ("a", "c")),
        (Normal(2.0, 0.0), lambda x: x == 2.0),
    ],
)
def test_distributions_draw_in_their_support(dist, check):
    values = dist.draw(key_rng(0, "k"), 200)
    assert len(values) == 200 and all(check(v) for v in values)


def test_distributions_have_their_moments():
    rng = key_rng(11, "x")
    x = np.array(Normal(150.0, 10.0).draw(rng, 20000))
    assert abs(x.mean() - 150.0) < 0.3 and abs(x.std() - 10.0) < 0.3
    u = np.log(LogUniform(1e-4, 1e-2).draw(key_rng(11, "y"), 20000))
    assert abs(u.mean() - np.log(1e-3)) < 0.05  # uniform in the logarithm


# ------------------------------------------------------------------ keys
def test_dotted_keys_and_kind_changes():
    assert parse_key("arm.links[1].length") == ("arm", "links", 1, "length")
    base = {"arm": {"links": [{"length": 1.0}, {"length": 2.0}]}, "controller": {"zeta": 0.5}}
    out = with_changes(
        base, {"arm.links[1].length": 3.0, "controller.kind": "joint-pd", "controller.kp": 10.0}
    )
    assert out["arm"]["links"] == [{"length": 1.0}, {"length": 3.0}]
    assert out["controller"] == {"kind": "joint-pd", "kp": 10.0}  # zeta was pd's
    assert base["arm"]["links"][1] == {"length": 2.0}  # the base is not touched
    joints = with_changes({"arm": {"joints": {"stiffness": 5.0}}}, {"arm.joints.kind": "linear"})
    assert joints["arm"]["joints"] == {"kind": "linear"}
    with pytest.raises(KeyPathError, match=r"has 2 items: no 'arm.links\[5\]'"):
        with_changes(base, {"arm.links[5].length": 1.0})
    with pytest.raises(KeyPathError, match="unknown section 'sensr'"):
        parse_key("sensr.noise_std")


def test_run_id_is_a_stable_hash_of_the_whole_scenario():
    # a literal: the same on every machine, process and Python (not Python's salted hash)
    assert run_id({"simulation": {"seed": 1}}) == "553a110cfcc4b823"
    assert run_id({"a": {"x": 1, "y": 2}}) == run_id({"a": {"y": 2, "x": 1}})
    assert run_id({"a": {"x": 1}}) != run_id({"a": {"x": 1.0}})
    code = "from flexarm.sweeps.keys import run_id; print(run_id({'simulation': {'seed': 1}}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "553a110cfcc4b823"


def test_metrics_are_those_of_the_result():
    res = flexarm.simulate(flexarm.FlexibleArm.paper(), duration=0.01)
    assert set(res.metrics()) == {*METRICS, "sim_time_s", "wall_time_s"}


def test_flexarm_sweep_is_the_function_even_after_importing_the_package():
    assert callable(flexarm.sweep) and flexarm.sweep.__module__ == "flexarm.sweeps.driver"
    import importlib

    importlib.import_module("flexarm.sweeps.spec")  # sets flexarm.sweeps, not flexarm.sweep
    assert flexarm.sweep is sweep


# ------------------------------------------------------------------ running
def test_each_row_is_the_run_done_alone_bit_for_bit():
    from flexarm.sim.scenario import Scenario

    spec = spec_of(
        grid={"sensor.noise_std": [1e-4, 1e-3]},
        monte_carlo={
            "n": 2,
            "seed": 0,
            "simulation.seed": {"distribution": "integers", "low": 0, "high": 1000},
        },
    )
    table = sweep(spec, workers=2, progress=False)
    for row, run in zip(table.rows(), spec.runs, strict=True):
        sc = Scenario.from_dict(spec.scenario(run.params))
        alone = flexarm.simulate(sc.arm, **sc.simulate_kwargs()).metrics()
        assert row["status"] == "ok" and row["run_id"] == run.run_id
        for name in ("rms_error_m", "max_error_m", "max_torque_Nm", "control_effort_N2m2s"):
            assert row[name] == alone[name]


def test_processes_give_the_threads_table_bit_for_bit():
    spec = spec_of(
        grid={"sensor.noise_std": [1e-4, -1.0]},
        monte_carlo={
            "n": 3,
            "seed": 2,
            "simulation.seed": {"distribution": "integers", "low": 0, "high": 1000},
        },
    )
    threads = sweep(spec, workers=2, processes=False, progress=False)
    procs = sweep(spec, workers=2, processes=True, chunk_size=2, progress=False)
    assert procs.info["processes"] and procs.counts() == {"ok": 3, "diverged": 0, "error": 3}
    assert not threads.info["processes"]
    assert procs.equals(threads, ignore=("wall_time_s",))
    default = sweep(spec, workers=2, progress=False)  # processes where they fork
    assert default.info["processes"] == sys.platform.startswith("linux")
    assert default.equals(threads, ignore=("wall_time_s",))
    assert not sweep(spec, workers=1, progress=False).info["processes"]  # nothing to share
    with pytest.raises(InvalidValueError, match="'processes' parameter of sweep"):
        sweep(spec, processes=True, client=object(), progress=False)
    with pytest.raises(InvalidTypeError, match="'processes' parameter of sweep"):
        sweep(spec, processes="yes", progress=False)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("platform", "runs", "workers", "expected"),
    [
        ("linux", 10, 2, True),
        ("linux", 1, 2, False),
        ("linux", 10, 1, False),
        ("darwin", 10, 2, False),
        ("win32", 10, 2, False),
    ],
)
def test_processes_by_default_where_they_fork(monkeypatch, platform, runs, workers, expected):
    monkeypatch.setattr(sys, "platform", platform)
    assert prefer_processes(runs, workers) is expected


def test_failures_are_recorded_per_run_and_the_sweep_goes_on():
    spec = spec_of(grid={"sensor.noise_std": [0.0, -1.0], "simulation.max_deflection": [4.5, 1e-9]})
    table = sweep(spec, workers=2, progress=False)
    assert table["status"].tolist() == ["ok", "diverged", "error", "error"]
    assert table.counts() == {"ok": 1, "diverged": 1, "error": 2}
    assert "noise_std" in table["message"][2] and ">= 0" in table["message"][2]
    assert "diverged" in table["message"][1] or "deflection" in table["message"][1]
    assert 0.0 <= table["sim_time_s"][1] < 0.02  # where it stopped
    assert math.isnan(table["rms_error_m"][1]) and math.isnan(table["sim_time_s"][2])
    assert table.best()["run"] == 0 and table.best(largest=True)["run"] == 0


def test_repeated_runs_are_simulated_once(counted):
    choice = {"distribution": "choice", "values": [0.5, 0.7]}
    spec = spec_of(monte_carlo={"n": 6, "seed": 1, "controller.zeta": choice})
    table = sweep(spec, workers=2, progress=False)
    assert len(table) == 6 and len(counted) == len(set(table["run_id"].tolist())) <= 2
    assert table.info["distinct_runs"] == len(counted)


def test_resume_skips_the_runs_the_journal_holds(tmp_path, counted):
    out = tmp_path / "out"
    grid = {"controller.zeta": [0.5, 0.6], "sensor.noise_std": [0.0, 1e-4]}
    first = sweep(spec_of(grid=grid), out=out, workers=2, progress=False)
    assert len(counted) == 4 and first.info["resumed"] == 0
    again = sweep(spec_of(grid=grid), out=out, workers=2, progress=False)
    assert len(counted) == 4 and again.info["resumed"] == 4  # nothing simulated
    assert again.equals(first)
    grown = sweep(
        spec_of(grid={**grid, "controller.zeta": [0.5, 0.6, 0.7]}),
        out=out,
        workers=2,
        progress=False,
    )
    assert len(counted) == 6 and grown.info["resumed"] == 4  # only the new zeta's runs
    assert len(read_journal(out / JOURNAL_FILE)) == 6


def test_an_interrupted_sweep_leaves_a_consistent_journal_and_resumes(tmp_path, monkeypatch):
    out = tmp_path / "out"
    spec = spec_of(grid={"controller.zeta": [0.5, 0.55, 0.6, 0.65, 0.7, 0.75]})
    real, calls = execute.run_scenario, []

    def run(scenario):  # Ctrl-C arrives while the fourth run is under way
        calls.append(1)
        if len(calls) == 4:
            raise KeyboardInterrupt
        return real(scenario)

    monkeypatch.setattr(execute, "run_scenario", run)
    with pytest.raises(SweepInterrupted) as info:
        sweep(spec, out=out, workers=1, progress=False)
    assert isinstance(info.value, KeyboardInterrupt) and info.value.total == 6
    text = (out / JOURNAL_FILE).read_bytes()
    assert text.endswith(b"\n")
    lines = text.splitlines()
    assert len(lines) == info.value.finished == 3
    assert all(json.loads(line)["status"] == "ok" for line in lines)
    assert not (out / "runs.csv").exists()  # the table is written when the sweep completes
    monkeypatch.setattr(execute, "run_scenario", real)
    done = sweep(spec, out=out, workers=2, progress=False)
    assert done.info["resumed"] == 3 and done.counts()["ok"] == 6
    assert done.equals(sweep(spec, workers=2, progress=False), ignore=("wall_time_s",))


def test_a_journal_line_cut_short_is_ignored_and_cut_off(tmp_path):
    path = tmp_path / JOURNAL_FILE
    rec = {
        "run_id": "a",
        "status": "ok",
        "message": "",
        "sim_time_s": 1.0,
        "wall_time_s": 0.1,
        "metrics": {"rms_error_m": 0.5},
        "flexarm": flexarm.__version__,
    }
    path.write_text(json.dumps(rec) + "\n" + json.dumps({**rec, "run_id": "b"})[:40])
    assert list(read_journal(path)) == ["a"]
    with Journal(path) as journal:
        journal.append({**rec, "run_id": "c"})
    assert list(read_journal(path)) == ["a", "c"]
    assert path.read_text().count("\n") == 2
    old = {**rec, "run_id": "d", "flexarm": "0.0.1"}  # another version's runs are not reused
    path.write_text(json.dumps(old) + "\n")
    assert read_journal(path) == {}


# ------------------------------------------------------------------ the table
@pytest.fixture(scope="module")
def table():
    spec = SweepSpec.from_dict(
        {
            "base": {"simulation": {"duration": 0.02}, "sensor": {"noise_std": 1e-4}},
            "grid": [
                {
                    "controller.zeta": [0.5, 0.7],
                    "simulation.seed": [1, 2],
                    "delay.reference": [False],
                },
                {
                    "controller.zeta": [0.6],
                    "trajectory.center": [[5.0, 0.5]],
                    "sensor.noise_std": [-1.0],
                },
            ],
        }
    )
    return sweep(spec, workers=2, progress=False)


def test_the_table_is_tidy_and_typed(table):
    assert len(table) == 5
    assert table.column_names[:7] == (
        "run",
        "run_id",
        "controller.zeta",
        "simulation.seed",
        "delay.reference",
        "trajectory.center",
        "sensor.noise_std",
    )
    assert table.column_names[7:10] == ("status", "message", "sim_time_s")
    assert table.column_names[-1] == "wall_time_s"
    assert table.metrics[:2] == ("rms_error_m", "max_error_m")
    assert table["controller.zeta"].dtype == np.float64
    assert table["simulation.seed"].dtype == np.float64  # a run without it: NaN
    assert table["delay.reference"].dtype.kind == "U"  # bool and missing: text
    assert table["trajectory.center"].tolist() == ["", "", "", "", "[5.0, 0.5]"]
    assert table["status"].tolist() == ["ok"] * 4 + ["error"]
    s = table.to_numpy()
    assert s["rms_error_m"][0] == table["rms_error_m"][0]


def test_csv_round_trip(table, tmp_path):
    table.write_csv(tmp_path / "t.csv")
    back = SweepTable.read_csv(tmp_path / "t.csv")
    assert back.equals(table) and back.parameters == table.parameters
    assert back.metrics == table.metrics
    pd = pytest.importorskip("pandas")
    frame = pd.read_csv(tmp_path / "t.csv")
    assert list(frame.columns) == list(table.column_names)
    assert frame["rms_error_m"].tolist()[:4] == table["rms_error_m"].tolist()[:4]


def test_parquet_round_trip_keeps_the_types(table, tmp_path):
    pytest.importorskip("pyarrow", reason="Parquet needs pyarrow: pip install 'flexarm[sweep]'")
    table.write_parquet(tmp_path / "t.parquet")
    back = SweepTable.read_parquet(tmp_path / "t.parquet")
    assert back.equals(table) and back.parameters == table.parameters
    assert back["run"].dtype == np.int64 and back["status"].dtype.kind == "U"
    pd = pytest.importorskip("pandas")
    assert pd.read_parquet(tmp_path / "t.parquet").shape == (len(table), len(table.column_names))


def test_parquet_without_pyarrow_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    spec = spec_of(grid={"controller.zeta": [0.5]})
    with pytest.raises(InvalidValueError, match=r"pyarrow.*flexarm\[sweep\]"):
        sweep(spec, out=tmp_path / "o", parquet=True, progress=False)
    assert not (tmp_path / "o").exists()
    t = sweep(spec, out=tmp_path / "o", progress=False)  # default: CSV only without pyarrow
    assert "runs.parquet" not in t.info["files"] and (tmp_path / "o" / "runs.csv").is_file()


def test_pandas_export(table):
    pytest.importorskip("pandas")
    frame = table.to_pandas()
    assert frame.shape == (5, len(table.column_names))
    assert frame["status"].tolist() == table["status"].tolist()


# ------------------------------------------------------------------ bad sweeps (library)
@pytest.mark.parametrize(
    ("data", "error", "match"),
    [
        ({"grid": {"controller.zeta": []}}, SweepError, "grid.controller.zeta: is empty"),
        ({"grid": {"controller.zeta": 0.5}}, SweepTypeError, "must be an array of values"),
        ({"monte_carlo": {"n": 0, "seed": 1}}, SweepError, "monte_carlo.n: must be an integer"),
        (
            {"monte_carlo": {"n": 2, "seed": 1, "controller.zeta": {"distribution": "beta"}}},
            SweepError,
            "distribution: must be one of",
        ),
        ({}, SweepError, "nothing to sweep"),
        (
            {
                "grid": {"controller.zeta": [0.5]},
                "monte_carlo": {
                    "n": 1,
                    "seed": 0,
                    "controller.zeta": {"distribution": "uniform", "low": 0, "high": 1},
                },
            },
            SweepError,
            "also in a grid",
        ),
        (
            {"grid": {"arm.joints": [{}], "arm.joints.stiffness": [1.0]}},
            SweepError,
            "inside 'arm.joints'",
        ),
    ],
)
def test_bad_sweeps_name_the_key(data, error, match):
    with pytest.raises(error, match=match):
        SweepSpec.from_dict({"base": SHORT, **data}, source="s.toml")


def test_an_unknown_swept_key_is_refused_before_any_run(tmp_path, counted):
    spec = spec_of(grid={"sensor.noise_stdd": [0.0]})
    with pytest.raises(SweepError, match=r"grid: unknown key 'sensor\.noise_stdd'"):
        sweep(spec, out=tmp_path / "o", progress=False)
    assert counted == [] and not (tmp_path / "o").exists()


# ------------------------------------------------------------------ Dask
@pytest.mark.cluster
def test_a_local_dask_cluster_gives_the_local_table_bit_for_bit():
    distributed = pytest.importorskip(
        "distributed", reason="dask.distributed is not installed (pip install 'flexarm[dask]')"
    )
    spec = spec_of(
        grid={"controller.zeta": [0.5, 0.7], "sensor.noise_std": [1e-4, -1.0]},
        monte_carlo={
            "n": 3,
            "seed": 5,
            "simulation.seed": {"distribution": "integers", "low": 0, "high": 2**31},
        },
    )
    local = sweep(spec, workers=2, progress=False)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0"
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = sweep(spec, client=client, chunk_size=2, progress=False)
        assert remote.info["scheduler"] == cluster.scheduler_address
    assert remote.counts() == local.counts() == {"ok": 6, "diverged": 0, "error": 6}
    assert remote["run_id"].tolist() == [r.run_id for r in spec.runs]
    assert remote.equals(local, ignore=("wall_time_s",))  # every metric bit for bit
