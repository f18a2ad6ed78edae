"""Vessels and packages: mugs, tumblers, bowls, jars, bottles, food boxes and containers.

Frames as in the catalogue: origin at the centre of the body's bottom face, +x front (away
from the robot), +y left, +z up; handles on the back (-x), towards the robot. Round vessels
are modelled with upright walls (a flared wall pivots between the pads: see README, suite
extra) of the sampled thickness: an open top's `size` is the opening inside the walls.
Masses are the solid material's volume times the instance's density, plus any contents.
"""

from __future__ import annotations

from typing import Any

from utamp_gym.kitchenware.params import (
    Built,
    Family,
    Instance,
    Param,
    box_volume,
    cuboid,
    cup,
    cup_inside,
    cylinder,
    disc,
    even,
    m,
)

#: the bars of a loop handle (the simulator's `sim.bodies.BAR`), for its volume
HANDLE_BAR = 0.008
SIDES = ("left", "right", "front", "back")


def sides(shape: str) -> dict[str, dict[str, Any]]:
    return {s: {"shape": shape} for s in SIDES}


def centred(size: float) -> dict[str, Any]:
    return {"size": [m(size), m(size)], "center": [0.0, 0.0]}


# ------------------------------------------------------------------ mug
def _mug(i: Instance) -> Built:
    r, h, wall = m(i["diameter"] / 2), i["height"], i["wall"]
    reach, hw, bottom = i["handle_reach"], even(i["handle_width"]), i["handle_bottom"]
    top = min(bottom + i["handle_height"], h - 0.006)
    table = {
        "description": f"{i.material} mug with a loop handle on its back; open top",
        "members": {
            "body": {"kind": "body", **cylinder(r, 0.0, h)},
            "handle": {
                "kind": "handle",
                **cuboid((-r - reach, -hw / 2, bottom), (-r, hw / 2, top)),
            },
        },
        "parts": {
            "on": {"shape": "open", **centred(2 * r - 2 * wall)},
            "under": {"shape": "flat", **centred(2 * r)},
            **sides("round"),
        },
    }
    handle = (2 * reach + (top - bottom)) * HANDLE_BAR * hw
    return Built(table, cup(r, h, wall, i["floor"]) + handle)


