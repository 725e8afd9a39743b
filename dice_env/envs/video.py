"""Save a throw's frames (from ``render_mode="rgb_array_list"``) as a GIF or an MP4."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from dice_env.disk import write_atomically
from dice_env.envs.dice_throw import RENDER_FPS


def save_video(frames: Sequence[np.ndarray], path: str | Path, fps: float = RENDER_FPS) -> Path:
    """Write ``frames`` (each H x W x 3 uint8) to ``path``; the suffix picks the format.

    ".gif" is written by Pillow; ".mp4" needs the ``video`` extra (imageio, imageio-ffmpeg).
    """
    path = Path(path)
    if not frames:
        raise ValueError("frames must hold at least one frame, got none")
    if path.suffix.lower() not in (".gif", ".mp4"):
        raise ValueError(f"path must end in .gif or .mp4, got {path.name!r}")
    if not fps > 0:
        raise ValueError(f"fps must be > 0, got {fps!r}")
    stack = np.stack([np.asarray(f, dtype=np.uint8) for f in frames])
    if path.suffix.lower() == ".gif":
        from PIL import Image

        first, *rest = (Image.fromarray(frame) for frame in stack)
        write_atomically(path, lambda f: first.save(f, format="GIF", save_all=True,
                                                    append_images=rest,
                                                    duration=1000.0 / fps, loop=0))
    else:
        try:
            import imageio.v3 as iio
            import imageio_ffmpeg  # noqa: F401
        except ImportError as error:
            raise ImportError("saving .mp4 needs the video extra: pip install "
                              "'dice_env[video]'; .gif works without it") from error
        iio.imwrite(path, stack, fps=fps, codec="libx264")
    return path
