"""Long generated chains (issue 12): a 20-joint arm derives in seconds and is exact.

The chain comes from ``benchmarks/chain_models.py`` (twists of +-90 deg and a generic 0.3 rad,
a full rigid body on every link).  Its task Jacobian has about 2e8 operations as a tree and
1e3 distinct nodes, so it exercises the DAG-aware paths: sympy -> SymEngine conversion with
a shared memo, free-symbol walks that visit each node once, and SymEngine's CSE for
functions over ``SYMPY_CSE_LIMIT``.  The reference is independent: numeric DH products for
FK and the geometric Jacobian, and the tests' own numeric Newton-Euler for the dynamics.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

from conftest import ROOT
from newton_euler import dh_transform, inverse_dynamics, links_of
from symkin import derive, load
from symkin.derivation.graph import Derivation
from symkin.expression_dag import distinct_nodes, tree_size
from symkin.kinematics.quantities import chain_frames, geometric_jacobian_matrix
from symkin.model import load_model
from symkin.optimize.cse import SYMPY_CSE_LIMIT
from tolerances import DYNAMICS, KINEMATICS

sys.path.insert(0, str(ROOT / "benchmarks"))
from chain_models import chain_yaml, dh_chain  # noqa: E402

N = 20
OUTPUTS = ["fk", "jacobian", "mass_matrix", "coriolis_vector", "gravity_vector"]
GRAVITY = np.array([0.0, 0.0, -9.81])


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    directory = tmp_path_factory.mktemp("chain")
    path = directory / f"chain{N}.yaml"
    path.write_text(chain_yaml(N))
    return derive(path, directory / "generated", outputs=OUTPUTS, backends=["numpy"], combine="none")


def _frames(q: np.ndarray) -> list[np.ndarray]:
    """base_T_i for i = 0..n by the numeric DH product."""
    frames = [np.eye(4)]
    for qi, link in zip(q, dh_chain(N)):
        frames.append(frames[-1] @ dh_transform(qi, link.d, link.a, link.alpha))
    return frames


def _geometric_jacobian(q: np.ndarray) -> np.ndarray:
    frames = _frames(q)
    tcp = frames[-1][:3, 3]
    columns = [np.concatenate([np.cross(T[:3, 2], tcp - T[:3, 3]), T[:3, 2]]) for T in frames[:-1]]
    return np.array(columns).T


def test_the_large_functions_took_the_dag_path(chain):
    """The test below is about the large-function path: the Jacobian must be over the sympy CSE limit."""
    manifest = json.loads((chain / "manifest.json").read_text())
    derived = {f["name"]: f["op_counts"]["derived"] for f in manifest["functions"]}
    assert derived["jacobian"] > SYMPY_CSE_LIMIT, derived


def test_a_20_joint_chain_matches_independent_numeric_kinematics_and_dynamics(chain):
    arm = load(chain)
    links = links_of(dh_chain(N))
    reach = sum(abs(link.a) + abs(link.d) for link in links)
    rng = np.random.default_rng(12)
    for _ in range(5):
        q, qd, qdd = (rng.uniform(-np.pi, np.pi, N), rng.uniform(-1, 1, N), rng.uniform(-1, 1, N))
        np.testing.assert_allclose(arm.fk(q), _frames(q)[-1], rtol=0, atol=KINEMATICS * N * reach)
        np.testing.assert_allclose(arm.jacobian(q), _geometric_jacobian(q), rtol=0, atol=KINEMATICS * N * reach)
        tau = arm.mass_matrix(q) @ qdd + arm.coriolis_vector(q, qd) + arm.gravity_vector(q)
        want = inverse_dynamics(links, GRAVITY, q, qd, qdd)
        # each torque sums n link contributions of size |tau|max, each with DYNAMICS relative rounding
        np.testing.assert_allclose(tau, want, rtol=0, atol=DYNAMICS * N * np.abs(want).max())


def _kinematic_graph_sizes(n: int, directory) -> tuple[int, int]:
    """(distinct nodes, tree size) of the TCP pose and geometric Jacobian of the n-joint chain."""
    path = directory / f"chain{n}.yaml"
    path.write_text(chain_yaml(n))
    derivation = Derivation(load_model(path))
    exprs = [*derivation[chain_frames].tcp.T, *derivation[geometric_jacobian_matrix]]
    return sum(1 for _ in distinct_nodes(exprs)), tree_size(exprs)


def test_the_kinematics_are_a_graph_that_grows_linearly_with_the_chain(tmp_path):
    """The chain walk shares every link's rotation and origin with the next link (issue 12).

    Each joint adds a bounded number of new nodes, so the distinct nodes of FK and the
    Jacobian grow as n (memory stays bounded) while the tree they stand for grows
    exponentially; every later walk (conversion, free symbols, CSE) visits distinct nodes.
    """
    nodes_12, tree_12 = _kinematic_graph_sizes(12, tmp_path)
    nodes_24, tree_24 = _kinematic_graph_sizes(24, tmp_path)
    assert nodes_24 <= 2.5 * nodes_12, (nodes_12, nodes_24)
    assert tree_24 > 1000 * tree_12, (tree_12, tree_24)
    assert nodes_24 < 1e-6 * tree_24, (tree_12, tree_24)
