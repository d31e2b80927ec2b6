"""GCI (seed eq. 8.28) and workspace measure: integrators, error estimates, measures, formulations.

Oracle: for the planar 2R, J^T J depends on theta2 only, so the GCI reduces to 1-D
integrals over theta2 of expressions taken from the symbolic Jacobian of the derivation,
evaluated by mpmath quadrature at 30 digits:

    Cartesian measure: GCI = int sigma_min^2 dtheta2 / int l1 l2 |sin theta2| dtheta2
                       (1/kappa |det J| = (sigma_min / sigma_max) sigma_min sigma_max)
    joint measure:     GCI = int sigma_min / sigma_max dtheta2 / (b - a)
"""

from __future__ import annotations

import itertools

import mpmath
import numpy as np
import pytest
import sympy
from conftest import GENERATED_DIR
from scipy.integrate import cubature
from tolerances import EPS

import symkin
from symkin.analysis import global_indices as G
from symkin.integration.adaptive import adaptive, genz_malik_rule
from symkin.integration.integrand import Integrand
from symkin.integration.integrators import INTEGRATORS, integrate
from symkin.analysis.inverse import closed_form_inverse
from symkin.mechanism.reach import bounding_box
from symkin.model import coordinates
from symkin.manifest_schema import Coordinate
from symkin.runtime.info import ModelInfo

ARM = symkin.load(GENERATED_DIR / "planar_2r")
QUARTER = (0.0, np.pi / 2)


@pytest.fixture(scope="module")
def exact(models, derivations):
    """exact(l1, l2, theta2 limits, measure, kinks) -> (GCI, measure per unit theta1 range)."""
    model = models["planar_2r"]
    th1, th2 = coordinates.symbols(model, "q")
    l1, l2 = model.parameter("l1").symbol, model.parameter("l2").symbol
    J = sympy.Matrix(derivations["planar_2r"]["jacobian"].outputs[0].expr)
    gram = sympy.simplify(J.T * J)
    assert not gram.has(th1)
    trace = sympy.lambdify((th2, l1, l2), gram.trace(), "mpmath")
    det = sympy.lambdify((th2, l1, l2), sympy.simplify(gram.det()), "mpmath")
    cache = {}

    def evaluate(a1, a2, limits2, measure, kinks=()):
        key = (a1, a2, limits2, measure, kinks)
        if key not in cache:
            with mpmath.workdps(30):
                L1, L2 = mpmath.mpf(a1), mpmath.mpf(a2)

                def sigmas(t):
                    tr, d = trace(t, L1, L2), det(t, L1, L2)
                    big = (tr + mpmath.sqrt(tr * tr - 4 * d)) / 2
                    return mpmath.sqrt(big), mpmath.sqrt(d / big)

                # Break the quadrature where the integrands have kinks: |sin| at 0, 1/kappa at isotropy.
                inner = sorted(k for k in (0.0,) + tuple(kinks) if limits2[0] < k < limits2[1])
                points = [mpmath.mpf(x) for x in (limits2[0], *inner, limits2[1])]
                if measure == "cartesian":
                    num = mpmath.quad(lambda t: sigmas(t)[1] ** 2, points)
                    den = mpmath.quad(lambda t: L1 * L2 * abs(mpmath.sin(t)), points)
                else:
                    num = mpmath.quad(lambda t: sigmas(t)[1] / sigmas(t)[0], points)
                    den = points[-1] - points[0]
                cache[key] = (float(num / den), float(den))
        return cache[key]

    return evaluate


def _limits(theta2):
    return np.array([QUARTER, theta2])


# --- the rules ---------------------------------------------------------------------------------


