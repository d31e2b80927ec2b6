"""The progress display (issue 19: the line fits the terminal it is drawn on; issue 60: a long stage says what it is
doing, how far it is and about how long is left, on a terminal and in a log)."""

from __future__ import annotations

import io
import re
import time

import pytest

from symkin.cli.progress import Progress, terminal_columns

#: Terminal control sequences (cursor moves, erasing) that rich writes around the status line.
CONTROL = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _lines(columns: int, stage: str, monkeypatch, **count) -> list[str]:
    monkeypatch.setenv("COLUMNS", str(columns))
    stream = Terminal()
    with Progress("model", stream=stream, delay=0.0) as progress:
        progress(stage, **count)
        time.sleep(0.35)
    return [line for line in re.split(r"[\r\n]", CONTROL.sub("", stream.getvalue())) if line.strip()]


@pytest.mark.parametrize("columns", [40, 100, 200])
def test_the_line_is_as_wide_as_the_terminal_less_one_column(columns, monkeypatch):
    stage = "derive " + "x" * 300
    lines = _lines(columns, stage, monkeypatch)
    assert lines
    assert all(len(line) == columns - 1 for line in lines)     # never wraps
    assert lines[0][1:].lstrip().startswith("[model] derive xxx")   # after the spinner


def test_a_short_stage_on_a_wide_terminal_is_shown_whole(monkeypatch):
    stage = "stage " + "y" * 130                                          # longer than the old 120-column cut
    lines = _lines(200, stage, monkeypatch)
    assert stage in lines[0]


def test_a_counted_stage_shows_its_count_on_the_terminal(monkeypatch):
    lines = _lines(120, "deriving fk", monkeypatch, done=3, total=12)
    assert "[model] deriving fk: 3/12" in lines[0]


