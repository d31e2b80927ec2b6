"""``symkin cache list|clear`` (issue 19, audit: the C build cache was never evicted)."""

from __future__ import annotations

import fcntl
import os
import time

import pytest

from symkin import load
from symkin.backends.c.cache import cached_libraries, clear
from symkin.cli import main
from tests.conftest import GENERATED_DIR

DAY = 86400.0


@pytest.fixture()
def cache(tmp_path, monkeypatch):
    directory = tmp_path / "cache"
    monkeypatch.setenv("SYMKIN_CACHE_DIR", str(directory))
    monkeypatch.setenv("SYMKIN_QUIET", "1")
    load(GENERATED_DIR / "planar_2r", "c")
    return directory


def _age(path, days):
    stamp = time.time() - days * DAY
    os.utime(path, (stamp, stamp))


def test_list_shows_the_compiled_library_and_a_load_marks_its_use(cache, capsys):
    (library,) = cached_libraries(cache)
    assert library.model == "planar_2r"
    assert library.size > 0
    assert main(["cache", "list"]) == 0
    out = capsys.readouterr().out
    assert str(cache) in out
    assert library.path.name in out
    assert "1 library" in out
    _age(library.path, 10)
    load(GENERATED_DIR / "planar_2r", "c")          # a cache hit: no build, but a use
    assert time.time() - cached_libraries(cache)[0].last_used < DAY


def test_clear_by_age_and_model_and_everything(cache, capsys):
    (library,) = cached_libraries(cache)
    _age(library.path, 10)
    assert clear(cache, older_than=20 * DAY).removed == ()
    assert clear(cache, model="delta").removed == ()
    assert main(["cache", "clear", "--older-than", "5"]) == 0
    assert "removed 1 library" in capsys.readouterr().out
    assert cached_libraries(cache) == []
    assert not any(cache.iterdir())   # the lock file went with it
    model = load(GENERATED_DIR / "planar_2r", "c")   # rebuilt on the next load
    assert model.fk([0.1, 0.2]).shape == (4, 4)
    assert main(["cache", "clear"]) == 0
    assert cached_libraries(cache) == []


def test_a_library_whose_build_lock_is_held_is_left_alone(cache, capsys):
    (library,) = cached_libraries(cache)
    with open(library.path.with_name(library.path.name + ".lock"), "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        assert main(["cache", "clear"]) == 0
        fcntl.flock(handle, fcntl.LOCK_UN)
    assert "a build holds its lock" in capsys.readouterr().out
    assert cached_libraries(cache) == [library] or cached_libraries(cache)[0].path == library.path


@pytest.mark.parametrize("arguments", [["cache"], ["cache", "clear", "--older-than", "soon"],
                                       ["cache", "clear", "--older-than", "-1"]])
def test_bad_cache_arguments_exit_with_code_2(arguments, cache, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(arguments)
    assert exit_info.value.code == 2
    assert len(cached_libraries(cache)) == 1