@pytest.mark.parametrize("d", [2, 3, 4, 5])
def test_genz_malik_rule_is_exact_for_polynomials(d):
    """Degree 7 for the full rule, degree 5 for the embedded one (mean over [-1, 1]^d)."""
    rule = genz_malik_rule(d)
    assert len(rule.nodes) == 2**d + 2 * d * d + 2 * d + 1
    for exponents in itertools.product(range(8), repeat=d):
        degree = sum(exponents)
        if degree > 7:
            continue
        f = np.prod(rule.nodes ** np.array(exponents), axis=1)
        mean = np.prod([1 / (e + 1) if e % 2 == 0 else 0.0 for e in exponents])
        for weights, exact_to in ((rule.degree7, 7), (rule.degree5, 5)):
            if degree <= exact_to:
                # a dot product of N node values (|f| <= 1, each <= 7 roundings): (N + 7) u sum |w|
                bound = (len(f) + 7) * EPS * np.abs(weights).sum()
                assert weights @ f == pytest.approx(mean, abs=bound)
    # Degree 8 is not integrated exactly: the error estimate sees it.
    f = rule.nodes[:, 0] ** 8
    assert abs(rule.degree7 @ f - 1 / 9) > 1e-6


def test_adaptive_agrees_with_scipy_cubature_and_brackets_the_exact_value():
    """A smooth 3-D integrand with a closed form, against scipy's per-region Genz-Malik cubature."""
    lower, upper = np.array([0.0, -1.0, 0.5]), np.array([1.0, 0.5, 2.0])

    def f(x):
        return np.stack([np.exp(x[:, 0] + 2 * x[:, 1] - x[:, 2]), np.cos(x[:, 0] * x[:, 1])], axis=-1)

    exact0 = (np.e - 1) * (np.exp(1.0) - np.exp(-2.0)) / 2 * (np.exp(-0.5) - np.exp(-2.0))
    result = adaptive(Integrand(lower, upper, f, ("a", "b"), ("x", "y", "z")), 200_000, rtol=1e-10)
    reference = cubature(f, lower, upper, rule="genz-malik", rtol=1e-8)
    assert abs(result.values[0] - exact0) <= result.bounds[0]
    assert result.bounds[0] < 1e-9 * exact0
    assert np.all(np.abs(result.values - reference.estimate) <= result.bounds + reference.error)


# --- convergence: every integrator reaches the same value --------------------------------------


TOLERANCES = {  # achieved |GCI - exact| at 2^18 evaluations, far above what each integrator reaches
    "joint": {"grid": 1e-5, "mc": 5e-3, "qmc": 1e-8, "adaptive": 1e-12},
    "cartesian": {"grid": 2e-4, "mc": 5e-3, "qmc": 5e-4, "adaptive": 1e-4},
}


@pytest.mark.parametrize("domain", ["joint", "cartesian"])
@pytest.mark.parametrize("method", list(INTEGRATORS))
def test_every_integrator_converges_to_the_exact_gci(exact, method, domain):
    truth, _ = exact(0.1, 0.1, QUARTER, "cartesian")
    ik = closed_form_inverse(ARM) if domain == "cartesian" else None
    errors, estimates = [], []
    for samples in (2**10, 2**14, 2**18):
        result = G.gci(ARM, method=method, samples=samples, seed=11, domain=domain, inverse=ik)
        errors.append(abs(result.value.value - truth))
        estimates.append(result.value.error)
    assert errors[-1] <= TOLERANCES[domain][method]
    assert estimates[-1] < estimates[0]  # the error estimate shrinks with the budget


# --- error estimates bracket the true error -----------------------------------------------------


def _coverage(method, domain, seeds, samples, truth_gci, truth_area, inverse=None):
    covered_gci, covered_area, half = 0, 0, 0
    box = bounding_box(ARM) if domain == "cartesian" else None
    for seed in range(seeds):
        result = G.gci(ARM, method=method, samples=samples, seed=seed, domain=domain, inverse=inverse, box=box)
        covered_gci += abs(result.value.value - truth_gci) <= result.value.error
        covered_area += abs(result.measure.value - truth_area) <= result.measure.error
        half += abs(result.value.value - truth_gci) <= result.value.error / 2
    return covered_gci / seeds, covered_area / seeds, half / seeds


