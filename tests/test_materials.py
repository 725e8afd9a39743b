"""Table material presets: grounds from restitution and friction, the restitution obtained."""

import pytest

from dice_env import Die, Ground, Scene, materials, table

# The simulator's flat-landing restitution at 1 m/s is within this of each preset's target
# (the step's error and gravity during the contact, larger on the softer grounds).
RESTITUTION_TOL = 0.01


def test_wood_is_the_default_table():
    assert materials.ground("wood") == Ground()
    assert materials.scene("wood") == Scene()


@pytest.mark.parametrize("name", list(materials.PRESETS))
def test_each_preset_builds_and_gives_its_restitution(name):
    material = materials.PRESETS[name]
    ground = materials.ground(name)
    assert (ground.stiffness, ground.friction) == (material.stiffness, material.friction)
    assert materials.measured(name) == pytest.approx(material.restitution, abs=RESTITUTION_TOL)


def test_damping_follows_the_die_mass():
    heavy = Die.standard("d6", mass=4 * table.DIE_MASS)
    for name, material in materials.PRESETS.items():
        light, heavier = materials.ground(name), materials.ground(name, heavy)
        assert heavier.damping == pytest.approx(2 * light.damping)
        assert heavier.damping == pytest.approx(table.damping_for_restitution(
            material.restitution, material.stiffness, heavy.mass))
    assert materials.scene("felt", heavy).die is heavy


def test_unknown_preset_names_the_presets():
    for bad in ("carpet", "Felt", 3):
        with pytest.raises(ValueError, match="felt, wood, glass, craps"):
            materials.ground(bad)


def test_material_values_are_checked():
    with pytest.raises(ValueError, match="restitution"):
        materials.Material(1.5, 0.3, 1e5, "")
    with pytest.raises(ValueError, match="stiffness"):
        materials.Material(0.5, 0.3, 0.0, "")
