"""The datasheet's per-sample arithmetic on JAX's default device (issue 66).

For a model loaded with the JAX backend, :func:`symkin.rating.datasheet.rate` evaluates the measures of
:mod:`symkin.rating.handle_measures` over the usable samples - apparent masses and inertias (eigenvalues of
J M^-1 J^T), force and torque capability (the farthest vertices of the efforts' polytope), resolutions, the
gravity share (the generated ``gravity_vector`` called inside the program), friction, damping and the passive
walls - as one jitted program: the formulas of :mod:`symkin.rating.formulas` in jax.numpy, the same code as the
host's, so that on a GPU the samples' J and M stay on the device and only the measures' values come back.  The
usable samples themselves (sampling, assembly, the conditioning cut) are decided as on the host.

:func:`rated_on_device` takes the measures as a function of the sampled arrays and an array module, traces it
once with jax.numpy (its factorizations one after the other: :class:`symkin.numerics.ordered_linalg.InOrder`) and
returns what it gave with numpy values: :class:`~symkin.rating.handle_measures.Measure`
is a pytree whose one leaf is its values (its name, unit and doc static), the reasons a group is not rated a
static node.
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from symkin.numerics.ordered_linalg import InOrder
from symkin.rating.handle_measures import Measure
from symkin.runtime.info import GeneratedModel

#: The arrays of the usable samples the measures read: the joints, the poses the generated functions take, the
#: handle's Jacobians pushed and turned, M, and the efforts that hold the device (a reason where there are none).
SAMPLED = ("q", "poses", "J_v", "J_w", "M", "G")

Measures = tuple[tuple[Measure, ...], dict[str, str]]


def rates_on_device(model: GeneratedModel) -> bool:
    """Whether the model is loaded with the JAX backend: its datasheet's arithmetic runs on JAX's device."""
    return getattr(model, "backend", None) == "jax"


@dataclass(frozen=True)
class _Reasons:
    """{group: why it is not rated} as a static node of the program's output (no arrays)."""

    items: tuple[tuple[str, str], ...]


@functools.cache
def _register() -> None:
    """Measure and _Reasons as pytrees, once per process."""
    import jax

    jax.tree_util.register_dataclass(Measure, data_fields=["values"],
                                     meta_fields=["name", "unit", "worst_is_min", "doc", "axis"])
    jax.tree_util.register_static(_Reasons)


#: Samples per call of the measures' program, which bounds its memory: the largest intermediates are the redundant
#: arm's peak force, C(n, m) 2^(m-1) (m + n) numbers per sample (720 for the UR10e: 190 MB per chunk).
CHUNK = 2**15


#: The programs kept for later ratings (:func:`rated_on_device`'s ``key``), the most recently used last.
PROGRAMS: OrderedDict[Hashable, Any] = OrderedDict()
#: ... at most this many (each holds its model and XLA's executables).
KEPT_PROGRAMS = 8


def rated_on_device(measures_of: Callable[[Mapping[str, Any], Any], Measures], sampled: Mapping[str, Any], *,
                    key: Hashable | None = None) -> Measures:
    """``measures_of(sampled, jax.numpy)`` compiled and run on JAX's default device, its values back as numpy
    arrays: ``sampled`` maps the names of :data:`SAMPLED` to arrays (traced) or to None or a reason (static).  The
    samples go through in chunks of :data:`CHUNK` or, when fewer, of the next power of two (the last one padded with
    its first sample, so that one compiled program serves every chunk, and later ratings of about as many samples).

    ``key``: what ``measures_of`` computes, hashable, equal for equal programs (the model, its rating options): a
    later call with an equal key and the same static entries of ``sampled`` runs the program compiled then (XLA
    compiles it again only for other array shapes) instead of compiling ``measures_of`` anew (about a second for a
    DELTA on a CPU).  None: compiled for this call only."""
    _register()
    traced = {name: value for name, value in sampled.items() if value is not None and not isinstance(value, str)}
    fixed = tuple(sorted((name, value) for name, value in sampled.items() if name not in traced))
    if key is None:
        compiled = _program(measures_of, fixed)
    else:
        compiled = PROGRAMS.pop((key, fixed), None) or _program(measures_of, fixed)
        PROGRAMS[key, fixed] = compiled
        while len(PROGRAMS) > KEPT_PROGRAMS:
            PROGRAMS.popitem(last=False)
    count = len(traced["q"])
    size = min(CHUNK, 1 << (count - 1).bit_length())  # a power of two: later ratings' counts take the same shapes
    parts = []
    for start in range(0, count, size):  # every chunk dispatched before any comes back: the device never waits
        index = start + np.where(np.arange(size) < count - start, np.arange(size), 0)
        measures, reasons = compiled({name: value[index] for name, value in traced.items()})
        parts.append([m.values for m in measures])
    values = [np.concatenate([np.asarray(v) for v in chunks])[:count] for chunks in zip(*parts)]
    return tuple(replace(m, values=v) for m, v in zip(measures, values)), dict(reasons.items)


def _program(measures_of: Callable[[Mapping[str, Any], Any], Measures], fixed: tuple[tuple[str, Any], ...]) -> Any:
    """The jitted program of ``measures_of`` over the traced arrays, the ``fixed`` entries (None or a reason) static."""
    import jax
    import jax.numpy as jnp

    def program(arrays: dict[str, Any]) -> tuple[tuple[Measure, ...], _Reasons]:
        measures, skipped = measures_of({**arrays, **dict(fixed)}, InOrder(jnp))
        return measures, _Reasons(tuple(skipped.items()))

    return jax.jit(program)
