"""A recorded throw as binary glTF 2.0 (``.glb``), for Blender, Godot, three.js and the like.

Every die is a flat-shaded mesh textured with its labels
(:func:`~dice_env.viewer.textures.face_atlas`) on a node the animation ``"throw"`` moves; the
floor and walls are the polygons the page draws (:mod:`~dice_env.viewer.scenery`). A root node
turns the z-up world to glTF's y up. The recording's data rides in ``asset.extras["recordings"]``
as JSON text (pygltflib drops a JSON object's nulls), so :func:`read_glb` gets it back.
"""

from __future__ import annotations

import json
import math
import os
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pygltflib as gl

from dice_env.disk import parse_json, write_atomically
from dice_env.envs.render import TABLE_COLOUR, WALL_COLOUR
from dice_env.model.checks import check_type
from dice_env.model.die import Die
from dice_env.model.rotations import matrix_to_quaternion
from dice_env.viewer.recording import Recording, library_version
from dice_env.viewer.scenery import scenery
from dice_env.viewer.textures import face_atlas, png_bytes

Z_UP = [-math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)]  # root rotation (x, y, z, w): z up to y up
EXTRAS = "recordings"  # asset.extras[EXTRAS]: the recordings' data, JSON text of a list
ANIMATION = "throw"
GLB_MAGIC, GLB_VERSION, JSON_CHUNK = b"glTF", 2, b"JSON"  # a .glb's header and first chunk
_COMPONENTS = {np.dtype(np.float32): gl.FLOAT, np.dtype(np.uint16): gl.UNSIGNED_SHORT}
_TYPES = {1: gl.SCALAR, 2: gl.VEC2, 3: gl.VEC3, 4: gl.VEC4}


def write_glb(recording: Recording, path: str | os.PathLike[str]) -> Path:
    """Write ``recording`` as a binary glTF to ``path`` (ending in ``.glb``); returns the path."""
    check_type("recording", recording, Recording)
    path = _glb_path(path)
    gltf = gl.GLTF2(asset=gl.Asset(generator=f"dice_env {library_version()}",
                                   extras={EXTRAS: json.dumps([recording.to_data()])}),
                    samplers=[gl.Sampler(magFilter=gl.LINEAR, minFilter=gl.LINEAR_MIPMAP_LINEAR,
                                         wrapS=gl.CLAMP_TO_EDGE, wrapT=gl.CLAMP_TO_EDGE)])
    blob = _Blob(gltf)
    meshes = {die: _die_mesh(blob, die) for die in dict.fromkeys(recording.dice)}
    for i, die in enumerate(recording.dice):
        gltf.nodes.append(gl.Node(name=f"die {i} ({die.name})", mesh=meshes[die]))
    _animate(blob, recording)
    _surroundings(blob, recording)
    gltf.nodes.append(gl.Node(name="dice_env (z up)", rotation=Z_UP,
                              children=list(range(len(gltf.nodes)))))
    gltf.scenes = [gl.Scene(name=recording.title or "throw", nodes=[len(gltf.nodes) - 1])]
    gltf.scene = 0
    gltf.buffers = [gl.Buffer(byteLength=len(blob.data))]
    gltf.set_binary_blob(bytes(blob.data))
    write_atomically(path, b"".join(gltf.save_to_bytes()))
    return path


