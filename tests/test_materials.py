"""Table material presets: grounds from restitution and friction, the restitution obtained."""

import numpy as np
import pytest

from dice_env import Die, Ground, Scene, State
from dice_env.model import defaults, materials
from dice_env.simulation.calibration import measured_restitution
from studies import materials as study
from studies import run as run_study
from studies.__main__ import main as studies_main

# The simulator's flat-landing restitution at 1 m/s is within this of each preset's target
# (the step's error and gravity during the contact, larger on the softer grounds).
RESTITUTION_TOL = 0.01


def test_wood_is_the_default_table():
    assert materials.ground("wood") == Ground()
    assert materials.scene("wood") == Scene()


@pytest.mark.parametrize("name", list(materials.MATERIALS))
def test_each_preset_builds_and_gives_its_restitution(name):
    material = materials.MATERIALS[name]
    ground = materials.ground(name)
    assert (ground.stiffness, ground.friction) == (material.stiffness, material.friction)
    assert measured_restitution(materials.scene(name)) == pytest.approx(material.restitution,
                                                                        abs=RESTITUTION_TOL)


def test_damping_follows_the_die_mass():
    heavy = Die.standard("d6", mass=4 * defaults.DIE_MASS)
    for name, material in materials.MATERIALS.items():
        light, heavier = materials.ground(name), materials.ground(name, heavy)
        assert heavier.damping == pytest.approx(2 * light.damping)
        assert heavier.damping == pytest.approx(defaults.damping_for_restitution(
            material.restitution, material.stiffness, heavy.mass))
    assert materials.scene("felt", heavy).die is heavy


def test_unknown_preset_names_the_presets():
    for bad in ("carpet", "Felt", 3):
        with pytest.raises(ValueError, match="'felt', 'wood', 'glass', 'craps'"):
            materials.ground(bad)


def test_material_values_are_checked():
    with pytest.raises(ValueError, match="restitution"):
        materials.Material(1.5, 0.3, 1e5, "")
    with pytest.raises(ValueError, match="stiffness"):
        materials.Material(0.5, 0.3, 0.0, "")


def test_quick_study_writes_the_page(tmp_path):
    numbers = run_study("materials", tmp_path, quick=True)
    text = (tmp_path / "materials.md").read_text()
    for name in materials.MATERIALS:
        assert f"| {name} |" in text
        assert numbers[f"{name}_restitution"] == pytest.approx(
            materials.MATERIALS[name].restitution, abs=RESTITUTION_TOL)
        for kind in ("vigorous", "gentle"):
            assert 0.0 <= numbers[f"{name}_{kind}_down"] <= 1.0
            assert numbers[f"{name}_{kind}_impacts"] >= 1.0
    assert (tmp_path / "figures" / "materials.png").stat().st_size > 10_000


def test_study_memory_counts_resting_faces():
    # a die released flat on face 6 (showing 1) at rest stays: it rests on its release-down
    # face, never on its release-up face
    scene = materials.scene("felt", t_max=2.0)
    state = State.release(scene, np.array([0.0, 0.0, 0.008 + 1e-4]), np.zeros(3))
    outcome = study.throw(scene, state)
    assert (outcome.faces.ended, outcome.down, outcome.up) == (1, 1, 0)
    assert outcome.memory("down")[0] == 1.0


def test_study_sample_size_is_checked(tmp_path):
    for bad in (1, 2.5, True):
        with pytest.raises(ValueError, match="throws must be an int >= 2"):
            study.run(tmp_path, throws=bad)
    studies_main(["materials", "--throws", "4", "--out", str(tmp_path)])
    assert "4 vigorous and 2 gentle throws" in (tmp_path / "materials.md").read_text()


def test_a_quick_run_never_replaces_a_full_page(tmp_path, monkeypatch, capsys):
    from studies.__main__ import DOCS, QUICK

    with pytest.raises(SystemExit):
        studies_main(["materials", "--quick", "--out", str(DOCS)])
    assert "may not write into" in capsys.readouterr().err
    monkeypatch.chdir(tmp_path)
    studies_main(["materials", "--quick", "--throws", "4"])
    assert (tmp_path / QUICK / "materials.md").exists()
