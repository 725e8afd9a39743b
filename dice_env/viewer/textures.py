"""Texture atlases of the dice's faces, drawn unlit as :mod:`dice_env.envs.render` draws them."""

from __future__ import annotations

import io
import math
from functools import lru_cache

import numpy as np

from dice_env.envs.render import FACE_COLOUR, RIM_WIDTH, face_art, face_colour
from dice_env.model.checks import check_int, check_type
from dice_env.model.die import Die

SUPERSAMPLE = 3  # subpixels a side averaged into one texture pixel (antialiasing)
PADDING = 1 / 32  # a tile's margin around its face's square, in tile widths (against bleeding)
CHUNK = 1 << 14  # subpixels drawn at once (bounds the memory of the numerals' distances)


@lru_cache(maxsize=64)
def face_atlas(die: Die, pixels: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """The texture atlas of ``die``'s faces and the texture coordinates of their corners.

    ``image``: opaque RGBA uint8, the faces in label order row by row in ``ceil(sqrt(F))``
    columns, each a square tile ``pixels`` (>= 8) a side. ``uv`` (F, P, 2): ``uv[k, i]`` the
    texture coordinate (origin top left, v down) of corner ``die.faces[k][i]``, NaN past a
    face's corners. Cached, both read-only.
    """
    check_type("die", die, Die)
    check_int("pixels", pixels, 8)
    arts, vertices = face_art(die), np.asarray(die.vertices)
    columns = math.ceil(math.sqrt(len(arts)))
    rows = -(-len(arts) // columns)
    sub = pixels * SUPERSAMPLE
    canvas = np.full((rows * sub, columns * sub, 3), FACE_COLOUR)
    uv = np.full((len(arts), max(len(face) for face in die.faces), 2), np.nan)
    for k, (art, face) in enumerate(zip(arts, die.faces, strict=True)):
        flat = (vertices[list(face)] - art.centre) @ art.axes.T
        middle = (flat.min(axis=0) + flat.max(axis=0)) / 2
        span = float(np.ptp(flat, axis=0).max()) * (1 + 2 * PADDING)  # the tile's side (m)
        step = span / sub
        offsets = (np.arange(sub) + 0.5) * step - span / 2
        us, vs = np.meshgrid(middle[0] + offsets, middle[1] - offsets)  # image rows go down
        points = np.column_stack([us.ravel(), vs.ravel()])
        colour = np.concatenate([face_colour(art, points[i:i + CHUNK], 1.0,
                                              RIM_WIDTH * die.size, step)
                                 for i in range(0, len(points), CHUNK)])
        row, column = divmod(k, columns)
        canvas[row * sub:(row + 1) * sub, column * sub:(column + 1) * sub] = \
            colour.reshape(sub, sub, 3)
        tile = (flat - middle) * (1.0, -1.0) / span + 0.5  # corners in the tile, v down
        uv[k, :len(face)] = (tile + np.array([column, row])) / (columns, rows)
    rgb = canvas.reshape(rows * pixels, SUPERSAMPLE, columns * pixels, SUPERSAMPLE, 3)
    rgb = np.clip(rgb.mean(axis=(1, 3)).round(), 0, 255).astype(np.uint8)
    image = np.concatenate([rgb, np.full((*rgb.shape[:2], 1), 255, np.uint8)], axis=2)
    image.flags.writeable = uv.flags.writeable = False
    return image, uv


def png_bytes(image: np.ndarray) -> bytes:
    """The PNG encoding of ``image``: (H, W, 3) RGB or (H, W, 4) RGBA uint8."""
    from PIL import Image

    image = np.asarray(image)
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] not in (3, 4):
        raise ValueError("image must be an (H, W, 3) or (H, W, 4) uint8 array, got "
                         f"{image.dtype} {image.shape}")
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG")
    return buffer.getvalue()
