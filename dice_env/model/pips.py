"""Drilled pips on the d6: spherical-cap cavities, empty or filled flush with paint.

``Die.standard("d6", pips=...)`` takes a :class:`Pips` or a preset of :data:`DRILLINGS`: the
geometry stays the cube's, the mass properties are the cube's minus its 21 cavities (plus the
paint of casino dice).

**Layout** (:func:`layout`): pips at 0 or ``±offset`` times the half-width along each face's
axes. With the 1 up, the 2 left and the 3 right, the 3's diagonal runs up from the left and the
2's down from the left (casino dice, dice-play.com), both ending at the 2-3-6 corner; the 6's
rows run along x (our choice). Each pattern is centrally symmetric, so the centre of mass moves
toward the 1-2-3 corner, 5 : 3 : 1 along z, x, y.

**Mass** (:func:`drill`): ``mass`` is the weighed mass. With ``n = 21`` cavities of volume
``V_c``, ``V = s^3`` and paint density ``rho_p`` (0: empty), the body's density is
``rho = (mass - rho_p n V_c) / (V - n V_c)``; each cavity adds a signed mass
``(rho_p - rho) V_c`` at its centroid with its own inertia (parallel-axis theorem).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from dice_env.model.checks import check_choice, check_nonnegative, check_positive, check_range
from dice_env.model.polyhedra import point_inertia

SHAPES = ("spherical cap",)
# Cellulose acetate, the body of casino dice (kg/m^3): AZoM, "Cellulose Acetate" (Plascams
# typical value); handbooks give 1270-1340 (Cardarelli, Materials Handbook, 2018).
CELLULOSE_ACETATE = 1280.0
# The smallest casino die edge (m): 0.750 in (gaming regulations allow 0.750-0.775 in).
CASINO_EDGE = 0.750 * 0.0254
# A paint density within this fraction of the body's leaves the uniform die (rounding).
SAME_DENSITY = 1e-12


@dataclass(frozen=True)
class Pips:
    """The pips of a d6: identical spherical-cap cavities in the standard layout.

    ``radius`` (m): the opening radius at the face; ``depth`` (m): in ``(0, radius]`` (at most
    a hemisphere); ``offset``: the off-centre pips' distance from the face centre along each
    face axis, a fraction in (0, 1) of the half-width; ``paint_density`` (kg/m^3): None (or 0)
    for empty pips, else a paint filling them flush; ``shape``: "spherical cap", the only one.
    """

    radius: float
    depth: float
    offset: float = 0.5
    paint_density: float | None = None
    shape: str = "spherical cap"

    def __post_init__(self) -> None:
        check_positive("radius", self.radius)
        check_range("depth", self.depth, 0.0, self.radius, low_open=True)
        check_range("offset", self.offset, 0.0, 1.0, low_open=True, high_open=True)
        if self.paint_density is not None:
            check_nonnegative("paint_density", self.paint_density)
        check_choice("shape", self.shape, SHAPES)


class Preset(NamedTuple):
    """A real die with pips: its :class:`Pips`, ``size`` (m), ``density`` and the sources.

    ``density`` (kg/m^3): mass over ``size^3``; None for either: the default d6's.
    """

    pips: Pips
    size: float | None
    density: float | None
    source: str


DRILLINGS = {
    "drilled16": Preset(
        Pips(radius=1.5e-3, depth=1.0e-3),
        None, None,
        "The default die (16 mm, 4.5 g) with drilled pips of 3 mm opening and 1 mm depth. "
        "These sizes are our estimate of common game dice, not a measured sample; they agree "
        "with common CAD models of a 16 mm die (e.g. Thingiverse thing 3493901, dice-v4.scad: "
        "pip spheres of radius 0.094 x edge = 1.5 mm, pips at a quarter of the edge from the "
        "centre = offset 0.5, depth 0.6 mm)."),
    "casino19": Preset(
        Pips(radius=2.25e-3, depth=1.0e-3, offset=0.55, paint_density=CELLULOSE_ACETATE),
        CASINO_EDGE, CELLULOSE_ACETATE,
        "A casino (craps) die: a cube of 0.750-0.775 in, transparent cellulose, spots drilled "
        "and filled flush 'with a compound equal in weight to the weight of the cellulose "
        "drilled out' (Michigan Admin. Code R 432.1814; Maryland COMAR 36.05.02.12, which "
        "also asks every spot to reach the same depth within 0.0004 in). Edge 0.750 in, body "
        "and paint of cellulose acetate (1.28 g/cm3, AZoM); the spot diameter 4.5 mm, depth "
        "1 mm and offset 0.55 are our estimates (the regulations give none)."),
}


def cap_properties(radius: float, depth: float) -> tuple[float, float, float, float]:
    """Volume and second moments of a spherical cap of opening ``radius`` a and ``depth`` h.

    Integrating disks ``r^2 = 2Rs - s^2`` at height ``s`` above the deepest point of a sphere
    of radius ``R = (a^2 + h^2) / (2h)``: ``V = pi h^2 (3R - h) / 3``, centroid height
    ``s_c = h (8R - 3h) / (4 (3R - h))``, axial moment
    ``I_a = (pi/2) (4R^2 h^3/3 - R h^4 + h^5/5)``, transverse moment about the centroid
    ``I_t = I_a / 2 + pi (R h^4 / 2 - h^5 / 5) - V s_c^2``. Returns ``V``, the centroid's
    depth ``h - s_c`` below the face, ``I_a`` and ``I_t``, the moments per unit density.
    """
    a, h = radius, depth
    r = (a * a + h * h) / (2 * h)
    volume = math.pi * h * h * (3 * r - h) / 3
    height = h * (8 * r - 3 * h) / (4 * (3 * r - h))
    axial = math.pi / 2 * (4 * r * r * h**3 / 3 - r * h**4 + h**5 / 5)
    transverse = axial / 2 + math.pi * (r * h**4 / 2 - h**5 / 5) - volume * height * height
    return volume, h - height, axial, transverse


def layout(offset: float = 0.5) -> dict[int, np.ndarray]:
    """Pip centres of each face label 1-6, (k, 3), body frame, in units of the half-width."""
    f = offset
    corners = [(u, v) for u in (f, -f) for v in (f, -f)]
    faces = {
        1: [(0, 0, 1)],
        2: [(1, -f, f), (1, f, -f)],
        3: [(f, 1, -f), (0, 1, 0), (-f, 1, f)],
        4: [(u, -1, v) for u, v in corners],
        5: [(-1, u, v) for u, v in corners] + [(-1, 0, 0)],
        6: [(x, y, -1) for x in (-f, 0, f) for y in (-f, f)],
    }
    return {label: np.array(points, dtype=np.float64) for label, points in faces.items()}


def with_defaults(name: str, pips: Pips | str, size: float | None, mass: float | None
                  ) -> tuple[Pips, float | None, float | None]:
    """The :class:`Pips` of ``pips`` (a preset name or a :class:`Pips`), with size and mass.

    A preset supplies a ``size`` or ``mass`` left None. Raises ValueError unless ``name`` is
    "d6".
    """
    if name != "d6":
        raise ValueError(f"pips are modelled on the d6 only, got name={name!r}")
    if isinstance(pips, Pips):
        return pips, size, mass
    if not isinstance(pips, str):
        raise TypeError(f"pips must be None, a Pips or a preset name, got {pips!r}")
    check_choice("pips", pips, DRILLINGS, also=" or a Pips")
    preset = DRILLINGS[pips]
    size = preset.size if size is None else size
    if mass is None and preset.density is not None and size is not None:
        check_positive("size", size)
        mass = preset.density * size**3
    return preset.pips, size, mass


def drill(size: float, mass: float, pips: Pips) -> tuple[np.ndarray, np.ndarray] | None:
    """The centre of mass and the inertia about it of a d6 of ``size`` drilled with ``pips``.

    ``mass`` is the weighed mass; None when the paint is as dense as the body. Raises
    ValueError when the pips overlap (``2 radius > offset size/2``), come nearer the face's
    edge than their depth (``offset size/2 + radius + depth > size/2``), or the paint alone
    outweighs ``mass``.
    """
    half = size / 2
    spacing = pips.offset * half
    if 2 * pips.radius > spacing:
        raise ValueError(f"pips overlap: 2 radius ({2e3 * pips.radius:g} mm) must be <= "
                         f"offset x size/2 ({1e3 * spacing:g} mm), the spacing of the 6's rows")
    if spacing + pips.radius + pips.depth > half:
        raise ValueError(f"pips reach the face's edge: offset x size/2 + radius + depth "
                         f"({1e3 * (spacing + pips.radius + pips.depth):g} mm) must be <= "
                         f"size/2 ({1e3 * half:g} mm)")
    volume, below, axial, transverse = cap_properties(pips.radius, pips.depth)
    centres = np.concatenate(list(layout(pips.offset).values()))
    normals = np.where(np.abs(centres) == 1.0, centres, 0.0)
    centroids = centres * half - below * normals
    n = len(centroids)
    outer = size**3
    paint = pips.paint_density or 0.0
    density = (mass - paint * n * volume) / (outer - n * volume)
    if density <= 0:
        raise ValueError(f"paint_density {paint} kg/m^3 fills the pips with more than the die's "
                         f"mass {mass} kg; the paint must weigh less than the die")
    change = paint - density
    if abs(change) <= SAME_DENSITY * density:
        return None
    com = change * volume * centroids.sum(axis=0) / mass
    along = np.einsum("ki,kj->ij", normals, normals)
    about_centre = (density * outer * size**2 / 6 * np.eye(3)
                    + change * (volume * sum(point_inertia(c) for c in centroids)
                                + transverse * (n * np.eye(3) - along) + axial * along))
    return com, about_centre - mass * point_inertia(com)
