"""The paper's claims (Figures 6–13) asserted on our runs of its own scripts."""

import numpy as np
import pytest

from dice_env.simulation.paper import ground_cube
from studies import paper_figures as pf


def test_figure_6_no_friction_keeps_sliding():
    # launch speed 5: without friction the cube still slides at 5 after 10 s; with it, stops
    assert pf.sliding_speed_at_end(ground_cube(mu=0.0)) == pytest.approx(5.0, abs=1e-6)
    assert abs(pf.sliding_speed_at_end(ground_cube())) < 0.01


def test_figure_7_no_damping_keeps_bouncing():
    assert pf.bounce_range_at_end(ground_cube(D=0.0)) > 3.0
    assert pf.bounce_range_at_end(ground_cube()) < 0.1


def test_figure_8_soft_ground_centre_sinks_below_zero():
    assert pf.lowest_centre(ground_cube(S=10.0)) < -0.3
    assert pf.lowest_centre(ground_cube()) > 0.45


def test_figures_9_to_12_stiff_ground_gains_energy_at_10000_steps_not_20000():
    coarse = ground_cube(S=1e6, allow_unstable=True)
    fine = ground_cube(S=1e6, clockmax=20000)
    assert pf.energy_gain_after_landing(coarse) > 10.0
    assert coarse.result.unstable[0]
    assert pf.energy_gain_after_landing(fine) < 0.0
    assert not fine.result.unstable[0]


def test_figure_4_rebounds_mostly_decrease():
    peaks = pf.rebound_peaks(pf.real_throw_cube(seed=pf.THROW_SEED, record_nodes=True))
    assert len(peaks) > 5
    assert peaks[0] > 1.5 and peaks[-1] < 0.6
    assert np.mean(np.diff(peaks) < 0) > 0.8


def test_figure_13_steps_grow_like_sqrt_stiffness_on_the_effective_mass_line():
    stiffness = np.array([1e3, 1e4, 1e5, 1e6])
    needed = {name: [] for name in pf.CRITERIA}
    for s in stiffness:
        grid = pf.search_grid(s, 60)
        rises = pf.energy_rises(s, grid)
        for name, limit in pf.CRITERIA.items():
            needed[name].append(pf.steps_needed(grid, rises, limit))
    for steps in needed.values():
        assert pf.fit_exponent(stiffness, np.array(steps)) == pytest.approx(0.5, abs=0.05)
    blowup = np.array(needed["rise <= 100%"]) / pf.theory_steps(stiffness, node_mass=False)
    assert np.all((blowup > 0.9) & (blowup < 1.15))
    node = np.array(needed["rise <= 100%"]) / pf.theory_steps(stiffness, node_mass=True)
    assert np.all(node < 0.85)


def test_theory_lines_differ_by_sqrt_2_at_large_stiffness():
    ratio = pf.theory_steps(1e8, node_mass=True) / pf.theory_steps(1e8, node_mass=False)
    assert ratio[0] == pytest.approx(np.sqrt(2), rel=1e-3)


def test_steps_needed_requires_a_bracketing_grid():
    with pytest.raises(ValueError, match="bracket"):
        pf.steps_needed(np.array([10, 20]), np.array([0.0, 0.0]), 0.1)


def test_quick_report_writes_markdown_and_figures(tmp_path):
    numbers = pf.run(tmp_path, quick=True)
    text = (tmp_path / "paper.md").read_text()
    assert "| 6 | mu = 0: keeps sliding" in text and "**confirmed**" in text
    for name in ("paper_fig4_5_real_throw", "paper_fig6_12_ground_cube",
                 "paper_fig13_steps_vs_stiffness"):
        assert (tmp_path / "figures" / f"{name}.png").stat().st_size > 10_000
    assert numbers["fig13_exponent_100"] == pytest.approx(0.5, abs=0.05)
    # the paper law's air drag: the gated throw keeps more energy and slides farther
    assert numbers["throw_gated_x_end"] > numbers["throw_paper_x_end"]
