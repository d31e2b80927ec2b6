"""The dynamics regressor of parallel models (issue 33): tau = Y(q, p, qd, qdd) pi for the DELTA and the pantograph.

Independent oracle: the models' own inverse dynamics (symkin.parallel.dynamics: the bodies entered by their
centres of mass, the rods by their lumped ends), derived with the masses kept free and evaluated at random
masses, inertias, gear ratios and friction levels - so a wrong column or a wrong mapping of the model's bodies
to pi shows wherever the sampled parameters move it.  And the physics of a translating platform: its first
moment and inertia do no work, so their columns vanish.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import MODELS_DIR
from symkin import load, pipeline
from symkin.dynamics.parameter_names import DRIVE, INERTIAL
from symkin.model import model_from_text
from tolerances import DYNAMICS

FRICTION = """
friction:
  {a}: {{viscous: 0.002, coulomb: 0.01, smoothing_velocity: 0.05}}
  {b}: {{viscous: 0.001, coulomb: {{positive: 0.02, negative: 0.015}}}}
"""

#: name: (geometry folded to numbers, the coordinates' names, task-space box half-widths about home)
CASES = {
    "delta": ("r_base,r_tcp,a,b", ("theta1", "theta2"), 0.03),
    "pantograph": ("d,l,L", ("theta1", "theta2"), 0.01),
}


def _derive(name, tmp_path_factory):
    geometry, joints, _ = CASES[name]
    text = (MODELS_DIR / f"{name}.yaml").read_text() + FRICTION.format(a=joints[0], b=joints[1])
    model = model_from_text(text, file=f"{name}.yaml")
    request = pipeline.resolve_request(model, only="regressor,energy_regressor,inverse_dynamics,kinetic_energy,potential_energy,ik", fixed=geometry)
    return model, load(pipeline.write(pipeline.generate(model, request), tmp_path_factory.mktemp(name)))


@pytest.fixture(scope="module", params=sorted(CASES))
def derived(request, tmp_path_factory):
    return request.param, *_derive(request.param, tmp_path_factory)


def _states(generated, half_width, count, seed):
    rng = np.random.default_rng(seed)
    home = np.array(generated.info.home)
    p = home + rng.uniform(-half_width, half_width, (count, len(home)))
    q = generated.ik(p).joints
    assert np.all(np.isfinite(q))
    return rng, q, p, rng.normal(size=q.shape), rng.normal(size=q.shape)


def test_regressor_times_parameters_is_the_inverse_dynamics(derived):
    """At random masses, inertias, gear ratios and friction levels of the model's bodies."""
    name, model, generated = derived
    rng, q, p, qd, qdd = _states(generated, CASES[name][2], 64, 51)
    free = [i for i in generated.info.functions["inverse_dynamics"].inputs if i.kind == "parameter"]
    assert free  # the masses stay free
    for _ in range(4):
        values = {i.name: i.default * rng.uniform(0.2, 5.0) for i in free}
        regressor = generated.regressor(q, p, qd, qdd, **values)
        tau = generated.inverse_dynamics(q, p, qd, qdd, **values)
        terms = np.abs(regressor.Y * regressor.pi[..., None, :])  # |Y_ik pi_k|: the scale the rounding acts on
        np.testing.assert_array_less(np.abs(np.einsum("sik,sk->si", regressor.Y, regressor.pi) - tau),
                                     DYNAMICS * terms.sum(axis=-1) + np.finfo(float).tiny)


def test_energy_regressor_times_parameters_is_the_energy(derived):
    """k + u = Y_e pi at random masses, inertias and gear ratios (the energies bodies by their centres of mass)."""
    name, model, generated = derived
    rng, q, p, qd, _ = _states(generated, CASES[name][2], 64, 54)
    functions = generated.info.functions
    free = {i.name: i.default for f in ("energy_regressor", "kinetic_energy", "potential_energy")
            for i in functions[f].inputs if i.kind == "parameter"}

    def own(function, values):  # the parameters a generated function takes
        return {k: v for k, v in values.items() if k in {i.name for i in functions[function].inputs}}

    for _ in range(4):
        values = {name: default * rng.uniform(0.2, 5.0) for name, default in free.items()}
        regressor = generated.energy_regressor(q, p, qd, **own("energy_regressor", values))
        energy = (generated.kinetic_energy(q, p, qd, **own("kinetic_energy", values))
                  + generated.potential_energy(q, p, **own("potential_energy", values)))
        terms = np.abs(regressor.Y_e * regressor.pi)
        np.testing.assert_array_less(np.abs(np.einsum("sk,sk->s", regressor.Y_e, regressor.pi) - energy),
                                     DYNAMICS * terms.sum(axis=-1) + np.finfo(float).tiny)
        names = generated.info.functions["energy_regressor"].results[0].elements
        assert names == generated.info.functions["regressor"].results[0].elements


