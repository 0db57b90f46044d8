"""``flexarm identify fit`` and ``flexarm identify study``: the fit and the study outputs,
one-line errors with status 2 and nothing written, and bugs that stay bugs.

Reading the data files is :mod:`flexarm.ident.data` (tests/test_ident_data.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexarm.ident.fits
import flexarm.ident.regression.convergence
from flexarm.cli import main
from flexarm.ident import SemiRecursiveKernelRegression
from helpers.cli import error_line, run, strict_json
from helpers.ident import files_fixture, samples_fixture  # noqa: F401 (the fixtures)

N = 400
FIT_FILES = {"estimate.csv", "estimate.png", "summary.json"}
FIT_KEYS = {
    "status",
    "mode",
    "data",
    "columns",
    "n_samples",
    "dropped_nan_rows",
    "estimator",
    "kernel",
    "bandwidth",
    "bandwidth_rule",
    "decay",
    "last_bandwidth",
    "binned",
    "series",
    "error_bound_max",
    "grid",
    "points_without_estimate",
    "wall_time_s",
    "out",
    "files",
    "estimate",
}


def identify(capsys, *argv):
    """``flexarm identify ARGV``: the status, stdout and stderr."""
    return run(capsys, "identify", *argv)


# ------------------------------------------------------------------ fitting


def test_json_summary_and_estimate(capsys, files, samples):
    x, y = samples
    argv = ["fit", files["csv"], "--x", "u", "--y", "w", "--json", "--grid", 64]
    status, out, err = identify(capsys, *argv)
    assert status == 0, err
    s = strict_json(out)
    assert set(s) == FIT_KEYS
    assert s["status"] == "ok" and s["n_samples"] == N and s["dropped_nan_rows"] == 0
    assert s["bandwidth_rule"] == "silverman" and s["grid"]["points"] == 64
    grid = np.linspace(x.min(), x.max(), 64)
    ref = SemiRecursiveKernelRegression("gaussian", s["bandwidth"], 0.2).fit(x, y).predict(grid)
    np.testing.assert_allclose(s["estimate"]["m"], ref, rtol=1e-12)
    np.testing.assert_allclose(s["estimate"]["x"], grid, rtol=0, atol=0)


def test_formats_and_columns_give_the_same_estimate(capsys, files):
    results = []
    for argv in (
        [files["csv"], "--x", "u", "--y", "w"],
        [files["csv"], "--x", "1", "--y", "2"],
        [files["txt"]],
        [files["npz"], "--x", "u", "--y", "w"],
        [files["table"], "--x", "1", "--y", "2"],
    ):
        status, out, err = identify(
            capsys, "fit", *argv, "--json", "--grid", 32, "--bandwidth", 0.3
        )
        assert status == 0, err
        results.append(strict_json(out)["estimate"]["m"])
    for r in results[1:]:
        assert r == results[0]


def test_out_writes_csv_png_and_summary(capsys, files, tmp_path):
    out_dir = tmp_path / "res"
    status, out, err = identify(
        capsys,
        "fit",
        files["npz"],
        "--x",
        "u",
        "--y",
        "w",
        "--out",
        out_dir,
        "--binned",
        "--kernel",
        "epanechnikov",
        "--grid",
        50,
    )
    assert status == 0, err
    assert {p.name for p in out_dir.iterdir()} == FIT_FILES
    table = np.loadtxt(out_dir / "estimate.csv", delimiter=",", skiprows=1)
    assert table.shape == (50, 2)
    s = json.loads((out_dir / "summary.json").read_text())
    assert s["binned"] == 0.1 and s["kernel"] == "epanechnikov" and s["error_bound_max"] >= 0
    assert (out_dir / "estimate.png").read_bytes()[:4] == b"\x89PNG"
    assert "results in" in out


def test_series_equals_direct_sums(capsys, files):
    argv = ["fit", files["npz"], "--x", "u", "--y", "w", "--json", "--decay", 0, "--grid", 40]
    _, out, _ = identify(capsys, *argv)
    status, out_series, err = identify(capsys, *argv, "--series")
    assert status == 0, err
    direct, series = strict_json(out)["estimate"]["m"], strict_json(out_series)["estimate"]["m"]
    assert strict_json(out_series)["series"] is True
    np.testing.assert_allclose(series, direct, rtol=1e-12)
    status, _, err = identify(capsys, "fit", files["npz"], "--series")  # decay 0.2: refused
    assert status == 2 and "'series'" in err


def test_drop_nan_reports_the_count(capsys, tmp_path, samples):
    x, y = samples
    p = tmp_path / "gaps.csv"
    rows = [f"{a!r},{b!r}" for a, b in zip(x.tolist(), y.tolist(), strict=True)]
    rows[3] = f"{float(x[3])!r},"
    rows[10] = f"nan,{float(y[10])!r}"
    p.write_text("u,w\n" + "\n".join(rows) + "\n")
    status, out, err = identify(capsys, "fit", p, "--drop-nan", "--json", "--grid", 16)
    assert status == 0, err
    s = strict_json(out)
    assert s["dropped_nan_rows"] == 2 and s["n_samples"] == N - 2


# ------------------------------------------------------------------ errors


GOOD = "u,w\n1,2\n2,3\n"


def bad_file(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("make", "extra", "match"),
    [
        (lambda d: d / "missing.csv", [], "does not exist"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n"), ["--x", "q"], "no column named 'q'"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,x\n"), [], "'x' is not a number"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,\n3,4\n"), [], "1 row\\(s\\) have NaN"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,3\n"), ["--bandwidth", "-1"], "'bandwidth'"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,3\n"), ["--bandwidth", "wide"], "--bandwidth"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,3\n"), ["--kernel", "cosine"], "--kernel"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,3\n"), ["--decay", "3"], "'decay'"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,3\n"), ["--binned", "0.9"], "'binned'"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,3\n"), ["--grid", "1"], "--grid"),
        # options of the other subcommands are unknown here: no conflict table needed
        (lambda d: bad_file(d, "a.csv", GOOD), ["--study"], "unrecognized.*--study"),
        (lambda d: bad_file(d, "a.csv", GOOD), ["--seed", "1"], "unrecognized.*--seed"),
        (lambda d: bad_file(d, "a.csv", GOOD), ["--lags", "5"], "unrecognized.*--lags"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,1\n1,3\n"), [], "'x' parameter.*must vary"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n2,inf\n"), [], "infinite"),
        (lambda d: bad_file(d, "a.csv", "u,w\n1,2\n"), [], "at least 2 data rows"),
        (lambda d: bad_file(d, "a.csv", GOOD), ["--bandwidth", "scott"], "--bandwidth"),
        (lambda d: bad_file(d, "a.npz", "zzz"), [], "not a readable .npz"),
        (lambda d: bad_file(d, "a.txt", "1 2\n3\n"), [], "line 2: 1 field"),
    ],
)
def test_errors_are_one_line_with_status_2_and_nothing_written(
    capsys, tmp_path, make, extra, match
):
    data = make(tmp_path)
    out_dir = tmp_path / "out"
    before = sorted(p.name for p in tmp_path.iterdir())
    status, out, err = identify(capsys, "fit", data, "--out", out_dir, *extra)
    assert status == 2
    assert out == ""
    assert error_line(err).startswith("flexarm identify fit: error:")
    assert pytest.importorskip("re").search(match, err), err
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_out_not_empty_is_refused(capsys, tmp_path, files):
    out_dir = tmp_path / "full"
    out_dir.mkdir()
    (out_dir / "keep.txt").write_text("mine")
    status, _, err = identify(capsys, "fit", files["csv"], "--out", out_dir)
    assert status == 2 and "not an empty directory" in err
    assert [p.name for p in out_dir.iterdir()] == ["keep.txt"]


def test_no_subcommand_or_no_data_is_an_error(capsys):
    status, _, err = identify(capsys)
    assert status == 2 and "fit,study,hammerstein" in err and len(err.strip().splitlines()) == 1
    status, _, err = identify(capsys, "fit")
    assert status == 2 and "DATA" in err and len(err.strip().splitlines()) == 1


# ------------------------------------------------------------------ study


def test_study_json_and_out(capsys, tmp_path):
    argv = ["study", "--n-min", 100, "--n-max", 800, "--n-steps", 3, "--repetitions", 3]
    status, out, err = identify(capsys, *argv, "--seed", 5, "--json")
    assert status == 0, err
    s = strict_json(out)
    assert s["mode"] == "study" and s["n"] == [100, 283, 800] and len(s["mise"]) == 3
    assert s["theory_slope"] == pytest.approx(-0.8) and s["seed"] == 5
    status, out2, err = identify(capsys, *argv, "--seed", 5, "--out", tmp_path / "st", "--json")
    assert status == 0, err
    again = strict_json(out2)
    assert again["mise"] == s["mise"]  # seeded: the same numbers
    assert {p.name for p in (tmp_path / "st").iterdir()} == {
        "study.csv",
        "study.png",
        "summary.json",
    }
    table = np.loadtxt(tmp_path / "st" / "study.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 1], s["mise"], rtol=1e-9)


def test_study_bad_options(capsys, tmp_path):
    status, _, err = identify(capsys, "study", "--n-min", 500, "--n-max", 100)
    assert status == 2 and "--n-min 500" in err and "--n-max 100" in err
    status, _, err = identify(capsys, "study", "--function", "cosine")
    assert status == 2 and "--function" in err
    status, _, err = identify(capsys, "study", "--x", "u")
    assert status == 2 and "unrecognized arguments: --x" in err


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--n-min", "500", "--n-max", "100"], "--n-max must be larger than --n-min"),
        (["--n-steps", "1"], "--n-steps"),
        (["--repetitions", "1"], "--repetitions"),
        (["--noise", "-1"], "'noise'"),
        (["--bandwidth", "0"], "'bandwidth'"),
        (["--decay", "-0.5"], "'decay'"),
        (["--kernel", "cosine"], "--kernel"),
        (["--distribution", "cauchy"], "--distribution"),
        (["--grid", "10"], "unrecognized arguments: --grid"),
        (["data.csv"], "unrecognized arguments: data.csv"),
    ],
)
def test_study_errors_are_one_line_with_status_2_and_nothing_written(
    capsys, tmp_path, extra, match
):
    out_dir = tmp_path / "out"
    argv = ["study", "--n-min", 20, "--n-max", 40, "--repetitions", 2, *extra]
    status, out, err = identify(capsys, *argv, "--out", out_dir)
    assert status == 2 and out == ""
    error_line(err)  # one line, no traceback
    assert pytest.importorskip("re").search(match, err), err
    assert not out_dir.exists()


def test_fit_files_hold_what_the_summary_says(capsys, files, tmp_path):
    out_dir = tmp_path / "res"
    argv = ["fit", files["csv"], "--x", "u", "--y", "w", "--grid", 30, "--out", out_dir]
    status, out, err = identify(capsys, *argv, "--json")
    assert status == 0, err
    s = strict_json(out)
    assert strict_json((out_dir / "summary.json").read_text()) == s
    table = np.loadtxt(out_dir / "estimate.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 0], s["estimate"]["x"], rtol=1e-11)
    np.testing.assert_allclose(table[:, 1], s["estimate"]["m"], rtol=1e-11)
    assert sorted(s["files"]) == sorted(p.name for p in out_dir.iterdir())


def _bug(*args, **kwargs):
    raise ValueError("a bug inside the library, not bad input")


@pytest.mark.parametrize(
    ("module", "name", "argv"),
    [
        (flexarm.ident.fits, "fit_regression", ["fit", "{csv}"]),
        (flexarm.ident.fits, "fit_hammerstein", ["hammerstein", "{csv}"]),
        (flexarm.ident.regression.convergence, "convergence_study", ["study"]),
    ],
)
def test_a_plain_value_error_is_a_bug_not_exit_2(monkeypatch, files, module, name, argv):
    """Only flexarm's own validation errors become exit status 2; anything else propagates
    (and shows its traceback) so that a library bug cannot pass for bad input."""
    monkeypatch.setattr(module, name, _bug)
    with pytest.raises(ValueError, match="a bug inside the library"):
        main(["identify", *(a.format(csv=files["csv"]) for a in argv)])


def test_a_plain_value_error_while_reading_is_a_bug(monkeypatch, files):
    import flexarm.ident.data

    monkeypatch.setattr(flexarm.ident.data, "load_columns", _bug)
    with pytest.raises(ValueError, match="a bug inside the library"):
        main(["identify", "fit", str(files["csv"])])
