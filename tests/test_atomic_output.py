"""Outputs are replaced all at once: failures and signals leave the previous output intact."""

from __future__ import annotations

import json
import signal
import subprocess
import time

import pytest

from conftest import MODELS_DIR, SYMKIN_CLI
from symkin import atomic


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


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("delay", [0.3, 0.8, 1.3])
def test_interrupting_derive_leaves_previous_output_intact(tmp_path, sig, delay):
    model = str(MODELS_DIR / "ur10e.yaml")
    reference = tmp_path / "reference"
    subprocess.run(SYMKIN_CLI + ["derive", model, "-o", str(reference), "-q"], check=True)
    after = (reference / "ur10e" / "manifest.json").read_text()
    tmp_path = tmp_path / "out"
    subprocess.run(SYMKIN_CLI + ["derive", model, "--only", "fk", "-o", str(tmp_path), "-q"], check=True)
    before = (tmp_path / "ur10e" / "manifest.json").read_text()
    proc = subprocess.Popen(SYMKIN_CLI + ["derive", model, "-o", str(tmp_path), "-q"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    time.sleep(delay)
    proc.send_signal(sig)
    proc.communicate(timeout=60)
    manifest = json.loads((tmp_path / "ur10e" / "manifest.json").read_text())
    files = sorted(p.name for p in (tmp_path / "ur10e").iterdir())
    # Either the old output or the complete new one, never a mix; no staging directories left behind.
    assert files == sorted(["manifest.json"] + [f for b in manifest["backends"].values() for f in b["files"]])
    assert (tmp_path / "ur10e" / "manifest.json").read_text() in (before, after)
    if proc.returncode == 0:
        assert (tmp_path / "ur10e" / "manifest.json").read_text() == after
    assert [p.name for p in tmp_path.iterdir()] == ["ur10e"]
