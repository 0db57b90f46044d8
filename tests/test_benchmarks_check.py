"""benchmarks/check.py's machinery on a fake recorded table and fake measurements:
the table's parsing and refusals, the ratio and the slip in both directions, the
exit status with and without --strict; and BENCHMARKS.md's headline table agrees
with benchmarks/recorded.toml. Nothing is timed.
"""

from __future__ import annotations

import importlib.util
import math
import pathlib
import re
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def check():
    spec = importlib.util.spec_from_file_location("check", ROOT / "benchmarks" / "check.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["check"] = module
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop("check", None)


TABLE = """
[speed]
what = "a call"
unit = "ns"
best = 100.0
median = 120.0
better = "lower"
command = "python speed.py"

[factor]
what = "real time"
unit = "x"
best = 500
median = 400
better = "higher"
command = "python rtf.py"

[rms]
what = "an error"
unit = "m"
best = 0.02
median = 0.02
better = "lower"
command = "python rms.py"
factor = 1.01
"""


def test_the_table_is_parsed_in_order(check):
    rows = check.parse_recorded(TABLE)
    assert list(rows) == ["speed", "factor", "rms"]
    assert rows["factor"].best == 500.0 and rows["factor"].better == "higher"
    assert rows["rms"].factor == 1.01 and rows["speed"].factor is None
    assert rows["speed"].command == "python speed.py"


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ('better = "lower"', r"'speed': 'better' must be one of"),
        ("best = 100.0", r"'speed': 'best' must be a number > 0"),
        ('unit = "ns"', r"'speed' has no 'unit'"),
        ('command = "python speed.py"', r"'speed' has unknown fields \['colour'\]"),
    ],
)
def test_a_bad_table_is_refused_naming_the_row(check, change, match):
    bad = {
        'better = "lower"': 'better = "faster"',
        "best = 100.0": "best = -1.0",
        'unit = "ns"': "",
        'command = "python speed.py"': 'command = "python speed.py"\ncolour = "red"',
    }[change]
    with pytest.raises(ValueError, match=match):
        check.parse_recorded(TABLE.replace(change, bad, 1))


def test_the_ratio_and_the_slip_go_the_way_of_better(check):
    rows = check.parse_recorded(TABLE)
    slower = check.compare(rows["speed"], check.Measured(200.0, 180.0), 1.5)
    assert slower.ratio == 2.0 and slower.median_ratio == 1.5 and slower.slipped
    faster = check.compare(rows["speed"], check.Measured(50.0, 60.0), 1.5)
    assert faster.ratio == 0.5 and faster.slip == 0.5 and not faster.slipped
    # higher is better: a smaller factor is the slip
    lower = check.compare(rows["factor"], check.Measured(250.0, 300.0), 1.5)
    assert lower.slip == 2.0 and lower.slipped
    higher = check.compare(rows["factor"], check.Measured(1000.0, 900.0), 1.5)
    assert higher.slip == 0.5 and not higher.slipped
    # a row's own factor wins over the one given
    rms = check.compare(rows["rms"], check.Measured(0.0204, 0.0204), 1.5)
    assert rms.factor == 1.01 and rms.slipped
    assert not check.compare(rows["rms"], check.Measured(0.0201, 0.0201), 1.5).slipped


def _run(check, tmp_path, argv, measures):
    table = tmp_path / "recorded.toml"
    table.write_text(TABLE, encoding="utf-8")
    lines: list[str] = []
    status = check.main(argv, measures=measures, recorded=table, out=lines.append)
    return status, lines


def _fake(values):
    return {key: (lambda repeat, v=v: v) for key, v in values.items()}


def test_main_prints_every_row_and_fails_only_when_strict(check, tmp_path):
    measures = _fake(
        {
            "speed": check.Measured(300.0, 330.0),  # 3x slower: slipped
            "factor": check.Measured(450.0, 400.0),
            "rms": check.Measured(skipped="no data"),
        }
    )
    status, lines = _run(check, tmp_path, [], measures)
    assert status == 0
    text = "\n".join(lines)
    speed = next(line for line in lines if line.startswith("speed"))
    assert "100 ns / 120 ns" in speed and "300 ns / 330 ns" in speed
    assert "3.000" in speed and "SLIPPED (worse by 3.00x > 1.5x)" in speed
    factor = next(line for line in lines if line.startswith("factor"))
    assert "0.900" in factor and factor.endswith("ok")
    assert "skipped: no data" in text
    assert _run(check, tmp_path, ["--strict"], measures)[0] == 1
    assert _run(check, tmp_path, ["--strict", "--factor", "4"], measures)[0] == 0
    assert _run(check, tmp_path, ["--strict", "--only", "factor", "rms"], measures)[0] == 0


def test_main_refuses_unknown_rows_and_rows_without_a_measurement(check, tmp_path, capsys):
    measures = _fake({k: check.Measured(1.0, 1.0) for k in ("speed", "factor", "rms")})
    with pytest.raises(SystemExit) as info:
        _run(check, tmp_path, ["--only", "nope"], measures)
    assert info.value.code == 2 and "unknown rows nope" in capsys.readouterr().err
    del measures["rms"]
    with pytest.raises(SystemExit):
        _run(check, tmp_path, [], measures)
    assert "without a measurement: rms" in capsys.readouterr().err
    status, lines = _run(check, tmp_path, ["--list"], _fake({"speed": 0, "factor": 0, "rms": 0}))
    assert status == 0 and any("recorded by: python rtf.py" in line for line in lines)


def test_every_recorded_row_has_a_measurement_and_its_row_in_benchmarks_md(check):
    rows = check.parse_recorded((ROOT / "benchmarks" / "recorded.toml").read_text("utf-8"))
    assert set(rows) == set(check.MEASURES)
    text = (ROOT / "BENCHMARKS.md").read_text(encoding="utf-8")
    for key, rec in rows.items():
        found = re.findall(rf"^\| `{key}` \|(.*)$", text, flags=re.M)
        assert len(found) == 1, key
        cells = [c.strip() for c in found[0].rstrip("|").split("|")]
        # | `key` | what | best | median | command |
        assert cells[1] == check._fmt(rec.best, rec.unit), key
        assert cells[2] == check._fmt(rec.median, rec.unit), key
        assert cells[3] == f"`{rec.command}`", key
        assert math.isfinite(rec.best)
