"""Flat kitchenware: plates, boards, trays, sheet pans and flat utensils.

Their tops carry things: a plate's well inside its rim, a board's face, a tray's floor
inside its rims, a sheet pan's floor inside its lip. Food surfaces are never put face-down.
Rims and board edges are declared as edge members (what a perception model reports as the
places a hand may pinch); whether the hand can pinch them is the rules' and physics' call.
"""

from __future__ import annotations

from typing import Any

from utamp_gym.kitchenware.params import (
    Built,
    Family,
    Instance,
    Param,
    cuboid,
    cylinder,
    disc,
    even,
    m,
)
from utamp_gym.kitchenware.vessels import sides


def _slab(lx: float, ly: float, h: float) -> dict[str, Any]:
    return cuboid((-lx / 2, -ly / 2, 0.0), (lx / 2, ly / 2, h))


# ------------------------------------------------------------------ plate
def _plate(i: Instance) -> Built:
    r, h, well, rim = m(i["diameter"] / 2), i["height"], i["well_height"], i["rim_width"]
    half = min(0.04, 0.3 * r)
    table = {
        "description": f"{i.material} plate: a flat well inside a raised rim",
        "members": {
            "body": {"kind": "body", **cylinder(r, 0.0, h)},
            "rim-front": {"kind": "edge", **cuboid((r - rim, -half, well), (r, half, h))},
            "rim-back": {"kind": "edge", **cuboid((-r, -half, well), (-r + rim, half, h))},
        },
        "parts": {
            "on": {"shape": "flat", "size": [m(2 * (r - rim))] * 2, "height": m(well),
                   "food_surface": True},
            "under": {"shape": "flat"},
            **sides("round"),
        },
    }  # fmt: skip
    return Built(table, disc(r, i["thickness"]) * 1.2)  # the rim's slope adds about a fifth


