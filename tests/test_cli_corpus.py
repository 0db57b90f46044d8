"""The corpus of bad command lines: every one ends with exit status 2, one line on
stderr naming the problem, no traceback, and nothing written.

Each case is ``(argv, needle, files)``: ``{tmp}`` in ``argv`` is the case's own
directory, ``files`` are written there first (scenario files, data files), and
``needle`` must appear in the one line. The cases are what new users were seen to
try (negative, NaN, infinite and huge numbers, unknown options, malformed, empty
and binary files, wrong columns, missing paths, outputs that are files) and the
variations of each on every command.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from flexarm.cli import main

Case = tuple[list[str], str, dict[str, bytes]]

BAD_NUMBERS = ["nan", "inf", "-inf", "abc", ""]
SCENARIO_OK = b"[simulation]\nduration = 0.01\n"


def _numbers(command: list[str], option: str, extra: list[tuple[str, str]]) -> Iterator[Case]:
    """``option`` with each of :data:`BAD_NUMBERS` and the option's own bad values."""
    for value in BAD_NUMBERS:
        yield [*command, f"{option}={value}"], option.lstrip("-"), {}
    for value, needle in extra:
        yield [*command, f"{option}={value}"], needle, {}


def _simulate() -> Iterator[Case]:
    sim = ["simulate", "--out", "{tmp}/out"]
    numeric = {
        "--duration": [("-1", "--duration"), ("0", "--duration"), ("1e12", "FLEXARM_MAX_MEMORY")],
        "--dt": [("-1", "--dt"), ("0", "--dt"), ("1e-12", "FLEXARM_MAX_"), ("1e9", "--dt")],
        "--substeps": [("0", "--substeps"), ("-1", "--substeps"), ("1.5", "--substeps")],
        "--record-every": [("0", "--record-every"), ("-3", "--record-every"), ("2.5", "every")],
        "--smoothing": [("-1", "--smoothing")],
        "--seed": [("-1", "--seed"), ("1.5", "--seed")],
        "--delay": [("-1", "--delay"), ("1e9", "FLEXARM_MAX_MEMORY"), ("seedx", "--delay")],
        "--pade-order": [("0", "--pade-order"), ("-1", "--pade-order"), ("x", "--pade-order")],
    }
    for option, extra in numeric.items():
        yield from _numbers(sim, option, extra)
    for option in (
        "--controller",
        "--sensor-model",
        "--delay-method",
        "--shaper",
        "--shaper-modes",
    ):
        yield [*sim, option, "bogus"], option, {}
    for sensor in [
        "",
        "point",
        "point:1",
        "point:x:0.5",
        "point:5:0.5",
        "point:1:-1",
        "point:1:99",
        "point:1:nan",
        "wrist",
        "point:1:0.5:2",
    ]:
        yield [*sim, f"--sensor={sensor}"], "sensor", {}
    yield [*sim, "--bogus"], "unrecognized", {}
    yield [*sim, "extra"], "unrecognized", {}
    yield ["simulate", "--out"], "--out", {}
    # --out that cannot take the results
    yield ["simulate", "--out", "{tmp}/file.txt"], "--out", {"file.txt": b"mine"}
    yield ["simulate", "--out", "{tmp}/full"], "--out", {"full/keep.txt": b"mine"}
    yield ["simulate", "--out", "{tmp}/no/such/dir"], "--out", {}
    # scenario files
    scen = [*sim, "--scenario", "{tmp}/s.toml"]
    yield ["simulate", "--scenario", "{tmp}/missing.toml"], "missing.toml", {}
    yield ["simulate", "--scenario", "{tmp}"], "not a scenario file", {}
    bad_files: list[tuple[bytes, str]] = [
        (b"\x00\x01\x02\xff\xfe binary", "s.toml"),
        (b"[simulation\nduration = 1", "s.toml"),
        (b"duration = 1\n", "duration"),
        (b"[nonsense]\n", "nonsense"),
        (b"[simulation]\nbogus = 1\n", "bogus"),
        (b'[simulation]\nduration = "long"\n', "duration"),
        (b"[simulation]\nduration = -1\n", "duration"),
        (b"[simulation]\nduration = nan\n", "duration"),
        (b"[simulation]\ndt = inf\n", "dt"),
        (b"[simulation]\ndt = 0\n", "dt"),
        (b"[simulation]\nsubsteps = 0\n", "substeps"),
        (b"[simulation]\nrecord_every = 0\n", "record_every"),
        (b"[simulation]\nseed = -5\n", "seed"),
        (b"[simulation]\ntorque_limit = -1\n", "torque_limit"),
        (b"[simulation]\ntorque_limit = [1, 2, 3]\n", "torque_limit"),
        (b'[simulation]\nelbow = "up"\n', "elbow"),
        (b"[simulation]\nmax_deflection = 0\n", "max_deflection"),
        (b"[simulation]\ncheck_sampling = 3\n", "check_sampling"),
        (b"[arm]\nn_modes = 0\n", "at least one mode"),  # rigid links, but the law needs one
        (b"[arm]\nn_modes = -1\n", "n_modes"),
        (b'[arm]\npreset = "robot"\n', "preset"),
        (b"[arm]\nlinks = []\n", "links"),
        (b"[arm]\nlinks = [{length = -1, flexural_rigidity = 1, linear_density = 1}]\n", "length"),
        (
            b"[arm]\nlinks = [{length = 1, flexural_rigidity = 0, linear_density = 1}]\n",
            "flexural_rigidity",
        ),
        (b"[arm]\nlinks = [{length = 1, flexural_rigidity = 1}]\n", "linear_density"),
        (b'[arm]\nboundary = "free-free"\n', "boundary"),
        (b'[trajectory]\nkind = "spiral"\n', "kind"),
        (b"[trajectory]\nside = -4\n", "side"),
        (b"[trajectory]\nside = 40\n", "workspace"),
        (b"[trajectory]\ntime_per_side = 0\n", "time_per_side"),
        (b'[trajectory]\nkind = "circle"\nradius = 0\n', "radius"),
        (b'[sensor]\nkind = "laser"\n', "kind"),
        (b"[sensor]\nnoise_std = -1\n", "noise_std"),
        (b'[sensor]\nkind = "point"\nlink = 7\ndistance = 0.5\n', "link"),
        (b'[sensor]\nmodel = "exact"\n', "model"),
        (b'[controller]\nkind = "pid"\n', "kind"),
        (b'[controller]\nkind = "jt-pd"\nkp = -1\n', "kp"),
        (b'[controller]\nkind = "fuzzy"\nks = -1\n', "ks"),
        (b"[delay]\ndelay = -0.1\n", "delay"),
        (b'[delay]\nmethod = "magic"\n', "method"),
        (b'[shaper]\nkind = "zvdd"\n', "kind"),
        (b"[simulation]\nduration = 1e12\n", "FLEXARM_MAX_MEMORY"),
    ]
    for content, needle in bad_files:
        yield scen, needle, {"s.toml": content}
    # command-line options over a valid file still name the option
    yield [*scen, "--dt", "-1"], "--dt", {"s.toml": SCENARIO_OK}
    yield [*scen, "--sensor", "point:9:1"], "sensor", {"s.toml": SCENARIO_OK}


