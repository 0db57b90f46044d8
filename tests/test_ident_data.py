"""Reading identification data (:mod:`flexarm.ident.data`): CSV, text and .npz columns,
and one-line :class:`DataError` messages naming the file, the place and the delimiter."""

from __future__ import annotations

import numpy as np
import pytest

from flexarm.errors import InvalidValueError
from flexarm.ident.data import DataError, load_columns, read_xy
from helpers.ident import files_fixture, samples_fixture  # noqa: F401 (the fixtures)


def test_load_columns_all_formats(files, samples):
    x, y = samples
    for path, cols in [
        (files["csv"], ["u", "w"]),
        (files["csv"], ["1", "2"]),
        (files["csv"], [1, "w"]),
        (files["txt"], ["0", "1"]),
        (files["npz"], ["u", "w"]),
        (files["npz"], [0, 1]),
        (files["table"], [1, 2]),
    ]:
        a, b = load_columns(path, cols)
        np.testing.assert_array_equal(a, x)
        np.testing.assert_array_equal(b, y)


def test_load_columns_empty_cells_are_nan(tmp_path):
    p = tmp_path / "n.csv"
    p.write_text("a,b,c\n1,2,x\n3,,y\nnan,4,z\n")
    a, b = load_columns(p, ["a", "b"])  # column c is not numeric, and not asked for
    np.testing.assert_array_equal(np.isnan(a), [False, False, True])
    np.testing.assert_array_equal(np.isnan(b), [False, True, False])


@pytest.mark.parametrize(
    ("text", "suffix", "cols", "match"),
    [
        ("a,b\n1,2\n3\n", ".csv", ["a", "b"], "line 3: 1 field"),
        ("a,b\n1,2\n3,oops\n", ".csv", ["a", "b"], "line 3, column 'b': 'oops' is not a number"),
        ("a,b\n1,2\n", ".csv", ["a", "c"], "no column named 'c' \\(columns: a, b;"),
        ("1 2\n3 4\n", ".txt", ["0", "5"], "column index 5 is out of range"),
        ("1 2\n3 4\n", ".txt", ["x", "1"], "no column named 'x' \\(the file has no header;"),
        ("a,b\n", ".csv", ["a", "b"], "header but no data rows"),
        ("\n\n", ".txt", ["0", "1"], "holds no data"),
        ("not a zip", ".npz", ["0", "1"], "not a readable .npz"),
    ],
)
def test_load_columns_errors(tmp_path, text, suffix, cols, match):
    p = tmp_path / f"bad{suffix}"
    p.write_text(text)
    with pytest.raises(DataError, match=match):
        load_columns(p, cols)


def test_data_error_is_flexarms_own_value_error():
    assert issubclass(DataError, InvalidValueError) and issubclass(DataError, ValueError)


@pytest.mark.parametrize(
    ("name", "content", "cols", "match"),
    [
        ("a.csv", "a,b\n1,2\n3\n", ["a", "b"], r"'.*a\.csv' line 3: .*comma-separated CSV"),
        ("a.txt", "1 2\n3 x\n", ["0", "1"], r"'.*a\.txt' line 2, column '1'.*whitespace"),
        ("a.csv", 'a,b\n"1,2\n', ["a", "b"], r"'.*a\.csv' is not valid comma-separated CSV"),
        ("b.txt", b"\xff\xfe\x00bad", ["0", "1"], r"'.*b\.txt' is not a UTF-8 text file"),
    ],
)
def test_messages_name_the_file_the_place_and_the_delimiter(tmp_path, name, content, cols, match):
    p = tmp_path / name
    if isinstance(content, bytes):
        p.write_bytes(content)
    else:
        p.write_text(content)
    with pytest.raises(DataError, match=match) as info:
        load_columns(p, cols)
    assert "\n" not in str(info.value)


def test_a_directory_or_a_missing_file_is_a_data_error(tmp_path):
    with pytest.raises(DataError, match="is not a file"):
        load_columns(tmp_path, ["0"])
    with pytest.raises(DataError, match="does not exist"):
        load_columns(tmp_path / "none.csv", ["0"])


def test_npz_problems(tmp_path):
    p = tmp_path / "x.npz"
    np.savez(p, a=np.zeros(3), b=np.zeros(4))
    with pytest.raises(DataError, match="different lengths"):
        load_columns(p, ["a", "b"])
    np.savez(p, a=np.zeros((2, 2)), b=np.zeros(2))
    with pytest.raises(DataError, match="not one-dimensional"):
        load_columns(p, ["a", "b"])
    np.savez(p, a=np.array(["x", "y"]), b=np.zeros(2))
    with pytest.raises(DataError, match="column 'a' is not numeric"):
        load_columns(p, ["a", "b"])


def test_read_xy_drops_or_refuses_nan_rows(tmp_path):
    p = tmp_path / "g.csv"
    p.write_text("u,w\n1,2\n2,\nnan,3\n4,5\n")
    with pytest.raises(DataError, match=r"2 row\(s\) have NaN.*data row 2"):
        read_xy(p, "u", "w")
    x, y, dropped = read_xy(p, "u", "w", drop_nan=True)
    np.testing.assert_array_equal(x, [1.0, 4.0])
    np.testing.assert_array_equal(y, [2.0, 5.0])
    assert dropped == 2
    x0, y0, _ = read_xy(p, drop_nan=True)  # default columns 0 and 1
    np.testing.assert_array_equal(x0, x)
    np.testing.assert_array_equal(y0, y)


@pytest.mark.parametrize(
    ("text", "match"),
    [("u,w\n1,2\n2,inf\n", "infinite"), ("u,w\n1,2\n", "at least 2 data rows")],
)
def test_read_xy_bad_rows(tmp_path, text, match):
    p = tmp_path / "r.csv"
    p.write_text(text)
    with pytest.raises(DataError, match=match):
        read_xy(p, "u", "w")
