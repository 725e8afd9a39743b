"""See a throw: an interactive 3D page of recorded throws, and their export for game engines.

:func:`record` simulates and records throws; :func:`write_html` writes a self-contained page
of them (three.js bundled in; play, pause, slider, slow motion, orbit camera),
:func:`write_glb` a binary glTF 2.0 of one (meshes with their labels, the motion as an
animation); both carry the recording, so :func:`replay` throws it again and checks the
faces. ``python -m dice_env.viewer --help`` writes a page from the command line.
"""

from dice_env.viewer.recording import FPS, Recording, ReplayError, load, record, replay, save

__all__ = ["FPS", "Recording", "ReplayError", "load", "record", "replay", "save"]