PLATE = Family(
    name="plate",
    summary="dinner, salad and deep plates (ceramic, melamine)",
    doc="A round plate whose flat well lies inside a raised rim; food goes on its top "
    "(never face-down), it is pinched at its rim.",
    materials=(("ceramic", 0.75), ("plastic", 0.25)),
    params=(
        Param("diameter", 180, 270, "mm", "diameter", "dinnerware", real=(150, 330)),
        Param("height", 18, 35, "mm", "height of the rim", "dinnerware"),
        Param("well_height", 5, 10, "mm", "height of the well's surface", "dinnerware"),
        Param("rim_width", 20, 40, "mm", "width of the rim around the well", "dinnerware"),
        Param("thickness", 4, 7, "mm", "material thickness (mass only)", "dinnerware"),
    ),
    build=_plate,
    sources=("dinnerware", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ boards
def _board_parts(lx: float, ly: float) -> dict[str, Any]:
    face = {"size": [m(lx), m(ly)], "center": [0.0, 0.0]}
    return {"on": {"shape": "flat", **face, "food_surface": True},
            "under": {"shape": "flat", **face}, **sides("thin")}  # fmt: skip


def _paddle_board(i: Instance) -> Built:
    lx, ly, t = even(i["length"]), even(i["width"]), i["thickness"]
    hl, hw = i["handle_length"], even(i["handle_width"])
    table = {
        "description": f"{i.material} cutting board with a handle on its back",
        "members": {
            "body": {"kind": "body", **_slab(lx, ly, t)},
            "handle": {
                "kind": "handle",
                **cuboid((-lx / 2 - hl, -hw / 2, 0.0), (-lx / 2, hw / 2, t)),
            },
        },
        "parts": _board_parts(lx, ly),
    }
    return Built(table, lx * ly * t + hl * hw * t)


PADDLE_BOARD = Family(
    name="paddle-board",
    summary="cutting boards with a handle",
    doc="A flat board with a handle on its back: grasped by the handle; its top is a food "
    "surface that carries things.",
    materials=(("wood", 0.8), ("plastic", 0.2)),
    params=(
        Param("length", 200, 280, "mm", "board length without the handle", "cutting-board",
              real=(200, 450)),
        Param("width", 150, 250, "mm", "width", "cutting-board", real=(150, 300)),
        Param("thickness", 15, 30, "mm", "thickness", "cutting-board", real=(12, 40)),
        Param("handle_length", 60, 100, "mm", "handle length", "cutting-board"),
        Param("handle_width", 30, 55, "mm", "handle width (across the fingers)",
              "cutting-board"),
    ),
    build=_paddle_board,
    sources=("cutting-board", "materials"),
)  # fmt: skip


def _chopping_board(i: Instance) -> Built:
    lx, ly, t, e = even(i["length"]), even(i["width"]), i["thickness"], i["edge"]
    half = ly / 2 - 0.02
    table = {
        "description": f"{i.material} cutting board without a handle",
        "members": {
            "body": {"kind": "body", **_slab(lx, ly, t)},
            "edge-front": {"kind": "edge", **cuboid((lx / 2 - e, -half, 0.0), (lx / 2, half, t))},
            "edge-back": {"kind": "edge", **cuboid((-lx / 2, -half, 0.0), (-lx / 2 + e, half, t))},
        },
        "parts": _board_parts(lx, ly),
    }
    return Built(table, lx * ly * t)


CHOPPING_BOARD = Family(
    name="chopping-board",
    summary="cutting and bread boards without a handle",
    doc="A flat board lying on the table: its front and back edges are declared as edge "
    "members (what a perception model reports), but a slab lying flat leaves no room for "
    "a finger beside them; its top carries things.",
    materials=(("wood", 0.75), ("plastic", 0.25)),
    params=(
        Param("length", 220, 360, "mm", "length", "cutting-board", real=(200, 460)),
        Param("width", 160, 280, "mm", "width", "cutting-board", real=(150, 300)),
        Param("thickness", 12, 40, "mm", "thickness", "cutting-board"),
        Param("edge", 15, 30, "mm", "depth of the edge strips declared as edges", "robot"),
    ),
    build=_chopping_board,
    sources=("cutting-board", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ tray and sheet pan
def _rimmed(
    i: Instance, lx: float, ly: float, h: float, floor: float, rim: float, what: str
) -> tuple[dict[str, Any], float]:
    """Members and parts of a rimmed flat container; its floor and rims' volume."""
    edges = {
        "edge-left": {"kind": "edge", **cuboid((-lx / 2, ly / 2 - rim, 0.0), (lx / 2, ly / 2, h))},
        "edge-right": {
            "kind": "edge",
            **cuboid((-lx / 2, -ly / 2, 0.0), (lx / 2, -ly / 2 + rim, h)),
        },
    }
    table = {
        "description": what,
        "members": {"body": {"kind": "body", **_slab(lx, ly, h)}, **edges},
        "parts": {
            "on": {"shape": "flat", "size": [m(lx - 2 * rim), m(ly - 2 * rim)],
                   "center": [0.0, 0.0], "height": m(floor), "food_surface": True},
            "under": {"shape": "flat", "size": [m(lx), m(ly)]},
            **sides("thin"),
        },
    }  # fmt: skip
    volume = lx * ly * floor + 2 * (lx + ly) * rim * (h - floor)
    return table, volume


def _tray(i: Instance) -> Built:
    lx, ly, h = even(i["length"]), even(i["width"]), i["height"]
    table, volume = _rimmed(
        i, lx, ly, h, i["floor"], i["rim"], f"{i.material} serving tray with handle bars"
    )
    gap, bar, span = i["handle_gap"], i["handle_bar"], even(i["handle_span"])
    for side, sign in (("front", 1), ("back", -1)):
        x0, x1 = sorted((sign * (lx / 2 + gap), sign * (lx / 2 + gap + bar)))
        table["members"][f"handle-{side}"] = {
            "kind": "handle",
            **cuboid((x0, -span / 2, h - bar), (x1, span / 2, h)),
        }
    volume += 2 * (span * bar * bar + 2 * gap * 0.01 * bar)
    return Built(table, volume * i.values.get("solid", 1.0))


TRAY = Family(
    name="tray",
    summary="serving trays with handle bars",
    doc="A rimmed tray (a floor inside raised rims) with a handle bar at front and back, "
    "held by posts: the bigger objects' base.",
    materials=(("wood", 0.75), ("plastic", 0.25)),
    params=(
        Param("length", 340, 420, "mm", "length without the handles", "tray", real=(300, 500)),
        Param("width", 280, 330, "mm", "width", "tray", real=(250, 350)),
        Param("height", 30, 50, "mm", "rim height", "tray"),
        Param("floor", 8, 18, "mm", "floor thickness (height of its surface)", "tray"),
        Param("rim", 12, 20, "mm", "rim thickness", "tray"),
        Param("handle_gap", 15, 30, "mm", "gap between rim and handle bar", "tray"),
        Param("handle_bar", 16, 24, "mm", "handle bar thickness", "tray"),
        Param("handle_span", 100, 150, "mm", "handle bar length", "tray"),
        Param("solid", 0.15, 0.3, "fraction", "solid fraction of a moulded tray's walls", "tray",
              materials=("plastic",)),
    ),
    build=_tray,
    sources=("tray", "materials"),
)  # fmt: skip


def _sheet_pan(i: Instance) -> Built:
    lx, ly, h = even(i["length"]), even(i["width"]), i["height"]
    table, volume = _rimmed(
        i, lx, ly, h, i["sheet"], i["lip"], f"{i.material} sheet pan: a flat floor inside a lip"
    )
    lip = i["lip"]
    for side, sign in (("front", 1), ("back", -1)):
        x0, x1 = sorted((sign * lx / 2, sign * (lx / 2 - lip)))
        table["members"][f"edge-{side}"] = {
            "kind": "edge",
            **cuboid((x0, -ly / 2 + lip, 0.0), (x1, ly / 2 - lip, h)),
        }
    # the lip is a rolled sheet, not solid: about a third of its box
    volume = lx * ly * i["sheet"] + 2 * (lx + ly) * lip * (h - i["sheet"]) / 3
    return Built(table, volume)


SHEET_PAN = Family(
    name="sheet-pan",
    summary="baking sheet pans with a rolled lip",
    doc="A thin flat sheet inside a low lip on all four sides (edge members): a large, "
    "light base.",
    materials=(("aluminium", 0.7), ("steel", 0.3)),
    params=(
        Param("length", 330, 420, "mm", "length (quarter to half sheet)", "sheet-pan",
              real=(330, 460)),
        Param("width", 240, 330, "mm", "width", "sheet-pan"),
        Param("height", 18, 30, "mm", "lip height", "sheet-pan"),
        Param("sheet", 0.8, 1.3, "mm", "sheet thickness", "sheet-pan", materials=("aluminium",)),
        Param("sheet", 0.6, 1.0, "mm", "sheet thickness", "sheet-pan", materials=("steel",)),
        Param("lip", 8, 14, "mm", "lip width", "sheet-pan"),
    ),
    build=_sheet_pan,
    sources=("sheet-pan", "materials"),
)  # fmt: skip


# ------------------------------------------------------------------ utensil
def _utensil(i: Instance) -> Built:
    bl, bw, bt = even(i["blade_length"]), even(i["blade_width"]), i["blade_thickness"]
    hl, hw, ht = i["handle_length"], even(i["handle_width"]), i["handle_thickness"]
    table = {
        "description": f"{i.material} spatula: a flat blade and a long handle",
        "members": {
            "body": {"kind": "body", **cuboid((-bl / 2, -bw / 2, 0.0), (bl / 2, bw / 2, bt))},
            "handle": {
                "kind": "handle",
                **cuboid((-bl / 2 - hl, -hw / 2, 0.0), (-bl / 2, hw / 2, ht)),
            },
        },
        "parts": {"on": {"shape": "thin"}, "under": {"shape": "flat"}, **sides("thin")},
    }
    return Built(table, bl * bw * bt + hl * hw * ht)


UTENSIL = Family(
    name="utensil",
    summary="spatulas and turners",
    doc="A flat blade and a long handle lying flat: grasped by either; nothing rests on it.",
    materials=(("wood", 0.7), ("plastic", 0.3)),
    params=(
        Param("blade_length", 60, 100, "mm", "blade length", "utensil"),
        Param("blade_width", 55, 75, "mm", "blade width", "utensil", real=(55, 90)),
        Param("blade_thickness", 6, 12, "mm", "blade thickness", "utensil"),
        Param("handle_length", 160, 230, "mm", "handle length", "utensil"),
        Param("handle_width", 20, 30, "mm", "handle width", "utensil"),
        Param("handle_thickness", 14, 22, "mm", "handle thickness", "utensil"),
    ),
    build=_utensil,
    sources=("utensil", "materials"),
)  # fmt: skip

__all__ = ["CHOPPING_BOARD", "PADDLE_BOARD", "PLATE", "SHEET_PAN", "TRAY", "UTENSIL"]