@pytest.mark.parametrize("method, samples", [("mc", 2**12), ("qmc", 2**10)])
def test_statistical_error_estimates_have_their_nominal_coverage(exact, method, samples):
    """Over 200 seeds the 95 % intervals cover the exact value about 95 % of the time.

    Binomial(200, 0.95): a coverage outside [0.89, 0.995] has probability < 1e-3.  Half
    the interval (about one standard error) must cover clearly less (~0.70), so the
    estimate is not merely conservative.
    """
    truth, area = exact(0.1, 0.1, QUARTER, "cartesian")
    gci_coverage, area_coverage, half = _coverage(method, "joint", 200, samples, truth, area * np.pi / 2)
    assert 0.89 <= gci_coverage <= 0.995
    assert 0.89 <= area_coverage <= 0.995
    assert 0.55 <= half <= 0.85


@pytest.mark.parametrize("method", ["mc", "qmc"])
def test_statistical_coverage_on_the_cartesian_domain(exact, method):
    truth, area = exact(0.1, 0.1, QUARTER, "cartesian")
    gci_coverage, area_coverage, _ = _coverage(method, "cartesian", 200, 2**12, truth, area * np.pi / 2,
                                               closed_form_inverse(ARM))
    assert 0.89 <= gci_coverage <= 0.995
    assert 0.89 <= area_coverage <= 0.995


DESIGNS = [  # (l1, l2, theta2 limits, kinks of 1/kappa inside)
    (0.1, 0.1, QUARTER, ()),
    (0.2, 0.1, (0.0, np.pi), ()),
    (np.sqrt(2) * 0.1, 0.1, (np.pi / 4, 7 * np.pi / 8), (3 * np.pi / 4,)),  # isotropic at theta2 = 135 deg
]


@pytest.mark.parametrize("method", ["grid", "adaptive"])
@pytest.mark.parametrize("design", DESIGNS, ids=["fig-8-19", "long-upper-arm", "isotropic"])
@pytest.mark.parametrize("measure", ["cartesian", "joint"])
def test_deterministic_error_estimates_bracket_the_true_error(exact, method, design, measure):
    l1, l2, theta2, kinks = design
    truth, _ = exact(l1, l2, theta2, measure, kinks)
    arm = ARM.bind(l1=l1, l2=l2)
    for samples in (2**8, 2**10, 2**12, 2**14, 2**16):
        result = G.gci(arm, method=method, samples=samples, measure=measure, limits=_limits(theta2))
        achieved = abs(result.value.value - truth)
        assert achieved <= result.value.error, (samples, achieved, result.value.error)


@pytest.mark.parametrize("method", ["grid", "adaptive"])
def test_deterministic_error_estimates_bracket_the_true_error_on_the_cartesian_domain(exact, method):
    """The reachability indicator jumps at the workspace boundary; the estimates still cover the error."""
    truth, area = exact(0.1, 0.1, QUARTER, "cartesian")
    ik, box = closed_form_inverse(ARM), bounding_box(ARM)
    for samples in (2**10, 2**12, 2**14, 2**16, 2**18):
        result = G.gci(ARM, method=method, samples=samples, domain="cartesian", inverse=ik, box=box)
        assert abs(result.value.value - truth) <= result.value.error, samples
        assert abs(result.measure.value - area * np.pi / 2) <= result.measure.error, samples


# --- measures and formulations ------------------------------------------------------------------


def test_area_is_exact_for_the_seed_arm(exact):
    """Fig. 8.19 arm: the area of the 0..90 deg workspace is (pi/2) l1 l2 (exact, from |det J| = l1 l2 sin theta2)."""
    for l in (0.1, 0.2):
        arm = ARM.bind(l1=l, l2=l)
        for method in ("adaptive", "qmc"):
            area = G.workspace_measure(arm, method=method, samples=2**14, seed=0)
            assert abs(area.value - np.pi / 2 * l * l) <= area.error
            assert area.relative_error < 1e-6


