"""Outputs are replaced all at once: failures and signals leave the previous output intact."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import atomic


def _derive_in_background(*args: str) -> subprocess.Popen:
    """``symkin derive`` in a child whose SIGINT is at its default (a KeyboardInterrupt in Python).

    A shell starts background jobs with SIGINT ignored, Python keeps an ignored SIGINT, and so
    would the child: the interrupt tests must not depend on how the test run was launched.
    """
    return subprocess.Popen(SYMKIN_CLI + ["derive", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _files_of(manifest: dict) -> list[str]:
    """Every file a manifest lists, itself included, sorted."""
    return sorted(["manifest.json"] + [f for b in manifest["backends"].values() for f in b["files"]])


def test_replace_directory_writes_all_files(tmp_path):
    atomic.replace_directory(tmp_path / "m", {"a.txt": "1", "sub/b.bin": b"\x00"})
    assert (tmp_path / "m" / "a.txt").read_text() == "1"
    assert (tmp_path / "m" / "sub" / "b.bin").read_bytes() == b"\x00"
    atomic.replace_directory(tmp_path / "m", {"c.txt": "2"})
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == ["c.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["m"]


def test_failure_while_writing_keeps_the_previous_output(tmp_path, monkeypatch):
    atomic.replace_directory(tmp_path / "m", {"a.txt": "old"})

    class Boom(Exception):
        pass

    real_fsync = atomic.os.fsync
    calls = []

    def failing_fsync(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise Boom()
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", failing_fsync)
    with pytest.raises(Boom):
        atomic.replace_directory(tmp_path / "m", {"a.txt": "new", "b.txt": "new"})
    assert (tmp_path / "m" / "a.txt").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["m"]


@pytest.mark.parametrize("path", ["../escape.txt", "/abs.txt", ""])
def test_paths_outside_the_directory_are_refused(tmp_path, path):
    with pytest.raises(ValueError, match="outside the output directory"):
        atomic.replace_directory(tmp_path / "m", {path: "x"})
    assert not (tmp_path / "m").exists()


@pytest.fixture(scope="module")
def complete_manifest(tmp_path_factory) -> str:
    """The manifest of a complete, uninterrupted derive of the UR10e (derived once)."""
    reference = tmp_path_factory.mktemp("reference")
    subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "ur10e.yaml"), "-o", str(reference), "-q"], check=True)
    return (reference / "ur10e" / "manifest.json").read_text()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("delay", [0.3, 0.8, 1.3])
def test_interrupting_derive_leaves_previous_output_intact(tmp_path, sig, delay, complete_manifest):
    model = str(MODELS_DIR / "ur10e.yaml")
    after = complete_manifest
    tmp_path = tmp_path / "out"
    subprocess.run(SYMKIN_CLI + ["derive", model, "--only", "fk", "-o", str(tmp_path), "-q"], check=True)
    before = (tmp_path / "ur10e" / "manifest.json").read_text()
    proc = _derive_in_background(model, "-o", str(tmp_path), "-q")
    time.sleep(delay)
    proc.send_signal(sig)
    proc.communicate(timeout=60)
    manifest = json.loads((tmp_path / "ur10e" / "manifest.json").read_text())
    files = sorted(p.name for p in (tmp_path / "ur10e").iterdir())
    # Either the old output or the complete new one, never a mix; no staging directories left behind.
    assert files == _files_of(manifest)
    assert (tmp_path / "ur10e" / "manifest.json").read_text() in (before, after)
    if proc.returncode == 0:
        assert (tmp_path / "ur10e" / "manifest.json").read_text() == after
    assert [p.name for p in tmp_path.iterdir()] == ["ur10e"]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_signal_during_the_swap_leaves_the_new_output_and_no_stray_directory(tmp_path, monkeypatch, sig):
    """A signal that arrives while the two renames are held back is delivered right after them:
    the new output is complete and the retired previous output must not be left behind."""
    from symkin.cli import _terminate

    atomic.replace_directory(tmp_path / "m", {"a.txt": "old"})
    real_rename = atomic.os.rename

    def rename_then_signal(src, dst):
        real_rename(src, dst)
        if Path(dst) == tmp_path / "m":
            os.kill(os.getpid(), sig)  # pending until the renames are done

    monkeypatch.setattr(atomic.os, "rename", rename_then_signal)
    previous = signal.signal(signal.SIGTERM, _terminate), signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises((KeyboardInterrupt, SystemExit)):
            atomic.replace_directory(tmp_path / "m", {"a.txt": "new"})
    finally:
        signal.signal(signal.SIGTERM, previous[0])
        signal.signal(signal.SIGINT, previous[1])
    assert (tmp_path / "m" / "a.txt").read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["m"]


def test_interrupting_the_first_derive_leaves_nothing_half_written(tmp_path):
    model = str(MODELS_DIR / "ur10e.yaml")
    for delay in (0.4, 1.0):
        out = tmp_path / f"out{delay}"
        proc = _derive_in_background(model, "-o", str(out), "-q")
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
        if out.exists():
            entries = [p.name for p in out.iterdir()]
            assert entries in ([], ["ur10e"]), entries
            if entries:
                manifest = json.loads((out / "ur10e" / "manifest.json").read_text())
                assert sorted(p.name for p in (out / "ur10e").iterdir()) == _files_of(manifest)


@pytest.mark.parametrize("kind", ["symlink", "file"])
def test_an_output_that_is_a_link_or_a_file_is_refused_untouched(tmp_path, kind):
    """Issue 59: ``-o`` naming a symbolic link or a file is refused (exit 2), not replaced by a directory, and
    nothing (no hidden ``.NAME.old-*``) is left beside it."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "precious.txt").write_text("keep")
    target = tmp_path / "out" / "planar_2r"
    target.parent.mkdir()
    if kind == "symlink":
        target.symlink_to(elsewhere, target_is_directory=True)
    else:
        target.write_text("a file")
    result = subprocess.run(SYMKIN_CLI + ["derive", str(MODELS_DIR / "planar_2r.yaml"), "-o", str(tmp_path / "out"),
                                          "--only", "fk", "--backend", "numpy", "--no-cache"],
                            capture_output=True, text=True)
    assert result.returncode == 2, result.stderr
    assert f"the output {target} is {'a symbolic link' if kind == 'symlink' else 'not a directory'}" in result.stderr
    assert sorted(p.name for p in target.parent.iterdir()) == ["planar_2r"]
    assert sorted(elsewhere.iterdir()) == [elsewhere / "precious.txt"]
    assert (elsewhere / "precious.txt").read_text() == "keep"
    with pytest.raises(Exception, match="symkin replaces only a directory it wrote"):
        atomic.replace_directory(target, {"a.txt": "x"})
