"""Cookware: frying pans, saucepans and stock pots (steel, aluminium, cast iron).

A frying pan's top is concave (its cooking surface: objects that span it rest on its rim)
and its walls flare from a flat floor; saucepans and pots are open with upright walls. Long
handles stand out of the back at the rim, a pot's two lugs out of its left and right sides.
Handle volumes count a solid fraction (tubular or stamped metal handles are hollow).
"""

from __future__ import annotations

import math

from utamp_gym.kitchenware.params import (
    Built,
    Family,
    Instance,
    Param,
    cuboid,
    cup,
    cylinder,
    disc,
    even,
    m,
)
from utamp_gym.kitchenware.vessels import centred, sides


def _long_handle(i: Instance, r: float, top: float) -> tuple[dict[str, object], float]:
    length, width, thick = i["handle_length"], even(i["handle_width"]), i["handle_thickness"]
    box = cuboid((-r - length, -width / 2, top - thick), (-r, width / 2, top))
    return {"kind": "handle", **box}, length * width * thick * i["handle_fill"]


# ------------------------------------------------------------------ frying pan
def _frying_pan(i: Instance) -> Built:
    r, h, wall = m(i["diameter"] / 2), i["height"], i["wall"]
    rb = m(r - i["flare"])
    handle, handle_volume = _long_handle(i, r, h)
    table = {
        "description": f"{i.material} frying pan: a concave cooking surface, a long handle on "
        "its back",
        "members": {"body": {"kind": "body", **cylinder(r, 0.0, h)}, "handle": handle},
        "parts": {"on": {"shape": "concave", **centred(2 * r - 2 * wall)},
                  "under": {"shape": "flat", **centred(2 * rb)}, **sides("round")},
    }  # fmt: skip
    slant = math.hypot(r - rb, h)
    solid = disc(rb, 1.5 * wall) + math.pi * (r + rb) * slant * wall + handle_volume
    return Built(table, solid)


_HANDLE = (
    Param("handle_fill", 0.4, 0.9, "fraction", "solid fraction of the handle's box", "skillet",
          materials=("steel", "aluminium")),
    Param("handle_fill", 0.8, 1.0, "fraction", "solid fraction of the handle's box", "skillet",
          materials=("cast-iron",)),
)  # fmt: skip

FRYING_PAN = Family(
    name="frying-pan",
    summary="frying pans and skillets (steel, aluminium, cast iron)",
    doc="A shallow pan whose walls flare from a flat floor, with a long handle at the rim. "
    "Its concave top carries only what spans it; the handle is the only grasp.",
    materials=(("aluminium", 0.45), ("steel", 0.35), ("cast-iron", 0.20)),
    params=(
        Param("diameter", 180, 260, "mm", "rim diameter", "skillet", real=(150, 380)),
        Param("height", 35, 60, "mm", "rim height", "skillet"),
        Param("flare", 12, 30, "mm", "how far the rim stands out of the floor", "skillet"),
        Param("wall", 2, 3.5, "mm", "wall thickness", "skillet",
              materials=("steel", "aluminium")),
        Param("wall", 3.5, 5, "mm", "wall thickness", "skillet", materials=("cast-iron",)),
        Param("handle_length", 110, 190, "mm", "handle length", "skillet", real=(110, 250)),
        Param("handle_width", 20, 32, "mm", "handle width (across the fingers)", "skillet"),
        Param("handle_thickness", 10, 20, "mm", "handle thickness", "skillet"),
        *_HANDLE,
    ),
    build=_frying_pan,
    sources=("skillet", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ saucepan
def _saucepan(i: Instance) -> Built:
    r, h, wall = m(i["diameter"] / 2), i["height"], i["wall"]
    handle, handle_volume = _long_handle(i, r, h - i["handle_drop"])
    table = {
        "description": f"{i.material} saucepan: open, upright walls, a long handle on its back",
        "members": {"body": {"kind": "body", **cylinder(r, 0.0, h)}, "handle": handle},
        # the flat bottom is the body's: without a size the bounding box (the handle
        # included) would centre what stands on the upside-down pan beyond its body
        "parts": {"on": {"shape": "open", **centred(2 * r - 2 * wall)},
                  "under": {"shape": "flat", **centred(2 * r)}, **sides("round")},
    }  # fmt: skip
    return Built(table, cup(r, h, wall, 2 * wall) + handle_volume)


SAUCEPAN = Family(
    name="saucepan",
    summary="saucepans with one long handle",
    doc="An open pot with upright walls and one long handle just below its rim; its flat "
    "bottom carries things when it stands upside down.",
    materials=(("steel", 0.6), ("aluminium", 0.4)),
    params=(
        Param("diameter", 140, 200, "mm", "diameter", "saucepan", real=(140, 240)),
        Param("height", 70, 115, "mm", "height", "saucepan", real=(70, 140)),
        Param("wall", 0.8, 2.5, "mm", "wall thickness", "saucepan"),
        Param("handle_length", 130, 190, "mm", "handle length", "saucepan"),
        Param("handle_width", 18, 28, "mm", "handle width (across the fingers)", "saucepan"),
        Param("handle_thickness", 8, 15, "mm", "handle thickness", "saucepan"),
        Param("handle_drop", 0, 12, "mm", "handle top below the rim", "saucepan"),
        Param("handle_fill", 0.4, 0.9, "fraction", "solid fraction of the handle's box",
              "saucepan"),
    ),
    build=_saucepan,
    sources=("saucepan", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ stock pot
def _stock_pot(i: Instance) -> Built:
    r, h, wall = m(i["diameter"] / 2), i["height"], i["wall"]
    reach, width, thick = i["lug_reach"], even(i["lug_width"]), i["lug_thickness"]
    top = h - i["lug_drop"]
    lugs = {
        f"handle-{side}": {
            "kind": "handle",
            **cuboid((-width / 2, lo, top - thick), (width / 2, hi, top)),
        }
        for side, lo, hi in (("left", r, r + reach), ("right", -r - reach, -r))
    }
    table = {
        "description": f"{i.material} pot: open, upright walls, a lug handle on each side",
        "members": {"body": {"kind": "body", **cylinder(r, 0.0, h)}, **lugs},
        "parts": {"on": {"shape": "open", **centred(2 * r - 2 * wall)},
                  "under": {"shape": "flat"}, **sides("round")},
    }  # fmt: skip
    return Built(table, cup(r, h, wall, 2 * wall) + 2 * reach * width * thick * 0.6)


STOCK_POT = Family(
    name="stock-pot",
    summary="pots and casseroles with two lug handles",
    doc="An open pot with upright walls and a lug handle on each side, grasped by a lug; "
    "upside down its flat bottom carries things.",
    materials=(("steel", 0.6), ("aluminium", 0.4)),
    params=(
        Param("diameter", 140, 210, "mm", "diameter", "stock-pot", real=(140, 300)),
        Param("height", 90, 150, "mm", "height", "stock-pot", real=(90, 250)),
        Param("wall", 0.8, 2.5, "mm", "wall thickness", "stock-pot"),
        Param("lug_reach", 22, 40, "mm", "how far a lug stands out", "stock-pot"),
        Param("lug_width", 30, 50, "mm", "lug width (across the fingers)", "stock-pot"),
        Param("lug_thickness", 10, 18, "mm", "lug thickness", "stock-pot"),
        Param("lug_drop", 5, 25, "mm", "lug top below the rim", "stock-pot"),
    ),
    build=_stock_pot,
    sources=("stock-pot", "materials"),
)  # fmt: skip

__all__ = ["FRYING_PAN", "SAUCEPAN", "STOCK_POT"]
