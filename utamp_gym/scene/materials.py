"""Materials of kitchenware: density, friction, robustness and how they look.

One table read by every layer that needs a material's physics or appearance: the
procedural generator (mass = density x volume, robustness), the simulator (friction,
colour and finish of each instance) and perception (material from appearance, mass
from a perceived volume). Names are what a catalogue type's ``material`` field holds;
an unknown material falls back to `DEFAULT`.

Sources (bulk densities of the solid material, room temperature):

* wood: USDA Forest Products Laboratory, *Wood Handbook* (FPL-GTR-190, 2010), Table 5-3a:
  kitchen hardwoods at 12 % moisture, beech 0.64-0.72, maple 0.63-0.70, oak 0.63-0.75,
  teak 0.66, jatoba/ipe 0.9-1.1 g/cm^3;
* glass: soda-lime container glass 2.44-2.53 g/cm^3; borosilicate 2.23 g/cm^3
  (Corning 7740 data sheet);
* ceramic: porcelain 2.3-2.5, stoneware 2.2-2.4 g/cm^3 (glazed tableware);
* steel: stainless 18/10 (AISI 304) 7.9-8.0 g/cm^3; carbon steel 7.85 g/cm^3;
* cast iron: grey cast iron 6.9-7.35 g/cm^3 (ASM Handbook, vol. 1);
* aluminium: 1xxx/3xxx series cookware alloys 2.70-2.73 g/cm^3;
* plastic: polypropylene 0.90-0.91, HDPE 0.94-0.97, melamine 1.5 g/cm^3 (PP/PE kitchen
  containers and boards);
* cardboard: folding boxboard 0.6-0.8 g/cm^3 (as a solid sheet).

Wall thicknesses (`Material.wall`) are those of typical pieces: drinking glass and
glassware 2.5-4 mm, glazed stoneware and porcelain 4-6 mm, stainless cookware 0.6-3 mm
(single-ply pots to tri-ply pans), cast iron 4-5 mm, aluminium cookware 2-4 mm, injection-
moulded PP/PE containers 1.5-2.5 mm, folding boxboard 0.4-1 mm; wooden boards, trays and
utensils are cut or carved solid.

Friction coefficients are the simulator's sliding friction against the table and the
Panda's fingers (dry contact, the order of published static coefficients: wood on wood
0.25-0.5, glass on glass 0.4-0.9, steel on steel 0.5-0.8 dry, lower once polished). Each
palette entry is a hex RGBA colour seen on real pieces of that material; palettes
overlap on purpose (white ceramic and white plastic, brown wood, cardboard and
terracotta, grey steel and grey plastic), so colour alone does not decide the material:
the finish (specular highlight, shininess, mirror reflectance) differs.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import NamedTuple


class Finish(NamedTuple):
    """How a surface reflects light; MuJoCo material attributes, each in [0, 1]."""

    specular: float
    shininess: float
    reflectance: float


class Material(NamedTuple):
    """Physical and visual properties of one material."""

    name: str
    density: float  # kg/m^3, nominal
    density_range: tuple[float, float]  # kg/m^3, what real pieces span
    friction: float  # sliding friction coefficient in the simulator
    robustness: str  # fragile | sturdy | solid: the load a piece of it carries
    palette: tuple[str, ...]  # hex RGBA colours
    finish: Finish
    translucent: bool = False
    #: typical wall or sheet thickness (m) of kitchenware made of it; None: solid pieces
    #: (carved or cut wood). Perception estimates a mass from it (`perception.material`).
    wall: float | None = None


MATERIALS: MappingProxyType[str, Material] = MappingProxyType(
    {
        m.name: m
        for m in (
            Material(
                "wood", 700.0, (450.0, 1100.0), 0.5, "sturdy",
                ("8c572bff", "dbb073ff", "b3804dff", "6e4423ff", "c89f6bff"),
                Finish(0.1, 0.1, 0.0),
            ),
            Material(
                "glass", 2500.0, (2230.0, 2530.0), 0.45, "fragile",
                ("9ed1f2cc", "b8f2cccc", "e6f2f2b3", "a6bfa6cc"),
                Finish(0.9, 0.9, 0.15), translucent=True, wall=0.003,
            ),
            Material(
                "ceramic", 2350.0, (2200.0, 2500.0), 0.45, "fragile",
                ("f2efe6ff", "e6e1d1ff", "3d5a8cff", "b85c38ff", "7a9e7eff"),
                Finish(0.6, 0.7, 0.05), wall=0.005,
            ),
            Material(
                "steel", 7900.0, (7850.0, 8000.0), 0.4, "sturdy",
                ("38383fff", "9e9eadff", "c4c6ccff", "7d7f86ff"),
                Finish(1.0, 0.8, 0.3), wall=0.0015,
            ),
            Material(
                "cast-iron", 7200.0, (6900.0, 7350.0), 0.45, "solid",
                ("26262bff", "33302eff", "1c1c1fff"),
                Finish(0.3, 0.3, 0.02), wall=0.004,
            ),
            Material(
                "aluminium", 2700.0, (2700.0, 2730.0), 0.4, "sturdy",
                ("b4b8bfff", "d2d5daff", "8f949cff"),
                Finish(0.7, 0.6, 0.15), wall=0.0025,
            ),
            Material(
                "plastic", 930.0, (900.0, 1500.0), 0.4, "sturdy",
                ("f2f2f0ff", "d94040ff", "408cd9ff", "f2bf33ff", "4db366ff", "9e9eadff"),
                Finish(0.3, 0.4, 0.0), wall=0.002,
            ),
            Material(
                "cardboard", 700.0, (600.0, 800.0), 0.55, "fragile",
                ("b08a5cff", "c9a678ff", "e8e0d0ff", "d94040ff", "3d5a8cff"),
                Finish(0.05, 0.05, 0.0), wall=0.0008,
            ),
        )
    }
)  # fmt: skip
#: what an unknown material is simulated as
DEFAULT = Material(
    "default", 1000.0, (500.0, 8000.0), 0.5, "sturdy",
    ("d94040ff", "408cd9ff", "f2bf33ff", "804db3ff", "4db366ff", "e680b3ff"),
    Finish(0.5, 0.5, 0.0), wall=0.003,
)  # fmt: skip


def material(name: str) -> Material:
    """The material called `name`, or `DEFAULT` (so scene files may name any material)."""
    return MATERIALS.get(name, DEFAULT)


def hex_rgba(colour: str) -> tuple[float, float, float, float]:
    """``"8c572bff"`` -> (r, g, b, a) in [0, 1]."""
    r, g, b, a = (int(colour[i : i + 2], 16) / 255 for i in range(0, 8, 2))
    return (r, g, b, a)


__all__ = ["DEFAULT", "MATERIALS", "Finish", "Material", "hex_rgba", "material"]
