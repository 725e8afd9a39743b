"""Stability map classes against the predicted bound, and the extreme cases."""

import numpy as np
import pytest

from dice_env.model.scene import ContactLaw
from studies import stability as st


@pytest.mark.parametrize("law", [ContactLaw.PAPER, ContactLaw.GATED])
@pytest.mark.parametrize("stiffness", [1e4, 1e6])
def test_below_bound_does_not_blow_up_and_far_above_does(law, stiffness):
    assert st.map_cell(stiffness, 0.3, law) != st.BLOWUP
    assert st.map_cell(stiffness, 0.1, law) == st.STABLE
    assert st.map_cell(stiffness, 5.0, law) == st.BLOWUP


def test_paper_law_is_stable_at_half_the_bound_where_the_gated_law_drifts():
    # the paper law's air drag hides the impact energy error of the nearly undamped scene
    assert st.map_cell(1e6, 0.5, ContactLaw.PAPER) == st.STABLE
    assert st.map_cell(1e6, 0.5, ContactLaw.GATED) == st.DRIFTING


def test_extreme_cases_cover_the_issue_ranges():
    cases = st.extreme_cases(quick=False)
    groups = {c.group for c in cases}
    assert {"speed", "spin", "friction", "damping", "tilt", "mass", "stiffness"} <= groups
    assert max(c.vigour.spin[1] for c in cases) == 1000.0
    assert max(c.vigour.speed[1] for c in cases) == 100.0
    masses = [c.scene.die.mass for c in cases if c.group == "mass"]
    assert min(masses) == 1e-3 and max(masses) == 1e3


def test_automatic_step_drift_shrinks_with_safety():
    case = next(c for c in st.extreme_cases(quick=True) if c.label == "S = 1e+06")
    sweep = st.safety_sweep([case], (0.1, 0.01), throws=8, seed=1)
    assert sweep[0, 1, 0] < sweep[0, 0, 0]
    assert sweep[0, 1, 0] < 0.01 and sweep[0, 1, 1] == 0


def test_quick_report(tmp_path):
    numbers = st.run(tmp_path, quick=True)
    assert numbers["extreme_any_nan"] == 0.0
    assert numbers["paper_blowing_up_below_bound"] == 0.0
    assert numbers["paper_stable_above_bound"] == 0.0
    assert numbers["paper_first_blowup"] > 1.0 and numbers["gated_first_blowup"] > 1.0
    assert (tmp_path / "figures" / "stability_map.png").stat().st_size > 10_000
    text = (tmp_path / "stability.md").read_text()
    assert "| baseline | default scene | 100% |" in text
    assert not np.isnan(numbers["gated_stable_below_bound"])
