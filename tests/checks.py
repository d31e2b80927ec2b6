"""Checks shared by test modules (issue 35: not defined in one test module and imported by another): the strict C
compile, the agreement bound of two evaluations of one function, the haptic wall's equilibrium, the layout of a
figure and assembled samples of the DELTA."""

from __future__ import annotations

import os
import shutil

import numpy as np

from symkin.derivation import catalog
from symkin.simulation import ArmSystem, MassSpringDamperUser, Plant, Wall, WallRenderer, run_sampled
from tolerances import svd

CC = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")

#: The issue's flags, plus what keeps float32 code honest (-Wconversion, -Wdouble-promotion).
STRICT_FLAGS = ["-std=c99", "-O3", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wconversion",
                "-Wdouble-promotion", "-Wshadow", "-Wstrict-prototypes", "-Wmissing-prototypes"]


#: Agreement bound of a well-conditioned function, relative to the largest entry of each output.
AGREEMENT = 1e-12


def agreement_bound(model, spec, inputs, numpy_model) -> np.ndarray:
    """Per batch entry: AGREEMENT, plus for a function that solves with a square matrix (tcp_force and
    operational_space with J, forward_dynamics with M) the rounding the solve amplifies: svd(n)
    times kappa^2 (the operational-space inertia J^-T M J^-1 solves twice; one solve gives kappa).
    Two evaluation orders of the same exact function then differ by that much near singularities."""
    return parts_agreement_bound(model, spec.parts or (spec.name,), [v.name for v in spec.vector_inputs], inputs,
                                 numpy_model)


def record_agreement_bound(model, record, inputs, numpy_model) -> np.ndarray:
    """:func:`agreement_bound` of the generated function a manifest ``record`` describes."""
    vectors = [i["name"] for i in record["inputs"] if i["kind"] == "vector"]
    return parts_agreement_bound(model, record.get("combines") or (record["name"],), vectors, inputs, numpy_model)


def parts_agreement_bound(model, parts, vector_names, inputs, numpy_model) -> np.ndarray:
    """:func:`agreement_bound` of a function of ``parts`` (a combined function: the worst of its parts) whose
    vector inputs ``vector_names`` take ``inputs``."""
    bound = np.full(len(inputs[0]), AGREEMENT)
    by_name = dict(zip(vector_names, inputs))
    for part in parts:
        solves_with = catalog.definition(part, model.mechanism).solves_with
        if solves_with is None:
            continue
        solved = numpy_model.info.functions[solves_with]
        matrix = getattr(numpy_model, solves_with)(*(by_name[v] for v in solved.vectors))
        matrix = matrix[0] if isinstance(matrix, tuple) else matrix
        bound = np.maximum(bound, AGREEMENT + svd(matrix.shape[-1]) * np.linalg.cond(matrix) ** 2)
    return bound


def assert_wall_equilibrium(plant: Plant, q0: np.ndarray, steps: int, offset: float = 0.01, stiffness: float = 500.0,
                            damping: float = 5.0, hand: dict[str, float] | None = None) -> None:
    """A hand pulled 2 ``offset`` (2 cm) beyond a wall ``offset`` from the TCP along the first handle coordinate
    comes to rest where k_a (r - p_h) = k_g (p_h - p) = k_w d (springs in series, p = x_w + d), and then feels
    exactly the wall's force: the renderer's gravity compensation must cancel the weight (shared with the
    DELTA's and the Agile Eye's tests; a turning handle's coordinates are angles)."""
    p0 = plant.point(q0)
    normal = np.zeros(len(p0))
    normal[0] = 1.0
    target = p0 + 2 * offset * normal
    user = MassSpringDamperUser(lambda t: (target, np.zeros(len(p0))), **(hand or {"arm_damping": 20.0}))
    wall = Wall(normal, float(p0[0]) + offset, stiffness=stiffness, damping=damping)
    system = ArmSystem(plant, user)
    run = run_sampled(system.derivative, WallRenderer(system, wall), system.initial(q0), 1e-3, steps)
    s = system.split(run.x[-1])
    d = wall.penetration(plant.point(s.q))
    k_a, k_g, k_w = user.arm_stiffness, user.grip_stiffness, wall.stiffness
    expected = k_a * offset / (k_a + k_w + k_a * k_w / k_g)
    np.testing.assert_allclose(d, expected, rtol=1e-3)
    desired, felt = WallRenderer(system, wall).desired_and_sensed(run.t[-1], run.x[-1])
    np.testing.assert_allclose(felt, desired, atol=1e-3 * np.abs(desired[0]))
    np.testing.assert_allclose(desired[0], -k_w * expected, rtol=1e-3)


def check_figure_layout(figure) -> None:
    """Render ``figure`` (Agg): every legend's box outside every axes box, every title and axis label inside the
    figure and clear of every other axes box (the colour bars are axes too)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(figure).draw()
    renderer = figure.canvas.get_renderer()
    boxes = [ax.get_window_extent(renderer) for ax in figure.axes]
    frame = figure.bbox
    legends = [ax.get_legend() for ax in figure.axes if ax.get_legend() is not None] + list(figure.legends)
    for legend in legends:
        box = legend.get_window_extent(renderer)
        assert not any(box.overlaps(axes_box) for axes_box in boxes), "a legend covers a panel"
    titles = [(figure._suptitle, None)] if figure._suptitle is not None else []
    titles += [(ax.title, ax) for ax in figure.axes if ax.get_title()]
    for title, owner in titles:
        box = title.get_window_extent(renderer)
        assert frame.x0 - 1 <= box.x0, "a title is cut"
        assert box.x1 <= frame.x1 + 1, "a title is cut"
        assert box.y1 <= frame.y1 + 1, "a title is cut"
        others = [b for ax, b in zip(figure.axes, boxes) if ax is not owner]
        assert not any(box.overlaps(other) for other in others), "a title runs into a panel or the colour bar"
    for owner in figure.axes:  # axis labels stay clear of the other panels and colour bars (issue 60)
        for label in (owner.xaxis.label, owner.yaxis.label):
            if not label.get_text() or not label.get_visible():
                continue
            box = label.get_window_extent(renderer)
            others = [b for ax, b in zip(figure.axes, boxes) if ax is not owner]
            assert not any(box.overlaps(other) for other in others), \
                f"the axis label {label.get_text()!r} runs into a panel or a colour bar"


def delta_assemblies(delta, count: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, s, p) of ``count`` assembled samples of generated/delta (arms uniform in -20..40 deg: the closed-form fk's
    pose and the passive joints that close the legs there, by the run-time solver) and, last, one sample whose arms
    put the platform out of reach (its fk's spheres do not meet: s zero, p a pose below the base)."""
    from symkin.runtime.parallel import solve_closure

    ns = delta.info.functions["closure"].inputs[1].shape[0]
    q = np.vstack([rng.uniform(np.radians(-20.0), np.radians(40.0), (count, 3)), np.radians([[0.0, 0.0, 180.0]])])
    p = np.asarray(delta.fk(q[:-1]).position)
    s = [solve_closure(delta, qk, np.zeros(ns), pk, unknowns=("s",)).solution["s"] for qk, pk in zip(q[:-1], p)]
    return q, np.vstack(s + [np.zeros(ns)]), np.vstack([p, [[0.0, 0.0, -0.15]]])