MUG = Family(
    name="mug",
    summary="mugs with a loop handle (ceramic, glass, enamelled steel)",
    doc="A cylindrical cup with an open top and a C-shaped loop handle on its back: "
    "grasped around its body when it fits the hand, else by the handle.",
    materials=(("ceramic", 0.65), ("glass", 0.25), ("steel", 0.10)),
    params=(
        Param("diameter", 72, 88, "mm", "outer diameter", "mug", real=(72, 90)),
        Param("height", 80, 110, "mm", "height", "mug", real=(80, 115)),
        Param("wall", 3, 6, "mm", "wall thickness", "mug", materials=("ceramic",)),
        Param("wall", 2.5, 4, "mm", "wall thickness", "tumbler", materials=("glass",)),
        Param("wall", 0.8, 1.5, "mm", "wall thickness (enamelled sheet)", "mixing-bowl",
              materials=("steel",)),
        Param("floor", 5, 10, "mm", "floor thickness (mass only)", "mug"),
        Param("handle_reach", 24, 34, "mm", "how far the handle stands out of the body", "mug"),
        Param("handle_height", 48, 70, "mm", "handle height", "mug"),
        Param("handle_width", 9, 15, "mm", "handle width (across the fingers)", "mug"),
        Param("handle_bottom", 12, 25, "mm", "height of the handle's lower end", "mug"),
    ),
    build=_mug,
    sources=("mug", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ tumbler
def _tumbler(i: Instance) -> Built:
    r, h, wall = m(i["diameter"] / 2), i["height"], i["wall"]
    table = {
        "description": f"{i.material} tumbler (a cup without handle); open top",
        "members": {"body": {"kind": "body", **cylinder(r, 0.0, h)}},
        "parts": {
            "on": {"shape": "open", **centred(2 * r - 2 * wall)},
            "under": {"shape": "flat"},
            **sides("round"),
        },
    }
    return Built(table, cup(r, h, wall, i["floor"]))


TUMBLER = Family(
    name="tumbler",
    summary="drinking glasses and cups without a handle",
    doc="An open cylinder on a heavy base, grasped around its body.",
    materials=(("glass", 0.6), ("plastic", 0.25), ("steel", 0.15)),
    params=(
        Param("diameter", 58, 80, "mm", "outer diameter", "tumbler", real=(58, 85)),
        Param("height", 85, 140, "mm", "height", "tumbler", real=(85, 150)),
        Param("wall", 2, 4, "mm", "wall thickness", "tumbler", materials=("glass",)),
        Param("wall", 1.5, 3, "mm", "wall thickness", "tumbler", materials=("plastic",)),
        Param("wall", 0.6, 1, "mm", "wall thickness", "tumbler", materials=("steel",)),
        Param("floor", 5, 15, "mm", "base thickness (mass only)", "tumbler"),
    ),
    build=_tumbler,
    sources=("tumbler", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ bowl
def _bowl(i: Instance) -> Built:
    r, h, wall = m(i["diameter"] / 2), i["height"], i["wall"]
    depth = min(i["rim_depth"], h - i["floor"] - 0.005)
    half = min(0.04, 0.4 * r)
    table = {
        "description": f"{i.material} bowl with upright walls; pinched at its rim",
        "members": {
            "body": {"kind": "body", **cylinder(r, 0.0, h)},
            "rim-front": {"kind": "edge", **cuboid((r - wall, -half, h - depth), (r, half, h))},
            "rim-back": {"kind": "edge", **cuboid((-r, -half, h - depth), (-r + wall, half, h))},
        },
        "parts": {"on": {"shape": "open", **centred(2 * r - 2 * wall)},
                  "under": {"shape": "flat"}, **sides("round")},
    }  # fmt: skip
    # a real bowl is rounded: about 3/4 of the material of the upright-walled cylinder
    return Built(table, 0.75 * cup(r, h, wall, i["floor"]))


BOWL = Family(
    name="bowl",
    summary="soup, cereal and mixing bowls (ceramic, melamine, steel)",
    doc="An open round vessel too wide to wrap the hand around, pinched at its rim: the "
    "rim's front and back are edge members, as thick as the wall.",
    materials=(("ceramic", 0.5), ("plastic", 0.3), ("steel", 0.2)),
    params=(
        Param("diameter", 110, 180, "mm", "outer diameter", "dinnerware", real=(110, 300)),
        Param("height", 45, 85, "mm", "height", "dinnerware", real=(45, 140)),
        Param("wall", 5, 8, "mm", "wall thickness (stoneware)", "dinnerware",
              materials=("ceramic",)),
        Param("wall", 4, 6, "mm", "wall thickness (melamine)", "mixing-bowl",
              materials=("plastic",)),
        Param("wall", 1.1, 1.5, "mm", "wall thickness (rolled rim)", "mixing-bowl",
              materials=("steel",)),
        Param("floor", 4, 7, "mm", "floor thickness (mass only)", "dinnerware",
              materials=("ceramic", "plastic")),
        Param("floor", 1.0, 1.5, "mm", "floor thickness (mass only)", "mixing-bowl",
              materials=("steel",)),
        Param("rim_depth", 20, 35, "mm", "height of the rim band declared as edges", "robot"),
    ),
    build=_bowl,
    sources=("dinnerware", "mixing-bowl", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ jar
def _jar(i: Instance) -> Built:
    r, hb, wall = m(i["diameter"] / 2), i["body_height"], i["wall"]
    rl = m(r - i["shoulder"])  # a wider lid (shoulder < 0) overhangs the body
    top = hb + i["lid_height"]
    table = {
        "description": f"{i.material} jar with a screw lid, filled {i['fill']:.0%}",
        "members": {
            "body": {"kind": "body", **cylinder(r, 0.0, hb)},
            "lid": {"kind": "handle", **cylinder(rl, hb, top)},
        },
        "parts": {"on": {"shape": "flat", **centred(2 * rl)}, "under": {"shape": "flat"},
                  **sides("round")},
    }  # fmt: skip
    lid = disc(rl, 0.001) * 7900 / i.density  # a 1 mm steel lid, as solid-material volume
    contents = i["fill"] * cup_inside(r, hb, wall, wall) * i["contents_density"]
    return Built(table, cup(r, hb, wall, 1.5 * wall) + lid, contents)


JAR = Family(
    name="jar",
    summary="screw-lid jars (jam, preserves, dry goods)",
    doc="A closed cylinder under a narrower screw lid: the hand takes the lid from above "
    "(the lid stands over the body), the lid's top carries small things.",
    materials=(("glass", 0.85), ("plastic", 0.15)),
    params=(
        Param("diameter", 55, 95, "mm", "body diameter", "jar", real=(55, 115)),
        Param("body_height", 60, 150, "mm", "height to the lid", "jar", real=(60, 240)),
        Param("wall", 2.5, 4, "mm", "wall thickness", "jar", materials=("glass",)),
        Param("wall", 1, 2, "mm", "wall thickness", "container", materials=("plastic",)),
        Param("shoulder", -3, 8, "mm", "how far the lid is set in from the body (< 0: wider)",
              "jar"),
        Param("lid_height", 12, 25, "mm", "lid height", "jar"),
        Param("fill", 0.4, 1.0, "fraction", "filled fraction", "jar"),
        Param("contents_density", 600, 1350, "kg/m3", "contents density", "jar"),
    ),
    build=_jar,
    sources=("jar", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ bottle
def _bottle(i: Instance) -> Built:
    r, hb, wall = m(i["diameter"] / 2), i["body_height"], i["wall"]
    rn = m(i["neck_diameter"] / 2)
    table = {
        "description": f"{i.material} bottle with a narrow neck, filled {i['fill']:.0%}",
        "members": {
            "body": {"kind": "body", **cylinder(r, 0.0, hb)},
            "neck": {"kind": "handle", **cylinder(rn, hb, hb + i["neck_height"])},
        },
        "parts": {"on": {"shape": "pointy"}, "under": {"shape": "flat"}, **sides("round")},
    }
    neck = (disc(rn, 1.0) - disc(rn - wall, 1.0)) * i["neck_height"]
    solid = cup(r, hb, wall, 2 * wall) + disc(rn, wall) + neck
    contents = i["fill"] * cup_inside(r, hb, wall, 2 * wall) * i["contents_density"]
    return Built(table, solid, contents)


BOTTLE = Family(
    name="bottle",
    summary="bottles of oil, vinegar, wine or water",
    doc="A cylindrical body under a narrow neck: grasped by the neck only (the neck stands "
    "over the body); nothing rests on its pointy top.",
    materials=(("glass", 0.65), ("plastic", 0.35)),
    params=(
        Param("diameter", 55, 80, "mm", "body diameter", "bottle", real=(55, 90)),
        Param("body_height", 140, 210, "mm", "height to the shoulder", "bottle",
              real=(140, 240)),
        Param("neck_diameter", 24, 34, "mm", "neck diameter", "bottle"),
        Param("neck_height", 50, 85, "mm", "neck and shoulder height", "bottle"),
        Param("wall", 2.5, 4, "mm", "wall thickness", "bottle", materials=("glass",)),
        Param("wall", 0.4, 0.9, "mm", "wall thickness (PET)", "bottle", materials=("plastic",)),
        Param("fill", 0.3, 1.0, "fraction", "filled fraction", "bottle"),
        Param("contents_density", 900, 1030, "kg/m3", "oil, wine, water", "bottle"),
    ),
    build=_bottle,
    sources=("bottle", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ food box
def _box(i: Instance) -> Built:
    size = (even(i["length"]), even(i["width"]), i["height"])
    lx, ly, h = size
    table = {
        "description": "cardboard box of dry food",
        "members": {
            "body": {"kind": "body", **cuboid((-lx / 2, -ly / 2, 0.0), (lx / 2, ly / 2, h))}
        },
        "parts": {"on": {"shape": "flat"}, "under": {"shape": "flat"}, **sides("flat")},
    }
    shell = 2 * (lx * ly + lx * h + ly * h) * i["board"]
    return Built(table, shell, i["fill"] * box_volume(size) * i["contents_density"])


BOX = Family(
    name="food-box",
    summary="folding-carton boxes of tea, crackers or pasta",
    doc="A closed cardboard box, grasped across its width from above.",
    materials=(("cardboard", 1.0),),
    params=(
        Param("length", 90, 200, "mm", "length (front to back)", "box", real=(90, 300)),
        Param("width", 40, 75, "mm", "width (across the fingers)", "box", real=(40, 120)),
        Param("height", 60, 170, "mm", "height", "box", real=(60, 300)),
        Param("board", 0.4, 0.8, "mm", "boxboard thickness", "box"),
        Param("fill", 0.5, 0.95, "fraction", "filled fraction", "box"),
        Param("contents_density", 150, 600, "kg/m3", "bulk density of the contents", "box"),
    ),
    build=_box,
    sources=("box", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ food container
def _container(i: Instance) -> Built:
    size = (even(i["length"]), even(i["width"]), i["height"])
    lx, ly, h = size
    wall = i["wall"]
    table = {
        "description": f"{i.material} food container with a flat lid",
        "members": {
            "body": {"kind": "body", **cuboid((-lx / 2, -ly / 2, 0.0), (lx / 2, ly / 2, h))}
        },
        "parts": {"on": {"shape": "flat"}, "under": {"shape": "flat"}, **sides("flat")},
    }
    shell = 2 * (lx * ly + lx * h + ly * h) * wall
    inside = (lx - 2 * wall) * (ly - 2 * wall) * (h - 2 * wall)
    return Built(table, shell, i["fill"] * inside * i["contents_density"])


CONTAINER = Family(
    name="container",
    summary="lidded food storage containers",
    doc="A closed rectangular container with a flat lid (carries small things), grasped "
    "across its width.",
    materials=(("plastic", 0.8), ("glass", 0.2)),
    params=(
        Param("length", 110, 200, "mm", "length (front to back)", "container", real=(110, 260)),
        Param("width", 55, 76, "mm", "width (across the fingers)", "container", real=(55, 180)),
        Param("height", 45, 100, "mm", "height", "container"),
        Param("wall", 1, 2, "mm", "wall thickness", "container", materials=("plastic",)),
        Param("wall", 3, 4.5, "mm", "wall thickness", "container", materials=("glass",)),
        Param("fill", 0.0, 0.8, "fraction", "filled fraction", "container"),
        Param("contents_density", 500, 1050, "kg/m3", "leftovers, soup, rice", "container"),
    ),
    build=_container,
    sources=("container", "materials"),
)  # fmt: skip

__all__ = ["BOTTLE", "BOWL", "BOX", "CONTAINER", "JAR", "MUG", "TUMBLER", "centred", "sides"]
