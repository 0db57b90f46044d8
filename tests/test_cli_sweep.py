"""``flexarm sweep``: the summary and its JSON, the files, resuming, Ctrl-C (exit 130,
one line, a consistent journal), and bad sweep files: one line on stderr, exit
status 2, nothing written."""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from flexarm.sweeps import execute
from flexarm.sweeps.driver import sweep
from flexarm.sweeps.journal import JOURNAL_FILE, read_journal
from flexarm.sweeps.table import SweepTable
from helpers.cli import as_at_a_terminal, help_text, run, strict_json

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "sweep_noise.toml"
SMALL = """\
[base]
simulation.duration = 0.02

[grid]
"controller.zeta" = [0.5, 0.7]
"sensor.noise_std" = [0.0, -1.0]

[monte_carlo]
n = 2
seed = 3
"simulation.seed" = { distribution = "integers", low = 0, high = 1000 }
"""
FILES = {"sweep.json", "journal.jsonl", "runs.csv", "runs.parquet", "summary.json"}


@pytest.fixture
def small(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return path


def test_the_example_is_a_valid_sweep():
    from flexarm.sweeps.spec import load_sweep

    spec = load_sweep(EXAMPLE)
    assert spec.n_runs == 120 and spec.parameters == (
        "sensor.noise_std",
        "controller.zeta",
        "simulation.seed",
    )
    assert spec.base["simulation"]["duration"] == 2.0
    assert spec.base["trajectory"]["kind"] == "square"  # from paper_square.toml


def test_summary_files_and_resume(capsys, small, tmp_path):
    pytest.importorskip("pyarrow")
    out = tmp_path / "out"
    status, text, err = run(capsys, "sweep", small, "--out", out, "--workers", "2")
    assert status == 0, err
    assert "8 runs of" in text and "(grid 2 x 2, monte_carlo n = 2)" in text
    assert "ok 4, diverged 0, error 4; 0 done before" in text
    assert "best  rms_error_m" in text and "worst rms_error_m" in text
    assert {p.name for p in out.iterdir()} == FILES
    table = SweepTable.read_parquet(out / "runs.parquet")
    assert len(table) == 8 and table.counts() == {"ok": 4, "diverged": 0, "error": 4}
    assert SweepTable.read_csv(out / "runs.csv").equals(table)
    status, text, err = run(capsys, "sweep", small, "--out", out, "--json")
    data = strict_json(text)
    assert status == 0 and data["resumed"] == 8 and data["rows"] == 8
    assert data["ok"] == 4 and data["error"] == 4 and data["ranked_by"] == "rms_error_m"
    assert data["best"]["rms_error_m"] <= data["worst"]["rms_error_m"]
    assert set(data["best"]) >= {"run", "run_id", "controller.zeta", "simulation.seed"}
    assert data == strict_json((out / "summary.json").read_text())


def test_default_output_directory_and_csv_only(capsys, small, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, _, err = run(capsys, "sweep", small, "--format", "csv", "--workers", "1")
    assert status == 0, err
    assert {p.name for p in (tmp_path / "sweep_small").iterdir()} == FILES - {"runs.parquet"}


def test_ctrl_c_is_one_line_exit_130_and_a_consistent_journal(capsys, small, tmp_path, monkeypatch):
    real, calls = execute.run_scenario, []

    def run_scenario(scenario):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(scenario)

    monkeypatch.setattr(execute, "run_scenario", run_scenario)
    out = tmp_path / "out"
    status, text, err = run(capsys, "sweep", small, "--out", out, "--workers", "1")
    assert status == 130 and text == ""
    assert err.count("\n") == 1 and "interrupted: 2 of 8 runs done" in err
    assert "resume" in err and "Traceback" not in err
    assert len(read_journal(out / JOURNAL_FILE)) == 2
    monkeypatch.setattr(execute, "run_scenario", real)
    status, text, err = run(capsys, "sweep", small, "--out", out, "--json")
    assert status == 0 and strict_json(text)["resumed"] == 2


@pytest.mark.skipif(os.name != "posix", reason="POSIX signals")
@pytest.mark.parametrize("how", [["--threads"], []], ids=["threads", "default"])
def test_a_real_sigint_leaves_whole_lines_and_the_sweep_resumes(tmp_path, how):
    """SIGINT to the command while runs are under way: exit 130, one line on stderr,
    the journal's lines whole; the same sweep then does only the runs left."""
    n = 60
    sweep_file = tmp_path / "many.toml"
    sweep_file.write_text(
        f"[base]\nsimulation.duration = 0.1\n[monte_carlo]\nn = {n}\nseed = 1\n"
        '"controller.zeta" = { distribution = "uniform", low = 0.5, high = 0.9 }\n'
    )
    out = tmp_path / "out"
    argv = [sys.executable, "-m", "flexarm", "sweep", str(sweep_file), "--out", str(out), *how]
    proc = subprocess.Popen(
        argv,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=as_at_a_terminal,
    )
    journal = out / JOURNAL_FILE
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.is_file() and journal.read_bytes().count(b"\n") >= 2:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert stdout == "" and stderr.count("\n") == 1 and "interrupted" in stderr
    data = journal.read_bytes()
    assert data.endswith(b"\n")
    lines = data.splitlines()
    assert 2 <= len(lines) < n
    assert all(json.loads(line)["status"] == "ok" for line in lines)
    table = sweep(sweep_file, out=out, workers=2, progress=False)
    assert table.info["resumed"] == len(lines) and table.counts()["ok"] == n


# ------------------------------------------------------------------ bad input
MC = "[monte_carlo]\nn = 2\nseed = 1\n"
BAD_FILES = {
    "not TOML": ("[grid\nx = 1\n", "not valid TOML"),
    "binary": (b"\x00\xff\xfe\x89PNG\r\n\x1a\n\x00\x00", "not valid TOML"),
    "unknown section": ('[grd]\n"controller.zeta" = [0.5]\n', "unknown section 'grd'"),
    "unknown key": (
        '[grid]\n"sensor.noise_stdd" = [0.0]\n',
        "grid: unknown key 'sensor.noise_stdd'",
    ),
    "unknown scenario section": ('[grid]\n"sensr.noise_std" = [0.0]\n', "unknown section 'sensr'"),
    "empty grid": ("[grid]\n", "grid: is empty"),
    "empty values": ('[grid]\n"controller.zeta" = []\n', "grid.controller.zeta: is empty"),
    "values not a list": ('[grid]\n"controller.zeta" = 0.5\n', "must be an array of values"),
    "a date": ('[grid]\n"controller.zeta" = [1979-05-27]\n', "must be a number, a string"),
    "n = 0": (
        '[monte_carlo]\nn = 0\nseed = 1\n"controller.zeta" = '
        '{ distribution = "uniform", low = 0.5, high = 0.9 }\n',
        "monte_carlo.n: must be an integer >= 1",
    ),
    "n not an integer": (
        '[monte_carlo]\nn = "ten"\nseed = 1\n',
        "monte_carlo.n: must be an integer",
    ),
    "no seed": (
        '[monte_carlo]\nn = 2\n"controller.zeta" = '
        '{ distribution = "uniform", low = 0.5, high = 0.9 }\n',
        "missing key 'monte_carlo.seed'",
    ),
    "bad distribution": (
        MC + '"controller.zeta" = { distribution = "gauss" }\n',
        "distribution: must be one of",
    ),
    "missing parameter": (
        MC + '"controller.zeta" = { distribution = "uniform", low = 0.5 }\n',
        "missing key 'monte_carlo.controller.zeta.high'",
    ),
    "unknown parameter": (
        MC + '"controller.zeta" = { distribution = "uniform", low = 0, high = 1, mean = 0 }\n',
        "unknown key 'monte_carlo.controller.zeta.mean'",
    ),
    "low above high": (
        MC + '"controller.zeta" = { distribution = "uniform", low = 2, high = 1 }\n',
        "high: must be > low",
    ),
    "loguniform from 0": (
        MC + '"sensor.noise_std" = { distribution = "loguniform", low = 0, high = 1 }\n',
        "low: must be > 0",
    ),
    "negative std": (
        MC + '"controller.zeta" = { distribution = "normal", mean = 1, std = -1 }\n',
        "std: must be >= 0",
    ),
    "empty choice": (
        MC + '"sensor.kind" = { distribution = "choice", values = [] }\n',
        "values: must be a non-empty array",
    ),
    "weights mismatched": (
        MC + '"sensor.kind" = { distribution = "choice", values = ["tip"], weights = [1, 2] }\n',
        "weights: must be an array of 1 numbers",
    ),
    "not a distribution": (MC + '"controller.zeta" = 0.5\n', "must be a table { distribution"),
    "nothing drawn": (MC, "monte_carlo: draws no key"),
    "grid and draws": (
        '[grid]\n"controller.zeta" = [0.5]\n' + MC + '"controller.zeta" = '
        '{ distribution = "uniform", low = 0.5, high = 0.9 }\n',
        "also in a grid",
    ),
    "missing base file": (
        'base = "nope.toml"\n[grid]\n"controller.zeta" = [0.5]\n',
        "base: nope.toml: no such file",
    ),
    "base not TOML": (
        'base = "bad.toml"\n[grid]\n"controller.zeta" = [0.5]\n',
        "base: bad.toml: not valid TOML",
    ),
    "bad base scenario": (
        '[base.sensor]\nkind = "laser"\n[grid]\n"controller.zeta" = [0.5]\n',
        "base: sensor.kind: must be one of",
    ),
    "unknown base section": (
        '[base.sensr]\nkind = "tip"\n[grid]\n"controller.zeta" = [0.5]\n',
        "base: unknown section 'sensr'",
    ),
    "nothing to sweep": ("[base.simulation]\nduration = 1.0\n", "nothing to sweep"),
    "unknown metric": (
        '[sweep]\nmetrics = ["rms"]\n[grid]\n"controller.zeta" = [0.5]\n',
        "unknown metric 'rms'",
    ),
    "unknown sweep option": (
        '[sweep]\nfoo = 1\n[grid]\n"controller.zeta" = [0.5]\n',
        "unknown key 'sweep.foo'",
    ),
    "too many runs": (
        "[grid]\n"
        + "".join(
            f'"{k}" = [{", ".join(str(0.1 * i) for i in range(100))}]\n'
            for k in ("controller.zeta", "sensor.noise_std", "arm.payload_mass", "delay.delay")
        ),
        "expands to 100000000 runs, more than 1000000",
    ),
    "index into no array": (
        '[grid]\n"arm.links[3].length" = [1.0]\n',
        "grid.arm.links[3].length: 'arm.links[3]' indexes something",
    ),
}


@pytest.mark.parametrize("case", list(BAD_FILES), ids=list(BAD_FILES))
def test_bad_sweep_files_are_one_line_status_2_nothing_written(capsys, tmp_path, case):
    content, needle = BAD_FILES[case]
    path = tmp_path / "sweep.toml"
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    (tmp_path / "bad.toml").write_text("[sensor\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    status, out, err = run(capsys, "sweep", path, "--out", tmp_path / "out")
    assert status == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("flexarm sweep: error: "), err
    assert needle in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_a_missing_sweep_file(capsys, tmp_path):
    status, _, err = run(capsys, "sweep", tmp_path / "nope.toml", "--out", tmp_path / "o")
    assert status == 2 and err.count("\n") == 1 and "nope.toml: no such file" in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--workers", "0"], "argument --workers: must be an integer >= 1"),
        (["--chunk-size", "x"], "argument --chunk-size: must be an integer >= 1"),
        (["--format", "xml"], "argument --format: invalid choice"),
        (["--scheduler", "nonsense://x"], "argument --scheduler: cannot connect"),
        (["--scheduler", "tcp://127.0.0.1:1"], "argument --scheduler: cannot connect"),
        (["--scheduler", "tcp://127.0.0.1:1", "--processes"], "argument --processes: not with"),
        (["--processes", "--threads"], "argument --threads: not allowed with argument"),
    ],
)
def test_bad_options_are_one_line_status_2(capsys, small, tmp_path, extra, needle):
    if "--scheduler" in extra:
        pytest.importorskip("distributed", reason="dask.distributed is not installed")
    status, _, err = run(capsys, "sweep", small, "--out", tmp_path / "o", *extra)
    assert status == 2 and err.count("\n") == 1 and needle in err, err
    assert not (tmp_path / "o").exists()


def test_out_must_be_new_empty_or_a_sweep(capsys, small, tmp_path):
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "thesis.tex").write_text("keep me")
    status, _, err = run(capsys, "sweep", small, "--out", busy)
    assert status == 2 and "argument --out:" in err and "holds no sweep" in err
    assert [p.name for p in busy.iterdir()] == ["thesis.tex"]
    status, _, err = run(capsys, "sweep", small, "--out", tmp_path / "no" / "such")
    assert status == 2 and "parent directory" in err


def test_missing_extras_are_named(capsys, small, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    monkeypatch.setitem(sys.modules, "distributed", None)
    status, _, err = run(capsys, "sweep", small, "--out", tmp_path / "o", "--format", "parquet")
    assert status == 2 and "parquet needs pyarrow" in err and "flexarm[sweep]" in err
    status, _, err = run(capsys, "sweep", small, "--out", tmp_path / "o", "--scheduler", "x:1")
    assert status == 2 and "needs dask.distributed" in err and "flexarm[dask]" in err
    assert not (tmp_path / "o").exists()


def test_help(capsys):
    out = help_text(capsys, "sweep")
    assert "--scheduler" in out and "exit status" in out
    from flexarm.cli import build_parser

    assert "sweep" in build_parser().format_help()


def test_progress_goes_to_stderr_only_on_a_terminal(capsys, small, tmp_path):
    status, out, err = run(capsys, "sweep", small, "--out", tmp_path / "o", "--workers", "1")
    assert status == 0 and "sweep [" not in err and "sweep [" not in out