def _reproduce() -> Iterator[Case]:
    rep = ["reproduce", "--out", "{tmp}/r"]
    numeric = {
        "--duration": [("-1", "duration"), ("0", "duration"), ("1e9", "FLEXARM_MAX_MEMORY")],
        "--dt": [("-1", "dt"), ("0", "dt"), ("1e-9", "FLEXARM_MAX_MEMORY")],
        "--ks": [("-1", "ks")],
        "--tolerance": [("-1", "tolerance"), ("0", "tolerance")],
        "--workers": [("0", "workers"), ("-2", "workers"), ("1.5", "workers")],
    }
    for option, extra in numeric.items():
        yield from _numbers(rep, option, extra)
    for ks_range in ["", ",", "1,,2", "1,x", "1,-2", "nan", "inf,1"]:
        yield [*rep, f"--ks-range={ks_range}"], "--ks-range", {}
    yield [*rep, "--law", "magic"], "--law", {}
    yield [*rep, "--bogus"], "unrecognized", {}
    yield ["reproduce", "--out", "{tmp}/file.txt"], "--out", {"file.txt": b"x"}
    yield ["reproduce", "--out", "{tmp}/full"], "--out", {"full/a.txt": b"x"}


def _modes() -> Iterator[Case]:
    modes = ["modes"]
    link = ["modes", "--length", "1", "--flexural-rigidity", "1", "--linear-density", "1"]
    numeric = {
        "--n-modes": [
            ("0", "n-modes"),
            ("-1", "n-modes"),
            ("1.5", "n-modes"),
            ("100000", "FLEXARM_MAX"),
        ],
        "--amplitude": [("0", "amplitude"), ("-1", "amplitude")],
    }
    for option, extra in numeric.items():
        yield from _numbers(modes, option, extra)
    given = {"--length": "1", "--flexural-rigidity": "1", "--linear-density": "1"}
    for option in given:
        for value in ["-1", "0", *BAD_NUMBERS]:
            argv = ["modes"]
            for name, default in given.items():
                argv.append(f"{name}={value if name == option else default}")
            yield argv, option.lstrip("-").split("-")[0], {}
    for option in ("--tip-mass", "--tip-inertia"):
        for value in ["-1", "nan", "inf"]:
            yield [*link, option, value], option.lstrip("-").split("-")[0], {}
    yield (
        ["modes", "--length", "1e300", "--flexural-rigidity", "1e-300", "--linear-density", "1"],
        "finite",
        {},
    )
    yield ["modes", "--length", "1"], "flexural", {}
    for option in ("--boundary", "--joints", "--normalization"):
        yield [*modes, option, "bogus"], option, {}


