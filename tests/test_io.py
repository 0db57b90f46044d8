"""Atomic writes: a file appears whole or not at all."""

from __future__ import annotations

import os

import numpy as np
import pytest

from flexarm._io import atomic_path
from flexarm.ident import SemiRecursiveKernelRegression


def test_success_replaces_the_target_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp != target
        tmp.write_bytes(b"new")
    assert target.read_bytes() == b"new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bin"]
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask


def test_failure_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError, match="disk"), atomic_path(target) as tmp:
        tmp.write_bytes(b"half")
        raise RuntimeError("disk full")
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bin"]


def test_estimator_save_is_atomic(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    est = SemiRecursiveKernelRegression(kernel="epanechnikov", bandwidth=0.3).fit(
        rng.uniform(size=200), rng.normal(size=200)
    )
    path = tmp_path / "state.npz"
    est.save(path)
    before = path.read_bytes()

    def broken(*args, **kwargs):
        raise OSError("no space left on device")

    monkeypatch.setattr(np, "savez", broken)
    with pytest.raises(OSError, match="no space"):
        est.partial_fit(rng.uniform(size=10), rng.normal(size=10)).save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["state.npz"]