def test_parameter_names_and_values_follow_the_bodies(derived):
    name, model, generated = derived
    names = generated.info.functions["regressor"].results[1].elements
    assert names[:2] == ("platform.m", "platform.mx")
    assert "rod.mB" in names
    assert "rod.dI" in names  # both have rods of one length
    last = model.coordinates[-1].name
    assert names[-4:] == tuple(f"{last}.{p}" for p in ("Ia", "fv", "fc", "fo"))
    _, q, p, qd, qdd = _states(generated, CASES[name][2], 1, 52)
    pi = dict(zip(names, generated.regressor(q, p, qd, qdd).pi[0]))
    bodies = {"delta": ("m_platform", "m_rod", 0.5), "pantograph": ("m_handle", "m_distal", 0.5)}[name]
    defaults = {i.name: i.default for i in generated.info.functions["regressor"].inputs if i.kind == "parameter"}
    assert pi["platform.m"] == defaults[bodies[0]]
    assert pi["rod.mB"] == pytest.approx(bodies[2] * defaults[bodies[1]], rel=4 * np.finfo(float).eps)
    assert pi["theta2.fc"] == pytest.approx((0.02 + 0.015) / 2)
    assert pi["theta2.fo"] == pytest.approx((0.02 - 0.015) / 2)


def test_a_translating_platform_has_no_first_moment_or_inertia_columns(derived):
    """The DELTA's platform and the pantograph's handle keep their orientation: their first moment and inertia
    neither move nor weigh differently anywhere (k = 1/2 m |v|^2, u = -m g . p + const), so only the mass is in Y."""
    name, model, generated = derived
    _, q, p, qd, qdd = _states(generated, CASES[name][2], 32, 53)
    Y = generated.regressor(q, p, qd, qdd).Y
    names = generated.info.functions["regressor"].results[0].elements
    platform = [k for k, n in enumerate(names) if n.startswith("platform.") and n != "platform.m"]
    assert np.all(Y[:, :, platform] == 0)
    assert np.all(np.abs(Y[:, :, names.index("platform.m")]).max(axis=-1) > 0)


