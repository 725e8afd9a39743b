"""See a throw: an interactive 3D page of recorded throws, and their export for game engines.

:func:`record` simulates and records throws; :func:`write_html` writes a self-contained page
of them (three.js bundled in; play, pause, slider, slow motion, orbit camera),
:func:`write_glb` a binary glTF 2.0 of one (meshes with their labels, the motion as an
animation); both carry the recording, so :func:`replay` throws it again and checks
the faces. :func:`load` takes a file as data: anything that is not a whole, consistent
recording is a :class:`RecordingError`. ``python -m dice_env.viewer --help`` writes a page
from the command line.
"""

from pathlib import Path

from dice_env.viewer.files import RecordingError, ReplayError, load, replay, save
from dice_env.viewer.html import write_html
from dice_env.viewer.recording import FPS, Recording, record


def write_glb(recording: Recording, path: str | Path) -> Path:
    """:func:`dice_env.viewer.gltf.write_glb` (needs pygltflib: the ``gltf`` extra)."""
    from dice_env.viewer.gltf import write_glb as write

    return write(recording, path)


__all__ = ["FPS", "Recording", "RecordingError", "ReplayError", "load", "record", "replay",
           "save", "write_glb", "write_html"]