def test_the_status_line_is_cleared_at_the_end(monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    stream = Terminal()
    with Progress("model", stream=stream, delay=0.0) as progress:
        progress("stage")
        time.sleep(0.25)
    assert stream.getvalue().endswith(("\x1b[2K", "\x1b[?25h"))   # erased, the cursor shown again


def test_a_long_stage_reports_its_count_and_estimate_in_a_log():
    """Not a terminal: a line when a stage has run ``delay`` s, then its count and the time left at the pace so far
    (here 0.1 s an item: the estimate for the items left), then its time."""
    stream = io.StringIO()
    with Progress("model", stream=stream, delay=0.05, log_interval=0.2) as progress:
        for done in range(8):
            progress("deriving", done=done, total=8)
            time.sleep(0.1)
    lines = stream.getvalue().splitlines()
    assert re.fullmatch(r"  \[model\] deriving: \d/8.* \.\.\.", lines[0])      # announced once it has run a while
    estimates = [float(m.group(1)) for line in lines if (m := re.search(r"about (\d+) s left", line))]
    assert estimates, lines
    assert re.fullmatch(r"  \[model\] deriving: \d\.\d s", lines[-1])


def test_a_quick_command_prints_nothing():
    for stream in (io.StringIO(), Terminal()):
        with Progress("model", stream=stream, delay=1.0) as progress:
            progress("stage", done=1, total=2)
        assert stream.getvalue() == ""


def test_the_estimate_is_the_pace_so_far_times_what_is_left():
    progress = Progress("model", stream=io.StringIO())
    progress("work", done=0, total=10)
    progress._count_start -= 2.0                         # two seconds ago ...
    progress("work", done=4, total=10)                   # ... four items done: half a second each, six left
    assert progress.remaining() == pytest.approx(3.0, abs=0.05)
    assert progress.status().startswith("[model] work: 4/10, about 3 s left")


def test_the_width_comes_from_columns_then_the_terminal_then_80(monkeypatch):
    monkeypatch.setenv("COLUMNS", "132")
    assert terminal_columns(io.StringIO()) == 132
    monkeypatch.delenv("COLUMNS")
    assert terminal_columns(io.StringIO()) == 80                           # not a terminal: the fallback


def test_the_derivation_reports_each_function_with_its_count():
    """symkin derive's stages: each function derived and optimized as k of n, then each backend emitted."""
    from conftest import MODELS_DIR
    from symkin import pipeline
    from symkin.model import load_model

    model = load_model(MODELS_DIR / "planar_2r.yaml")
    request = pipeline.resolve_request(model, "fk,jacobian", "numpy,js", fixed="all")
    calls: list[tuple[str, int | None, int | None]] = []
    pipeline.generate(model, request, lambda stage, done=None, total=None: calls.append((stage, done, total)))
    n = 2 + bool(request.combine)                           # the scene's combined function counts too
    assert calls[:4] == [("deriving fk", 0, n), ("optimizing fk", 0, n), ("deriving jacobian", 1, n),
                         ("optimizing jacobian", 1, n)]
    assert calls[-2:] == [("emitting numpy code", 0, 2), ("emitting js code", 1, 2)]


def test_a_count_without_a_total_is_shown_as_it_is():
    progress = Progress("model", stream=io.StringIO())
    progress("flooding (cells reached)", done=12)
    assert progress.status() == "[model] flooding (cells reached): 12"


def test_the_open_display_is_the_librarys_reporter_and_the_previous_one_comes_back():
    from symkin.reporting import report_progress, reporting_to

    report_progress("nobody listens", done=1, total=2)       # no reporter installed: nothing happens
    outer: list[tuple] = []
    with reporting_to(lambda stage, done=None, total=None: outer.append((stage, done, total))):
        with Progress("model", stream=io.StringIO(), enabled=False) as progress:
            report_progress("inner loop", done=3, total=7)
        assert progress.status().startswith("[model] inner loop: 3/7")
        report_progress("after", done=1)
    assert outer == [("after", 1, None)]


def _recorded(run) -> list[tuple]:
    from symkin.reporting import reporting_to

    calls: list[tuple] = []
    with reporting_to(lambda stage, done=None, total=None: calls.append((stage, done, total))):
        run()
    return calls


def test_a_simulation_reports_its_periods_and_its_simulated_time():
    import numpy as np

    from symkin.simulation.integrate import REPORT_PERIODS, run_adaptive, run_sampled

    def rhs(t, x, u):
        return np.array([x[1], -x[0] + u[0]])

    def control(t, x):
        return np.array([0.0])

    sampled = _recorded(lambda: run_sampled(rhs, control, np.array([1.0, 0.0]), 1e-3, 200))
    assert sampled == [("simulating (control periods)", k, 200) for k in range(0, 200, REPORT_PERIODS)]
    adaptive = _recorded(lambda: run_adaptive(rhs, control, np.array([1.0, 0.0]), np.linspace(0.0, 0.05, 11)))
    done = [d for _stage, d, _total in adaptive]
    assert {(stage, total) for stage, _d, total in adaptive} == {("simulating (ms of simulated time)", 50)}
    assert done == sorted(set(done))                         # at most once a millisecond, forward
    assert done[-1] == 50


def test_ipopt_reports_each_iteration_of_at_most_max_iter():
    import casadi

    from symkin.design.solving import IPOPT_OPTIONS, IterationReport

    x = casadi.MX.sym("x", 2)
    problem = {"x": x, "f": (x[0] - 1) ** 2 + 10 * (x[1] - x[0] ** 2) ** 2, "g": x[0] + x[1]}
    iterations = IterationReport("solving (IPOPT iterations)", problem, 50)
    solver = casadi.nlpsol("rosenbrock", "ipopt", problem, IPOPT_OPTIONS | {"ipopt.max_iter": 50}
                           | iterations.options())
    calls = _recorded(lambda: solver(x0=[-1.0, 1.0], lbg=-10, ubg=10))
    count = solver.stats()["iter_count"]
    assert calls == [("solving (IPOPT iterations)", k, 50) for k in range(count + 1)]   # iteration 0 is the start