def _assert_both_regressors(generated, states, rates, rng):
    """Y pi = tau and Y_e pi = k + u at the device's states ``states`` (q, p and a wrist's qw) and rates ``rates``
    ((qd, qdd), a wrist's after each), at three random draws of every free parameter (0.2 to 5 times its default)."""
    functions = generated.info.functions
    free = {i.name: i.default for f in ("regressor", "energy_regressor", "kinetic_energy", "potential_energy")
            for i in functions[f].inputs if i.kind == "parameter"}

    def own(function, values):  # the parameters a generated function takes
        return {k: v for k, v in values.items() if k in {i.name for i in functions[function].inputs}}

    velocities = rates[:len(rates) // 2]
    for _ in range(3):
        values = {name: default * rng.uniform(0.2, 5.0) for name, default in free.items()}
        regressor = generated.regressor(*states, *rates, **own("regressor", values))
        tau = generated.inverse_dynamics(*states, *rates, **own("inverse_dynamics", values))
        terms = np.abs(regressor.Y * regressor.pi[..., None, :])
        np.testing.assert_array_less(np.abs(np.einsum("sik,sk->si", regressor.Y, regressor.pi) - tau),
                                     DYNAMICS * terms.sum(axis=-1) + np.finfo(float).tiny)
        energy = generated.energy_regressor(*states, *velocities, **own("energy_regressor", values))
        k_u = (generated.kinetic_energy(*states, *velocities, **own("kinetic_energy", values))
               + generated.potential_energy(*states, **own("potential_energy", values)))
        np.testing.assert_array_less(np.abs(np.einsum("sk,sk->s", energy.Y_e, energy.pi) - k_u),
                                     DYNAMICS * np.abs(energy.Y_e * energy.pi).sum(axis=-1) + np.finfo(float).tiny)
    return free


def _generated(text, file, fixed, tmp_path):
    model = model_from_text(text, file=file)
    request = pipeline.resolve_request(model, only="regressor,energy_regressor,inverse_dynamics,kinetic_energy,"
                                       "potential_energy,ik", fixed=fixed)
    return model, load(pipeline.write(pipeline.generate(model, request), tmp_path))


def test_a_hybrid_devices_wrist_enters_both_regressors(tmp_path):
    """The DELTA carrying a 3R wrist, friction on the legs and on a wrist joint: Y pi = tau and Y_e pi = k + u at
    random masses of the arms, rods, platform and wrist bodies, random wrist states and a rotor on the actuators;
    the rows are the legs' then the wrist's, the wrist's columns its links' and joints' after the legs' drives."""
    tcp = "  tcp: {xyz: [0, h, 0]}\n"
    text = (MODELS_DIR / "delta_wrist.yaml").read_text().replace(
        tcp, tcp + "  friction:\n    psi2: {viscous: 0.001, coulomb: 0.004}\n") + FRICTION.format(a="theta1", b="theta2")
    assert "psi2: {viscous" in text
    model, generated = _generated(text, "delta_wrist.yaml", "r_base,r_tcp,a,b,w,h", tmp_path)
    rng, q, p, qd, qdd = _states(generated, 0.03, 64, 55)
    qw, qwd, qwdd = rng.uniform(-1.2, 1.2, q.shape), rng.normal(size=q.shape), rng.normal(size=q.shape)
    names = generated.info.functions["regressor"].results[1].elements
    wrist = [j.name for j in model.parallel.wrist.coordinates]
    assert names[names.index("theta3.fo") + 1:] == tuple(
        [f"{link}.{p}" for link in ("fork1", "fork2", "handle") for p in INERTIAL]
        + [f"{joint}.{p}" for joint in wrist for p in DRIVE])
    assert generated.regressor(q, p, qw, qd, qwd, qdd, qwdd).Y.shape == (64, 6, len(names))
    free = _assert_both_regressors(generated, (q, p, qw), (qd, qwd, qdd, qwdd), rng)
    assert {"m_fork1", "m_handle", "m_platform", "m_arm"} <= set(free)


def test_a_spherical_platforms_distal_links_enter_both_regressors(tmp_path):
    """The Agile Eye (distal arcs, a camera on the turning platform): Y pi = tau and Y_e pi = k + u at random masses
    and radii of the arcs and the camera; the distal link's ten columns follow the actuated link's, its values are
    its body about its frame's origin, and its columns carry effort (the arcs turn with every motion) but for the
    mass's: the arcs' frames sit at the centre of rotation, where a point mass neither moves nor rises."""
    text = (MODELS_DIR / "agile_eye.yaml").read_text() + FRICTION.format(a="theta1", b="theta2")
    model, generated = _generated(text, "agile_eye.yaml", None, tmp_path)
    rng, q, p, qd, qdd = _states(generated, 0.2, 64, 56)
    names = generated.info.functions["regressor"].results[1].elements
    distal = [f"distal_link.{p}" for p in INERTIAL]
    assert names[names.index("actuated_link.Izz") + 1:names.index("actuated_link.Izz") + 11] == tuple(distal)
    regressor = generated.regressor(q, p, qd, qdd)
    pi = dict(zip(names, regressor.pi[0]))
    defaults = {i.name: i.default for i in generated.info.functions["regressor"].inputs if i.kind == "parameter"}
    r_d, m_d = defaults["r_d"], defaults["m_d"]
    assert pi["distal_link.m"] == m_d
    assert pi["distal_link.my"] == pytest.approx(m_d * 2 * r_d / np.pi, rel=4 * np.finfo(float).eps)
    largest = np.abs(regressor.Y[:, :, [names.index(n) for n in distal]]).max(axis=(0, 1))
    assert largest[0] == 0
    assert np.all(largest[1:] > 0)
    free = _assert_both_regressors(generated, (q, p), (qd, qdd), rng)
    assert {"m_d", "r_d", "m_camera", "I_camera"} <= set(free)


def test_both_regressors_share_one_build_of_the_unit_mass_distributions(monkeypatch):
    """The unit mass distributions of the columns are a node of the derivation graph: deriving the regressor and
    the energy regressor builds them once."""
    from symkin.derivation import Derivation
    from symkin.parallel import regressor

    calls = []
    build = regressor.unit_inertias
    monkeypatch.setattr(regressor, "unit_inertias", lambda *args: calls.append(args) or build(*args))
    text = (MODELS_DIR / "pantograph.yaml").read_text() + FRICTION.format(a="theta1", b="theta2")
    derivation = Derivation(model_from_text(text, file="pantograph.yaml"))
    for quantity in ("regressor", "energy_regressor"):
        derivation[quantity]  # noqa: B018 - deriving is the point: the count of builds below is the test
    assert len(calls) == 1
