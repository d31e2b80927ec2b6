"""How the workspace analyses sample each example mechanism (symkin.mechanism.sampling, issue 62): the question
the commands ask instead of the kind.  Legs without closed forms are continued (tests/parallel/test_generic_legs.py)."""

from __future__ import annotations

import pytest

from symkin import mechanism
from symkin.mechanism import Sampling

#: The expected sampling of example models: from the seed and the model files (an open chain's joint box; a DELTA,
#: pantograph, Stewart-Gough platform and the DELTA with a wrist reached through their closed-form ik; the Agile
#: Eye's orientations).
EXPECTED = {"ur10e": Sampling.JOINTS, "planar_2r": Sampling.JOINTS, "phantom_premium": Sampling.JOINTS,
            "delta": Sampling.INVERSE, "pantograph": Sampling.INVERSE, "stewart": Sampling.INVERSE,
            "delta_wrist": Sampling.INVERSE, "agile_eye": Sampling.ORIENTATIONS}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_example_is_sampled_as_its_closed_forms_allow(loaded, name):
    model = loaded(name, "numpy")
    assert mechanism.sampling(model) is EXPECTED[name]
    assert mechanism.sampled_in_task_space(model) == (EXPECTED[name] is not Sampling.JOINTS)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_only_a_hybrid_devices_handle_is_on_further_joints(loaded, name):
    """The DELTA with a wrist carries its handle on joints beyond the platform (rated as a whole device)."""
    assert mechanism.handle_on_further_joints(loaded(name, "numpy")) == (name == "delta_wrist")
