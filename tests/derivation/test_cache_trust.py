"""Issue 59 (severe 4, 5): the cache is data, not code - planted entries neither run nor write outside ``-o``.

The attacker here can write into the cache folder (a shared ``SYMKIN_CACHE_DIR``, a CI cache restored from
another job) but does not hold the per-user secret, which lives outside the cache.  References: the planted
files themselves (a module that would write a marker file when imported, an entry naming a folder outside
``-o``), and the folder modes a shared cache has.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
from pathlib import Path

import pytest

from conftest import GENERATED_DIR, MODELS_DIR, SYMKIN_CLI
from symkin import cache_trust, load, pipeline_cache
from symkin.errors import CacheTrustError

REQUEST = ["--only", "fk,jacobian", "--backend", "numpy"]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    directory = tmp_path / "cache"
    monkeypatch.setenv("SYMKIN_CACHE_DIR", str(directory))
    monkeypatch.setenv("SYMKIN_QUIET", "1")
    return directory


def derive(model: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(SYMKIN_CLI + ["derive", str(model), "-o", str(out), *REQUEST, *extra],
                          capture_output=True, text=True, env=os.environ)


def plant(entry: Path, files: dict[str, bytes], model: str, mac: str | None = None) -> None:
    """Rewrite ``entry`` as an attacker would: new files, their hashes recorded, a seal the attacker can make."""
    import shutil

    shutil.rmtree(entry / "files")
    hashes = {}
    for name, data in files.items():
        (entry / "files" / name).parent.mkdir(parents=True, exist_ok=True)
        (entry / "files" / name).write_bytes(data)
        hashes[name] = hashlib.sha256(data).hexdigest()
    record = {"model": model, "notes": [], "files": hashes}
    if mac is not None:
        record["mac"] = mac
    (entry / "entry.json").write_text(json.dumps(record))


def test_a_planted_module_in_a_derivation_entry_is_not_run(cache, tmp_path):
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    assert derive(model, tmp_path / "first").returncode == 0
    (entry,) = [p for p in (cache / "derivations").iterdir() if not p.name.startswith(".")]
    marker = tmp_path / "planted-code-ran"
    original = {p.relative_to(entry / "files").as_posix(): p.read_bytes()
                for p in (entry / "files").rglob("*") if p.is_file()}
    payload = f"open({str(marker)!r}, 'w').write('ran')\n".encode()
    planted = {name: (payload + data if name.endswith(".py") else data) for name, data in original.items()}
    for mac in (None, "0" * 64, hashlib.sha256(b"guess").hexdigest()):  # no seal, a forged one
        plant(entry, planted, "planar_2r", mac)
        hit = derive(model, tmp_path / "second")
        assert hit.returncode == 0, hit.stderr
        assert "unchanged since a derivation kept in the cache" not in hit.stdout   # derived afresh
        module = next((tmp_path / "second" / "planar_2r").rglob("*.py"))
        assert str(marker) not in module.read_text()
        load(tmp_path / "second" / "planar_2r", "numpy")
        assert not marker.exists()
        (entry,) = [p for p in (cache / "derivations").iterdir() if not p.name.startswith(".")]


def test_a_planted_model_name_cannot_replace_a_folder_outside_the_output(cache, tmp_path):
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    assert derive(model, tmp_path / "out").returncode == 0
    victim = tmp_path / "victim"
    victim.mkdir()
    (victim / "precious.txt").write_text("keep me")
    (entry,) = [p for p in (cache / "derivations").iterdir() if not p.name.startswith(".")]
    files = {p.relative_to(entry / "files").as_posix(): p.read_bytes()
             for p in (entry / "files").rglob("*") if p.is_file()}
    record = json.loads((entry / "entry.json").read_text())
    for name in ("../victim", str(victim), "planar_2r/../../victim"):
        plant(entry, files, name, record["mac"])          # even the genuine seal of another name
        result = derive(model, tmp_path / "out")
        assert result.returncode == 0, result.stderr
        assert (victim / "precious.txt").read_text() == "keep me"
        assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["planar_2r"]
        (entry,) = [p for p in (cache / "derivations").iterdir() if not p.name.startswith(".")]


def test_a_planted_compiled_library_is_built_again(cache, tmp_path):
    # built in another process: this one must not have the library mapped when it is overwritten in place
    subprocess.run([*SYMKIN_CLI[:1], "-c", f"from symkin import load; load({str(GENERATED_DIR / 'planar_2r')!r}, 'c')"],
                   check=True, env=os.environ)
    (library,) = [p for p in cache.iterdir() if p.name.endswith(".so")]
    genuine = library.read_bytes()
    planted = genuine[:-1] + bytes([genuine[-1] ^ 1])                        # another library under its name
    library.write_bytes(planted)
    (cache / (library.name + ".seal")).write_text(hashlib.sha256(planted).hexdigest())
    model = load(GENERATED_DIR / "planar_2r", "c")
    assert library.read_bytes() != planted                                   # rebuilt, not loaded
    assert model.fk([0.1, 0.2]).shape == (4, 4)


def test_a_cache_folder_others_can_write_or_own_is_refused(cache, tmp_path):
    cache.mkdir(mode=0o700)
    os.chmod(cache, 0o777)
    with pytest.raises(CacheTrustError, match="writable by others.*\n    fix: chmod go-w"):
        load(GENERATED_DIR / "planar_2r", "c")
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes((MODELS_DIR / "planar_2r.yaml").read_bytes())
    result = derive(model, tmp_path / "out")
    assert result.returncode == 2
    assert "writable by others" in result.stderr
    assert "Traceback" not in result.stderr
    os.chmod(cache, 0o700)
    cache.rmdir()
    cache.symlink_to(tmp_path, target_is_directory=True)
    with pytest.raises(CacheTrustError, match="symbolic link"):
        pipeline_cache.directory()


def test_the_secret_is_private_and_kept_outside_the_cache(cache, tmp_path, monkeypatch):
    secret = tmp_path / "config" / "cache-secret"
    monkeypatch.setenv("SYMKIN_CACHE_SECRET", str(secret))
    cache_trust._secret.cache_clear()
    try:
        first = cache_trust.seal("label", "digest")
        assert secret.stat().st_mode & 0o777 == 0o600
        assert len(secret.read_bytes()) == cache_trust.SECRET_BYTES
        assert not str(secret).startswith(str(cache))
        cache_trust._secret.cache_clear()
        assert cache_trust.seal("label", "digest") == first                    # read back, not made anew
        os.chmod(secret, 0o644)
        cache_trust._secret.cache_clear()
        with pytest.raises(CacheTrustError, match="not a private file"):
            cache_trust.seal("label", "digest")
    finally:
        cache_trust._secret.cache_clear()


def test_a_robot_file_that_includes_others_is_never_cached_whatever_precedes_its_root(tmp_path):
    """A byte-order mark (or a comment) before the root element hid a xacro's includes from the cache key: a
    stale derivation came back after an included file changed."""
    text = ('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:include filename="a.xacro"/></robot>')
    for prefix in (b"", b"\xef\xbb\xbf", b"<!-- arm -->\n", b"\xef\xbb\xbf<?xml version='1.0'?>\n"):
        path = tmp_path / "arm.urdf.xacro"
        path.write_bytes(prefix + text.encode())
        assert pipeline_cache.request_key(path, {"only": "fk"}) is None, prefix
    path.write_bytes(text.encode("utf-16"))
    assert pipeline_cache.request_key(path, {"only": "fk"}) is None
    model = tmp_path / "planar_2r.yaml"
    model.write_bytes(b"\xef\xbb\xbf" + (MODELS_DIR / "planar_2r.yaml").read_bytes())
    assert pipeline_cache.request_key(model, {"only": "fk"}) is not None
