"""The glTF export of recorded throws: valid glTF 2.0, keyframes as recorded, data round trip."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib as gl
import pytest

from dice_env import Die, Scene, State
from dice_env.model.rotations import matrix_to_quaternion, quaternion_to_matrix
from dice_env.model.surroundings import walls
from dice_env.simulation.group import GroupState
from dice_env.viewer import Recording, load, record
from dice_env.viewer.gltf import ANIMATION, Z_UP, read_glb, write_glb
from dice_env.viewer.scenery import scenery
from dice_env.viewer.textures import face_atlas, png_bytes

JS = Path(__file__).resolve().parents[1] / "dice_env" / "viewer" / "js"
DTYPES = {gl.FLOAT: np.float32, gl.UNSIGNED_SHORT: np.uint16, gl.UNSIGNED_INT: np.uint32}
WIDTHS = {gl.SCALAR: 1, gl.VEC2: 2, gl.VEC3: 3, gl.VEC4: 4}


def _d6() -> Recording:
    scene = Scene()
    state = State.release(scene, np.array([0, 0, 0.05]), np.array([0.5, 0, 0]),
                          np.array([10.0, 5, 3]))
    return record(scene, scene.die, state)[0]


def _d20_tray() -> Recording:
    scene = Scene(walls=walls("tray"))
    state = State.release(scene, np.array([-0.1, 0, 0.05]), np.array([1.0, 0.3, 0]),
                          np.array([10.0, 5, 3]))
    return record(scene, Die.standard("d20"), state)[0]


def _twelve() -> Recording:
    scene = Scene(walls=walls("tray"))
    kinds = (Die(), Die.standard("d20"), Die().load(3), Die.cuboid((0.02, 0.016, 0.012)))
    hands = [State.release(scene, np.array([-0.075 + 0.03 * (k % 6), -0.02 + 0.04 * (k // 6),
                                            0.04]),
                           np.array([0.3, 0.1, 0]), np.array([5.0, -3, 2 + k]))
             for k in range(12)]
    return record(scene, kinds * 3, GroupState.of(hands), t_max=0.6)[0]


CASES = {"d6": _d6, "d20_tray": _d20_tray, "twelve": _twelve}


@pytest.fixture(scope="module", params=sorted(CASES))
def written(request: pytest.FixtureRequest,
            tmp_path_factory: pytest.TempPathFactory) -> tuple[Recording, Path]:
    recording = CASES[request.param]()
    return recording, write_glb(recording, tmp_path_factory.mktemp("glb") / "throw.glb")


def _accessor(gltf: gl.GLTF2, index: int) -> np.ndarray:
    """The data of accessor ``index`` as an array (count,) or (count, width)."""
    accessor = gltf.accessors[index]
    view = gltf.bufferViews[accessor.bufferView]
    width = WIDTHS[accessor.type]
    data = np.frombuffer(gltf.binary_blob(), DTYPES[accessor.componentType],
                         accessor.count * width, view.byteOffset + (accessor.byteOffset or 0))
    return data if width == 1 else data.reshape(-1, width)


def test_validator_finds_no_errors(written: tuple[Recording, Path]) -> None:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    if not (JS / "node_modules" / "gltf-validator").is_dir():
        pytest.skip(f"gltf-validator is not installed: run npm install in {JS}")
    _, path = written
    run = subprocess.run([node, str(JS / "validate.mjs"), str(path)], capture_output=True,
                         text=True, timeout=60, check=False)
    issues = json.loads(run.stdout)["issues"]
    assert run.returncode == 0, run.stdout
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]


def test_keyframes_and_meshes_are_the_recording(written: tuple[Recording, Path]) -> None:
    recording, path = written
    gltf = gl.GLTF2.load_binary(str(path))
    root = gltf.nodes[gltf.scenes[gltf.scene].nodes[0]]
    assert root.rotation == pytest.approx(Z_UP)
    (animation,) = gltf.animations
    assert animation.name == ANIMATION
    quaternions = matrix_to_quaternion(recording.orientation)  # w, x, y, z
    for i, die in enumerate(recording.dice):
        assert i in root.children
        channels = {c.target.path: animation.samplers[c.sampler]
                    for c in animation.channels if c.target.node == i}
        assert set(channels) == {"translation", "rotation"}
        for sampler in channels.values():
            assert sampler.interpolation == gl.ANIM_LINEAR
            np.testing.assert_allclose(_accessor(gltf, sampler.input), recording.t, atol=1e-6)
        translation = _accessor(gltf, channels["translation"].output)
        np.testing.assert_allclose(translation, recording.position[:, i], atol=1e-7)
        rotation = _accessor(gltf, channels["rotation"].output)[:, [3, 0, 1, 2]]
        np.testing.assert_allclose(np.abs(np.einsum("nk,nk->n", rotation, quaternions[:, i])),
                                   1.0, atol=1e-6)
        np.testing.assert_allclose(quaternion_to_matrix(rotation.astype(np.float64)),
                                   recording.orientation[:, i], atol=1e-6)
        (primitive,) = gltf.meshes[gltf.nodes[i].mesh].primitives
        assert len(_accessor(gltf, primitive.indices)) == 3 * sum(len(f) - 2 for f in die.faces)
        corners = np.asarray(die.vertices)[np.concatenate(die.faces)] - np.asarray(die.com)
        np.testing.assert_allclose(_accessor(gltf, primitive.attributes.POSITION), corners,
                                   atol=1e-8)
        assert gltf.materials[primitive.material].pbrMetallicRoughness.baseColorTexture
    walls_drawn = [n for n in gltf.nodes if (n.name or "").startswith("wall")]
    assert len(walls_drawn) == len(recording.scene.walls)
    for node, wall in zip(walls_drawn, recording.scene.walls, strict=True):
        (primitive,) = gltf.meshes[node.mesh].primitives
        corners = _accessor(gltf, primitive.attributes.POSITION)
        np.testing.assert_allclose(corners @ wall.normal, wall.offset, atol=1e-6)


def test_floor_and_walls_are_the_pages(written: tuple[Recording, Path]) -> None:
    recording, path = written
    gltf = gl.GLTF2.load_binary(str(path))
    view, scene = scenery(recording), recording.scene
    planes = {"floor": (view.floor, scene.ground)} | {
        f"wall {k}": (corners, scene.walls[k]) for k, corners in view.walls.items()}
    drawn = {n.name: n for n in gltf.nodes if n.name == "floor" or n.name.startswith("wall")}
    assert drawn.keys() == planes.keys()
    for name, (corners, plane) in planes.items():
        (primitive,) = gltf.meshes[drawn[name].mesh].primitives
        position = _accessor(gltf, primitive.attributes.POSITION)
        assert any(np.allclose(position, c, atol=1e-7) for c in (corners, corners[::-1])), name
        np.testing.assert_allclose(_accessor(gltf, primitive.attributes.NORMAL),
                                   np.tile(plane.normal, (len(corners), 1)), atol=1e-7)
        a, b, c = position[_accessor(gltf, primitive.indices).reshape(-1, 3).T]
        assert (np.cross(b - a, c - a) @ plane.normal > 0).all(), name  # counter-clockwise


def test_data_comes_back(written: tuple[Recording, Path]) -> None:
    recording, path = written
    assert gl.GLTF2.load_binary(str(path)).asset.generator.startswith("dice_env ")
    assert read_glb(path) == [recording.to_data()]
    (loaded,) = load(path)
    assert loaded.outcome == recording.outcome and loaded.dice == recording.dice
    np.testing.assert_array_equal(loaded.position, recording.position)


def test_atlas_holds_every_face() -> None:
    die = Die.standard("d8")
    image, uv = face_atlas(die, pixels=32)
    assert image.shape == (96, 96, 4) and image.dtype == np.uint8
    assert uv.shape == (8, 3, 2) and (uv > 0).all() and (uv < 1).all()
    tiles = np.floor(uv * 3).astype(int)  # each face's corners in its own tile
    assert (tiles == tiles[:, :1]).all() and len({tuple(t[0]) for t in tiles}) == 8
    assert png_bytes(image).startswith(b"\x89PNG")


def test_bad_arguments_name_the_parameter(tmp_path: Path) -> None:
    recording = _d6()
    with pytest.raises(TypeError, match="recording"):
        write_glb(recording.to_data(), tmp_path / "x.glb")
    with pytest.raises(ValueError, match="path"):
        write_glb(recording, tmp_path / "x.gltf")
    with pytest.raises(TypeError, match="path"):
        write_glb(recording, 3)
    with pytest.raises(ValueError, match="path"):
        read_glb(tmp_path / "x.json")
    plain = tmp_path / "plain.glb"
    gl.GLTF2().save_binary(str(plain))
    with pytest.raises(ValueError, match="no dice_env recording"):
        read_glb(plain)
    with pytest.raises(TypeError, match="die"):
        face_atlas("d6")
    with pytest.raises(ValueError, match="pixels"):
        face_atlas(Die(), pixels=4)
    with pytest.raises(ValueError, match="image"):
        png_bytes(np.zeros((4, 4), np.uint8))