def _identify() -> Iterator[Case]:
    good = b"x,y\n" + b"".join(f"{i / 10},{(i % 7) / 3}\n".encode() for i in range(60))
    fit = ["identify", "fit", "{tmp}/d.csv", "--out", "{tmp}/out"]
    for option, extra in {
        "--bandwidth": [("-1", "bandwidth"), ("0", "bandwidth")],
        "--decay": [("-1", "decay"), ("2", "decay")],
        "--grid": [("0", "grid"), ("-1", "grid"), ("1", "grid"), ("100000000000", "FLEXARM_MAX")],
    }.items():
        for value in [*BAD_NUMBERS, *(v for v, _ in extra)]:
            needle = dict(extra).get(value, option.lstrip("-"))
            yield [*fit, f"{option}={value}"], needle, {"d.csv": good}
    yield [*fit, "--kernel", "box"], "--kernel", {"d.csv": good}
    yield [*fit, "--x", "9"], "column", {"d.csv": good}
    yield [*fit, "--y", "zz"], "zz", {"d.csv": good}
    yield [*fit, "--binned=2"], "binned", {"d.csv": good}
    yield [*fit, "--series"], "series", {"d.csv": good}
    data_files = [
        (b"", "d.csv"),
        (b"x,y\n", "d.csv"),
        (b"x,y\nnan,nan\nnan,1\n", "NaN"),
        (b"x;y\n1;2\n3;4\n5;6\n", "delimiter=';'"),
        (b"\x00\xff\x00binary", "d.csv"),
        (b"x,y\n1,2\n3\n", "d.csv"),
        (b"x,y\na,b\nc,d\n", "d.csv"),
    ]
    for content, needle in data_files:
        yield fit, needle, {"d.csv": content}
    yield ["identify", "fit", "{tmp}/none.csv"], "none.csv", {}
    yield ["identify", "fit", "{tmp}"], "not a file", {}
    yield ["identify", "fit", "{tmp}/d.npz"], "d.npz", {"d.npz": b"not a zip file"}
    study = ["identify", "study", "--out", "{tmp}/out"]
    for option, extra in {
        "--n-min": [("0", "n-min"), ("-1", "n-min")],
        "--n-max": [("1", "--n-max must be larger than --n-min")],
        "--n-steps": [("0", "n-steps")],
        "--repetitions": [("0", "repetitions")],
        "--noise": [("-1", "noise")],
        "--seed": [("-1", "seed")],
    }.items():
        for value in ["abc", "", *(v for v, _ in extra)]:
            needle = dict(extra).get(value, option.lstrip("-"))
            yield [*study, f"{option}={value}"], needle, {}
    yield [*study, "--function", "cubic"], "--function", {}
    yield ["identify"], "", {}
    yield ["identify", "bogus"], "bogus", {}