def test_cartesian_and_joint_space_formulations_agree_where_the_map_is_one_to_one(exact):
    """0 <= theta2 <= 90 deg: one elbow branch, q -> TCP one-to-one: the same GCI and area."""
    ik = closed_form_inverse(ARM)
    joint = G.gci(ARM, method="adaptive", samples=2**14)
    cartesian = G.gci(ARM, method="qmc", samples=2**18, seed=3, domain="cartesian", inverse=ik)
    # Twice the combined 95 % error bars: one seed is not a coverage test (those are above).
    assert abs(joint.value.value - cartesian.value.value) <= 2 * (joint.value.error + cartesian.value.error)
    assert abs(joint.measure.value - cartesian.measure.value) <= 2 * (joint.measure.error + cartesian.measure.error)
    assert cartesian.value.error < 1e-3 * cartesian.value.value


def test_the_measure_matters():
    """Averaging over joint space (dq) rates configurations, not places: a different number."""
    cartesian = G.gci(ARM, method="adaptive", samples=2**12)
    joint = G.gci(ARM, method="adaptive", samples=2**12, measure="joint")
    assert abs(cartesian.value.value - joint.value.value) > 100 * (cartesian.value.error + joint.value.error)


def test_overlapping_branches_are_counted_with_multiplicity_in_joint_space(exact):
    """-90 <= theta2 <= 90 deg: elbow up and down reach overlapping regions.

    |det J| dq counts the overlap twice (area = pi l1 l2 exactly, both branches), the
    Cartesian domain counts each point once (strictly less, at least one branch's area).
    """
    limits = _limits((-np.pi / 2, np.pi / 2))
    joint = G.workspace_measure(ARM, method="adaptive", samples=2**14, limits=limits)
    cartesian = G.workspace_measure(ARM, method="qmc", samples=2**16, seed=0, limits=limits, domain="cartesian",
                                    inverse=closed_form_inverse(ARM))
    assert abs(joint.value - np.pi * 0.01) <= joint.error
    assert np.pi / 2 * 0.01 + cartesian.error < cartesian.value < np.pi * 0.01 - cartesian.error


def test_gci_is_dimensionless_and_area_scales_with_length_squared():
    base = G.gci(ARM, method="adaptive", samples=2**12)
    scaled = G.gci(ARM.bind(l1=0.37, l2=0.37), method="adaptive", samples=2**12)
    assert scaled.value.value == pytest.approx(base.value.value, rel=1e-12)
    assert scaled.measure.value == pytest.approx(base.measure.value * 3.7**2, rel=1e-12)


def test_global_index_accepts_other_local_indices():
    from symkin.numerics import conditioning

    gci = G.gci(ARM, method="adaptive", samples=2**12).value.value
    smooth = G.global_index(ARM, method="adaptive", samples=2**12,
                            index=conditioning.inverse_frobenius_condition_number).value.value
    assert gci < smooth <= 1  # 1/kappa <= 1/kappa_F <= k/kappa


def test_bad_requests_are_explained():
    with pytest.raises(ValueError, match="unknown integration method"):
        integrate(G.joint_space_integrand(ARM), "simpson", 100)
    with pytest.raises(ValueError, match="square task Jacobian"):
        G.joint_space_integrand(_RectangularStub(), measure="cartesian")
    with pytest.raises(ValueError, match="needs an inverse kinematics"):
        G.gci(ARM, domain="cartesian", samples=64)
    with pytest.raises(ValueError, match="unknown measure"):
        G.gci(ARM, measure="polar", samples=64)


class _RectangularStub:
    """A loaded-model stand-in with a 3 x 2 task Jacobian (x, y, z from two joints)."""

    name = "stub"
    info = ModelInfo("stub", "serial", (Coordinate("a", "R", None), Coordinate("b", "R", None)), ("x", "y", "z"),
                     (), {})
    joint_limits = ((-np.pi, np.pi), (-np.pi, np.pi))

    @staticmethod
    def jacobian(q):
        return np.ones(np.shape(q)[:-1] + (3, 2))
