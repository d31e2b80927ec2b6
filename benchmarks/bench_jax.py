"""The JAX backend on whatever device JAX sees (issue 66): the UR10e's fk + J + M + V + G and the GCI integrand per
configuration, beside the numpy and C backends in the same run.

Run with ``make bench`` or ``python benchmarks/bench_jax.py [--batch N] [--repeat N]``.

The UR10e with every parameter folded, its combined function of fk, the geometric Jacobian, M, V and G (one
shared CSE); nanoseconds per configuration of one call over ``--batch`` configurations (best of ``--repeat``
calls, after one that compiles):

* ``numpy``, ``C``: the generated batched functions, every output written to host memory;
* ``JAX, outputs on the device``: the jitted function, every output left on JAX's default device
  (``block_until_ready``);
* ``JAX, reduced on the device``: the jitted function and a sum of every output to one number per configuration in
  one jitted function (only that number comes back): on a CPU the outputs' entries are still computed in one loop
  and written to memory (the module's ``_in_one_loop``), on other devices XLA may fuse them into the sum;
* ``GCI integrand``: what ``symkin gci`` integrates over the joint limits, [1/kappa(J), 1] of the task Jacobian per
  configuration (its singular values; the position rows divided by L = 1 m) reduced to their mean and covariance
  (``Integrand.mean_and_covariance``): the host integrand (:func:`symkin.analysis.global_indices.joint_space_integrand`:
  the C backend's J, numpy's batched SVD and covariance) against the device integrand
  (:func:`symkin.analysis.device_integrand.device_joint_space_integrand`: one jitted function, the points sent
  from the host, only the moments back);
* ``DELTA GCI integrand``: the same for models/delta.yaml (folded), a parallel mechanism with closed forms, with
  the Cartesian measure |det J| dq: the host decides its working mode by the C backend's fk and ik (ik(fk(q)) = q),
  the device in the same jitted function as J and its moments;
* ``Stewart Cartesian GCI integrand``: what ``symkin gci models/stewart.yaml`` integrates, [1_W 1/kappa, 1_W] over a
  box of platform centres at the home orientation: the closed-form ik, the assembly mode (the sign of det J^-1),
  the actuators' limits and 1/kappa of the twist Jacobian diag(I, E) (J^-1)^-1 homogenized by its characteristic
  length, per point - the host integrand (:func:`symkin.analysis.global_indices.cartesian_integrand`, the C
  backend's ik and J^-1, numpy's det, inverse and SVD) against the device's
  (:func:`symkin.analysis.device_cartesian.device_cartesian_integrand`);
* ``Agile Eye orientation GCI integrand``: what ``symkin gci models/agile_eye.yaml`` integrates over the roll-pitch-yaw
  chart of SO(3), [|cos pitch| 1_W 1/kappa, |cos pitch| 1_W]: the closed-form ik, the joint limits and 1/kappa of
  J^-1 E^-1 per orientation - the host's (:func:`symkin.analysis.orientations.orientation_integrand` on the C backend)
  against the device's (:func:`symkin.analysis.device_cartesian.device_orientation_integrand`).

``DELTA datasheet``: the seconds of ``symkin rate``'s arithmetic (:func:`symkin.rating.datasheet.rate`, every group
of measures rated) over ``--samples`` workspace samples with numpy and on JAX's device, its first and second rating.

With ``--compile``, also the seconds of the first call of every function of the UR10e's scene with the JAX backend
(XLA's compile, at one configuration): what keeps the JAX backend out of the example scenes so far.

Issue 66's targets: on a GPU of the H200 class <= 1 ns per configuration for fk + J + M + V + G reduced on the
device, and a 10^6-design x 10^4-configuration GCI sweep of the UR10e projected <= 60 s (the GCI row's time times
10^10); on a CPU no slower than the numpy backend.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402

import symkin  # noqa: E402
from symkin.analysis.device_cartesian import device_cartesian_integrand  # noqa: E402
from symkin.analysis.device_integrand import device_joint_space_integrand  # noqa: E402
from symkin.analysis.global_indices import cartesian_integrand, joint_space_integrand  # noqa: E402
from symkin.analysis.inverse import inverse_kinematics_for  # noqa: E402
from symkin.analysis.orientations import FULL_CHART, orientation_integrand  # noqa: E402
from symkin.mechanism import reach  # noqa: E402
from symkin.text_table import format_table  # noqa: E402

OUTPUTS = ["fk", "jacobian_geometric", "mass_matrix", "coriolis_vector", "gravity_vector"]


def best_seconds(call, repeat: int) -> float:
    """The fastest of ``repeat`` calls of ``call`` (each waits for its result), after one call that compiles."""
    call()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batch", type=int, default=100_000, help="configurations per call (default: %(default)s)")
    parser.add_argument("--repeat", type=int, default=5, help="timed calls per case (default: %(default)s)")
    parser.add_argument("--samples", type=int, default=100_000,
                        help="workspace samples of the datasheet rows (default: %(default)s)")
    parser.add_argument("--compile", action="store_true",
                        help="also time the first call (the compile) of every function of the UR10e's scene")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        directory = symkin.derive(ROOT / "models" / "ur10e.yaml", tmp, outputs=OUTPUTS, backends=["numpy", "c", "jax"],
                                  fixed=["all"], combine="all")
        numpy_model, c_model, jax_model = (symkin.load(directory, backend) for backend in ("numpy", "c", "jax"))
        rng = np.random.default_rng(0)
        q, qd = rng.uniform(-np.pi, np.pi, (args.batch, 6)), rng.uniform(-1.0, 1.0, (args.batch, 6))
        q_device, qd_device = jax.device_put(q), jax.device_put(qd)
        reduced = jax.jit(lambda x, v: sum(jnp.sum(o.reshape(o.shape[0], -1), axis=-1)
                                           for o in jax_model.combined(x, v)))

        gci_directory = symkin.derive(ROOT / "models" / "ur10e.yaml", Path(tmp) / "gci", outputs=["jacobian"],
                                      backends=["c", "jax"], fixed=["all"])
        host = joint_space_integrand(symkin.load(gci_directory, "c"), measure="joint", length=1.0)
        device = device_joint_space_integrand(symkin.load(gci_directory, "jax"), measure="joint", length=1.0)
        device.mean_and_covariance(q)                   # compiles
        # a parallel mechanism with closed forms: its working mode (fk assembles, ik(fk(q)) = q) decided per point too
        delta_directory = symkin.derive(ROOT / "models" / "delta.yaml", Path(tmp) / "delta",
                                        outputs=["fk", "ik", "jacobian"], backends=["c", "jax"], fixed=["all"])
        delta_host = joint_space_integrand(symkin.load(delta_directory, "c"))
        delta_device = device_joint_space_integrand(symkin.load(delta_directory, "jax"))
        q_delta = rng.uniform(delta_host.lower, delta_host.upper, (args.batch, 3))
        delta_device.mean_and_covariance(q_delta)       # compiles
        # a pose platform at a constant orientation over the Cartesian domain: ik, assembly mode, (J^-1)^-1, 1/kappa
        stewart_directory = symkin.derive(ROOT / "models" / "stewart.yaml", Path(tmp) / "stewart",
                                          outputs=["ik", "inverse_jacobian"], backends=["c", "jax"], fixed=["all"])
        held = {backend: reach.held_at(symkin.load(stewart_directory, backend), None) for backend in ("c", "jax")}
        box = reach.bounding_box(held["c"])
        stewart_host, stewart_device = (
            integrand(held[backend], inverse_kinematics_for(held[backend]), box, length="auto")
            for integrand, backend in ((cartesian_integrand, "c"), (device_cartesian_integrand, "jax")))
        centres = rng.uniform(box[0], box[1], (args.batch, 3))
        stewart_device.mean_and_covariance(centres)     # compiles
        # a spherical platform's orientations: ik, limits, |cos pitch| and 1/kappa of J^-1 E^-1
        eye_directory = symkin.derive(ROOT / "models" / "agile_eye.yaml", Path(tmp) / "agile_eye",
                                      outputs=["ik", "inverse_jacobian"], backends=["c", "jax"], fixed=["all"])
        eye_host, eye_device = (orientation_integrand(symkin.load(eye_directory, backend)) for backend in ("c", "jax"))
        angles = rng.uniform(*FULL_CHART, (args.batch, 3))
        eye_device.mean_and_covariance(angles)          # compiles

        cases = [
            ("fk + J + M + V + G", "numpy", lambda: numpy_model.combined(q, qd)),
            ("fk + J + M + V + G", "C", lambda: c_model.combined(q, qd)),
            ("fk + J + M + V + G", "JAX, outputs on the device",
             lambda: jax.block_until_ready(jax_model.combined(q_device, qd_device))),
            ("fk + J + M + V + G", "JAX, reduced on the device",
             lambda: jax.block_until_ready(reduced(q_device, qd_device))),
            ("GCI integrand (1/kappa of J and its moments)", "C J + numpy SVD, on the host",
             lambda: host.mean_and_covariance(q)),
            ("GCI integrand (1/kappa of J and its moments)", "JAX, reduced on the device",
             lambda: device.mean_and_covariance(q)),
            ("DELTA GCI integrand (working mode, |det J|, 1/kappa)", "C fk, ik, J + numpy, on the host",
             lambda: delta_host.mean_and_covariance(q_delta)),
            ("DELTA GCI integrand (working mode, |det J|, 1/kappa)", "JAX, reduced on the device",
             lambda: delta_device.mean_and_covariance(q_delta)),
            ("Stewart Cartesian GCI integrand (ik, assembly mode, (J^-1)^-1, 1/kappa)",
             "C ik, J^-1 + numpy, on the host", lambda: stewart_host.mean_and_covariance(centres)),
            ("Stewart Cartesian GCI integrand (ik, assembly mode, (J^-1)^-1, 1/kappa)", "JAX, reduced on the device",
             lambda: stewart_device.mean_and_covariance(centres)),
            ("Agile Eye orientation GCI integrand (ik, limits, |cos pitch|, 1/kappa of J^-1 E^-1)",
             "C ik, J^-1 + numpy, on the host", lambda: eye_host.mean_and_covariance(angles)),
            ("Agile Eye orientation GCI integrand (ik, limits, |cos pitch|, 1/kappa of J^-1 E^-1)",
             "JAX, reduced on the device", lambda: eye_device.mean_and_covariance(angles)),
        ]
        rows = [[case, backend, f"{1e9 * best_seconds(call, args.repeat) / args.batch:.2f}"]
                for case, backend, call in cases]
        sweep = float(rows[5][2]) * 1e-9 * 1e10   # the UR10e's GCI integrand on the device
    print(f"JAX {jax.__version__} on {jax.devices()[0].device_kind} ({jax.default_backend()}), "
          f"batch {args.batch}, best of {args.repeat}")
    print(format_table(["case", "backend", "ns per configuration"], rows))
    print(f"a 10^6-design x 10^4-configuration GCI sweep at the JAX row's rate: {sweep:.0f} s "
          "(issue 66's target on an H200-class GPU: <= 60 s; fk + J + M + V + G reduced <= 1 ns)")
    print(format_table(["DELTA datasheet (symkin rate)", "backend", "seconds", "us per sample"],
                       _datasheet_rows(args.samples)))
    if args.compile:
        print(format_table(["UR10e scene function", "first call, JAX (s)"], _first_calls()))
    return 0


def _datasheet_rows(samples: int) -> list[list[str]]:
    """Seconds of a DELTA's datasheet (every group rated) over ``samples`` workspace samples, numpy's against JAX's
    device (:mod:`symkin.rating.on_device`): its first rating (XLA compiles the generated functions and the measures'
    program) and a second one (the generated functions and the measures' program compiled: the program is kept per
    model and rating options, :data:`symkin.rating.on_device.PROGRAMS`)."""
    from symkin.rating import datasheet
    from symkin.rating.handle_measures import Actuation

    with tempfile.TemporaryDirectory() as tmp:
        directory = symkin.derive(ROOT / "models" / "delta.yaml", tmp, backends=["numpy", "jax"],
                                  outputs=["fk", "ik", "jacobian", "mass_matrix", "gravity_vector"])
        actuation = Actuation(np.full(3, 0.3), np.full(3, 0.15), np.full(3, 1e-4), np.full(3, 0.01), np.full(3, 0.02))
        models = {backend: symkin.load(directory, backend) for backend in ("numpy", "jax")}
        rows = []
        for backend, label in (("numpy", "numpy"), ("jax", "JAX, first rating"), ("jax", "JAX, second rating")):
            start = time.perf_counter()
            sheet = datasheet.rate(models[backend], actuation, samples=samples)
            seconds = time.perf_counter() - start
            rows.append([f"{len(sheet.q)} samples", label, f"{seconds:.3f}", f"{1e6 * seconds / len(sheet.q):.2f}"])
    return rows


def _first_calls() -> list[list[str]]:
    """Seconds of the first call (trace, XLA compile, run) of each function of the UR10e's scene, one configuration."""
    with tempfile.TemporaryDirectory() as tmp:
        model = symkin.load(symkin.derive(ROOT / "models" / "ur10e.yaml", tmp, backends=["jax"]), "jax")
        rows = []
        for name, record in model.info.functions.items():
            arguments = [np.zeros(len(vector.elements)) for vector in record.vectors.values()]
            start = time.perf_counter()
            jax.block_until_ready(getattr(model, name)(*arguments))
            rows.append([name, f"{time.perf_counter() - start:.2f}"])
    return rows


if __name__ == "__main__":
    sys.exit(main())