def read_glb(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The recordings' data (a list of :meth:`Recording.to_data`) in a :func:`write_glb` file."""
    path = _glb_path(path)
    data = path.read_bytes()
    if len(data) < 20 or data[:4] != GLB_MAGIC:
        raise ValueError(f"path {str(path)!r} is not a binary glTF (no {GLB_MAGIC!r} header)")
    version, length, size = struct.unpack_from("<III", data, 4)
    if version != GLB_VERSION or length != len(data):
        raise ValueError(f"path {str(path)!r} is not a whole glTF {GLB_VERSION} file (its "
                         f"header says version {version}, {length} bytes; it holds "
                         f"{len(data)} bytes)")
    if data[16:20] != JSON_CHUNK or 20 + size > length:
        raise ValueError(f"path {str(path)!r} has no whole JSON chunk after its header")
    gltf = parse_json(data[20:20 + size])
    asset = gltf.get("asset") if isinstance(gltf, dict) else None
    extras = asset.get("extras") if isinstance(asset, dict) else None
    if not isinstance(extras, dict) or not isinstance(extras.get(EXTRAS), str):
        raise ValueError(f"path {str(path)!r} holds no dice_env recording "
                         f"(asset.extras[{EXTRAS!r}])")
    return parse_json(extras[EXTRAS])


def _glb_path(path: str | os.PathLike[str]) -> Path:
    """``path`` as a Path, checked to end in ``.glb``."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or a path, got {type(path).__name__}")
    path = Path(path)
    if path.suffix.lower() != ".glb":
        raise ValueError(f"path must end in .glb, got {path.name!r}")
    return path


class _Blob:
    """The binary buffer of a glTF being built, with its buffer views and accessors."""

    def __init__(self, gltf: gl.GLTF2) -> None:
        self.gltf = gltf
        self.data = bytearray()

    def view(self, data: bytes, target: int | None = None) -> int:
        """A buffer view of ``data`` (appended, 4-byte aligned); returns its index."""
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=len(self.data),
                                                   byteLength=len(data), target=target))
        self.data.extend(data)
        return len(self.gltf.bufferViews) - 1

    def accessor(self, array: np.ndarray, target: int | None = None,
                 bounds: bool = False) -> int:
        """An accessor of ``array`` (M,) or (M, K) in its own view (``bounds``: with min, max)."""
        columns = 1 if array.ndim == 1 else array.shape[1]
        flat = array.reshape(len(array), columns)
        self.gltf.accessors.append(gl.Accessor(
            bufferView=self.view(array.tobytes(), target),
            componentType=_COMPONENTS[array.dtype], count=len(array), type=_TYPES[columns],
            min=flat.min(axis=0).tolist() if bounds else None,
            max=flat.max(axis=0).tolist() if bounds else None))
        return len(self.gltf.accessors) - 1

    def mesh(self, name: str, positions: np.ndarray, normals: np.ndarray,
             triangles: np.ndarray, material: int, uv: np.ndarray | None = None) -> int:
        """A mesh of one primitive (``triangles`` (T, 3) corner indices); returns its index."""
        attributes = gl.Attributes(
            POSITION=self.accessor(positions.astype(np.float32), gl.ARRAY_BUFFER, bounds=True),
            NORMAL=self.accessor(normals.astype(np.float32), gl.ARRAY_BUFFER),
            TEXCOORD_0=None if uv is None else self.accessor(uv.astype(np.float32),
                                                             gl.ARRAY_BUFFER))
        # A die's face corners (of at most polyhedra.MAX_VERTICES corners) fit 16-bit indices.
        indices = self.accessor(triangles.astype(np.uint16).ravel(), gl.ELEMENT_ARRAY_BUFFER)
        self.gltf.meshes.append(gl.Mesh(name=name, primitives=[gl.Primitive(
            attributes=attributes, indices=indices, material=material)]))
        return len(self.gltf.meshes) - 1

    def material(self, name: str, colour: np.ndarray | None = None,
                 texture: bytes | None = None) -> int:
        """A matte material of an sRGB ``colour`` (3,) 0-255 (two-sided) or a PNG ``texture``."""
        pbr = gl.PbrMetallicRoughness(metallicFactor=0.0, roughnessFactor=0.7)
        if texture is None:  # sRGB to glTF's linear factors
            c = np.asarray(colour) / 255.0
            pbr.baseColorFactor = [*np.where(c <= 0.04045, c / 12.92,
                                             ((c + 0.055) / 1.055) ** 2.4).tolist(), 1.0]
        else:
            self.gltf.images.append(gl.Image(bufferView=self.view(texture), mimeType="image/png"))
            self.gltf.textures.append(gl.Texture(sampler=0, source=len(self.gltf.images) - 1))
            pbr.baseColorTexture = gl.TextureInfo(index=len(self.gltf.textures) - 1)
        self.gltf.materials.append(gl.Material(name=name, pbrMetallicRoughness=pbr,
                                               doubleSided=texture is None))
        return len(self.gltf.materials) - 1


def _die_mesh(blob: _Blob, die: Die) -> int:
    """The die's mesh about its centre of mass, each face fanned into triangles; its index."""
    image, uv = face_atlas(die)
    vertices = die.vertices_body
    starts = np.cumsum([0, *(len(face) for face in die.faces)])
    triangles = np.array([(start, start + i, start + i + 1)
                          for start, face in zip(starts, die.faces, strict=False)
                          for i in range(1, len(face) - 1)])
    return blob.mesh(
        die.name, vertices[np.concatenate(die.faces)],
        np.repeat(die.face_normals, [len(face) for face in die.faces], axis=0), triangles,
        blob.material(f"{die.name} faces", texture=png_bytes(image)),
        np.concatenate([coords[:len(face)] for coords, face in zip(uv, die.faces,
                                                                     strict=True)]))


def _animate(blob: _Blob, recording: Recording) -> None:
    """The animation "throw": each die node's translation and rotation at every frame."""
    times = blob.accessor(recording.t.astype(np.float32), bounds=True)
    quaternions = matrix_to_quaternion(recording.orientation)[..., [1, 2, 3, 0]]  # x, y, z, w
    flips = np.einsum("nki,nki->nk", quaternions[1:], quaternions[:-1]) < 0
    quaternions[1:] *= np.where(np.cumsum(flips, axis=0) % 2, -1.0, 1.0)[..., None]  # short way
    samplers, channels = [], []
    for i in range(recording.n_dice):
        for path, values in (("translation", recording.position[:, i]),
                             ("rotation", quaternions[:, i])):
            samplers.append(gl.AnimationSampler(
                input=times, output=blob.accessor(values.astype(np.float32)),
                interpolation=gl.ANIM_LINEAR))
            channels.append(gl.AnimationChannel(
                sampler=len(samplers) - 1, target=gl.AnimationChannelTarget(node=i, path=path)))
        blob.gltf.nodes[i].translation = recording.position[0, i].tolist()
        blob.gltf.nodes[i].rotation = quaternions[0, i].tolist()
    blob.gltf.animations.append(gl.Animation(name=ANIMATION, samplers=samplers, channels=channels))


def _surroundings(blob: _Blob, recording: Recording) -> None:
    """Nodes of the floor and of each wall the page draws (:func:`scenery`), as flat polygons."""
    view, scene = scenery(recording), recording.scene
    _polygon(blob, "floor", view.floor, np.asarray(scene.ground.normal),
             blob.material("floor", colour=TABLE_COLOUR))
    if not view.walls:
        return
    material = blob.material("wall", colour=WALL_COLOUR)
    for k, corners in view.walls.items():
        _polygon(blob, f"wall {k}", corners, np.asarray(scene.walls[k].normal), material)


def _polygon(blob: _Blob, name: str, corners: np.ndarray, normal: np.ndarray,
             material: int) -> None:
    """A node of the convex polygon ``corners`` (K, 3): a fan counter-clockwise about ``normal``."""
    fan = np.cross(corners[1:-1] - corners[0], corners[2:] - corners[0]).sum(axis=0)
    if fan @ normal < 0:
        corners = corners[::-1]
    triangles = np.array([(0, i, i + 1) for i in range(1, len(corners) - 1)])
    mesh = blob.mesh(name, corners, np.tile(normal, (len(corners), 1)), triangles, material)
    blob.gltf.nodes.append(gl.Node(name=name, mesh=mesh))