def _figures() -> Iterator[Case]:
    """--format and --dpi on every command that writes figures: a format of the three,
    a resolution within 20..1200 dpi, and only where figures are written."""
    good = b"u,y\n" + b"".join(f"{i % 5 - 2},{(i % 7) / 3}\n".encode() for i in range(60))
    commands = [
        (["simulate", "--out", "{tmp}/out"], {}),
        (["reproduce", "--out", "{tmp}/out"], {}),
        (["identify", "fit", "{tmp}/d.csv", "--out", "{tmp}/out"], {"d.csv": good}),
        (["identify", "study", "--out", "{tmp}/out"], {}),
        (["identify", "hammerstein", "{tmp}/d.csv", "--out", "{tmp}/out"], {"d.csv": good}),
        (["identify", "hammerstein", "--out", "{tmp}/out"], {}),
    ]
    for argv, files in commands:
        for value in ["jpg", "", ".png"]:
            yield [*argv, f"--format={value}"], "--format", files
        for value in ["nan", "inf", "abc", "", "0", "-72", "10", "5000", "300dpi"]:
            yield [*argv, f"--dpi={value}"], "--dpi", files
    # figures are written only with --out: asked for without it, it is an error
    yield ["simulate", "--format", "pdf"], "--out", {}
    yield ["identify", "fit", "{tmp}/d.csv", "--dpi", "300"], "--out", {"d.csv": good}
    yield ["identify", "study", "--format", "svg"], "--out", {}
    yield ["identify", "hammerstein", "{tmp}/d.csv", "--format", "svg"], "--out", {"d.csv": good}


CASES: list[Case] = [*_simulate(), *_reproduce(), *_modes(), *_identify(), *_figures()]


def _id(case: Case) -> str:
    argv, _, files = case
    return " ".join(argv).replace("{tmp}/", "") + (f" [{','.join(files)}]" if files else "")


def test_the_corpus_is_large():
    assert len(CASES) >= 200


@pytest.mark.parametrize("case", CASES, ids=[_id(c) for c in CASES])
def test_bad_command_lines(case, tmp_path, capsys, monkeypatch):
    argv, needle, files = case
    monkeypatch.chdir(tmp_path)
    for name, content in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content)
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    status = main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    out, err = capsys.readouterr()
    assert out == ""
    assert status == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert needle in lines[0], lines[0]
    after = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    assert after == before  # nothing written, no temporary left


def _is_root() -> bool:
    return hasattr(os, "geteuid") and os.geteuid() == 0


@pytest.mark.skipif(_is_root(), reason="root writes into read-only directories")
def test_a_read_only_out_parent(tmp_path, capsys):
    parent = tmp_path / "ro"
    parent.mkdir()
    parent.chmod(0o500)
    try:
        status = main(["simulate", "--duration", "0.01", "--out", str(parent / "out")])
    finally:
        parent.chmod(0o700)
    err = capsys.readouterr().err
    assert status in (1, 2) and len(err.strip().splitlines()) == 1
    assert "permission" in err.lower() or "read-only" in err.lower()
    assert list(parent.iterdir()) == []


def test_paths_are_shown_as_given(tmp_path, capsys):
    status = main(["simulate", "--scenario", str(Path(tmp_path, "nope.toml"))])
    assert status == 2 and "nope.toml" in capsys.readouterr().err


@pytest.mark.parametrize(
    "code, words",
    [
        (errno.EROFS, "read-only"),
        (errno.EBUSY, "mount point"),
        (errno.ENOSPC, "disk is full"),
        (errno.EACCES, "permission denied"),
    ],
)
def test_results_that_cannot_be_written_say_why(tmp_path, capsys, monkeypatch, code, words):
    """The write fails as the system says (a read-only mount, a mount point, a full
    disk): exit 1, one line saying why in words, nothing written."""
    from flexarm.sim.results import SimulationResult

    def refuse(self, directory, summary, **kwargs):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(SimulationResult, "write", refuse)
    status = main(["simulate", "--duration", "0.01", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 1
    assert err.strip().splitlines() == [err.strip()] and words in err and "nothing written" in err
    assert list(tmp_path.iterdir()) == []
