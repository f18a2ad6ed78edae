"""The README's results section, written from the files in ``docs/results/`` (never typed).

    python docs/_scripts/readme.py [--check]

Rewrites each block of ``README.md`` between ``<!-- results:NAME begin ... -->`` and
``<!-- results:NAME end -->`` with what `blocks` computes: ``paper``, the physics success rates
next to the paper's (`facts.paper_rows`, with the pose noise, seeds, commit and command the
summaries record), and ``open-world``, one figure per results file with the commit it records.
``--check`` writes nothing and exits 1 when README.md differs (``tests/test_docs.py`` checks
the same). The targets a figure is held to are the ones of the benchmark that measured it.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
RESULTS = ROOT / "docs" / "results"
README = ROOT / "README.md"
sys.path.insert(0, str(HERE))

import facts  # noqa: E402

from utamp_gym.provenance import parse_footer  # noqa: E402

BLOCK = re.compile(
    r"(?P<begin><!-- results:(?P<name>[\w-]+) begin [^\n]*-->\n)(?P<body>.*?)"
    r"(?P<end><!-- results:(?P=name) end -->)",
    re.S,
)


def load_script(path: str | Path) -> ModuleType:
    """Import a script of the repository (``benchmarks/x.py``) as a module, without running
    its ``main`` (its folder goes on ``sys.path`` for its sibling imports, as when it runs)."""
    path = (ROOT / path).resolve()
    name = f"_script_{path.parent.name}_{path.stem}"
    if name in sys.modules:
        return sys.modules[name]
    if str(path.parent) not in sys.path:  # last: its names must not shadow installed ones
        sys.path.append(str(path.parent))
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None, path
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while it runs
    spec.loader.exec_module(module)
    return module


def recorded(name: str) -> dict[str, Any]:
    """The provenance a results file records (JSON keys or the Markdown footer)."""
    path = RESULTS / name
    if path.suffix == ".json":
        data = json.loads(path.read_text())
        prov = {k: data[k] for k in ("commit", "command", "note") if k in data}
    else:
        prov = parse_footer(path.read_text()) or {}
    if "commit" not in prov:
        raise ValueError(f"docs/results/{name} records no commit")
    return prov


def _pct(rate: float) -> str:
    return f"{100 * rate:.1f}".removesuffix(".0") + " %"


def _short(text: str, short: bool) -> str:
    return f"**{text}**" if short else text


def physics_speed() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "physics_speed.json").read_text())
    ratios = ", ".join(f"{s['ratio']['wall_s']:.2f}× {s['suite']}" for s in d["summary"])
    return (
        f"physics per five-object episode vs `{d['base']}`, one run",
        f"wall {ratios}",
        "physics_speed.md",
    )


def procedural_eval() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "procedural_eval.json").read_text())
    target = load_script("benchmarks/procedural_sweep.py").TARGET
    rates = {s["split"]: s["success_rate_of_planned"] for s in d["splits"]}
    cells = ", ".join(f"{split} {_short(_pct(r), r < target)}" for split, r in rates.items())
    what = (
        "procedural-v1, UTAMP-2-rules in physics, planned runs that succeed "
        f"({d['args']['seeds']} seeds)"
    )
    return what, cells, "procedural_eval.md"


def procedural_outcomes() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "procedural_outcomes.json").read_text())
    bench = load_script("benchmarks/procedural_outcomes.py")
    target = bench.TARGET
    rate = d["allowed_physics_ok"] / d["allowed"]
    clean = d["allowed_clean_physics_ok"] / d["allowed_clean"]
    worst = min(f["allowed_ok"] / f["allowed"] for f in d["by_family"].values() if f.get("allowed"))
    family = _short(f"every family ≥ {int(100 * worst)} %", worst < target)
    forbidden = d["forbidden_picks_physics_ok"] / d["forbidden_picks"]
    figure = (
        f"allowed actions succeed {_short(_pct(rate), rate < target)} ({_pct(clean)} in states "
        "the rules lead to); "
        f"{family}; forbidden picks physics carries out: "
        f"{_short(_pct(forbidden), forbidden > bench.FORBIDDEN_PICKS)}"
    )
    # the same grasp under its other finger order left out
    grasps = d["forbidden_grasps_physics_ok"] / d["forbidden_grasps"]
    figure += f" ({_pct(grasps)} of the grasps refused under every name)"
    return "rules against physics on procedural states", figure, "procedural_outcomes.md"


def perceived() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "perceived.json").read_text())
    bench = load_script("benchmarks/perceived_eval.py")
    runs = {suite: d[suite]["utamp2-perceived"] for suite in ("pick-place", "sliding")}
    success = ", ".join(
        f"{suite} " + _short(f"{r['success_rate']:.2f}", r["success_rate"] < bench.TARGET_SUCCESS)
        for suite, r in runs.items()
    )
    f1 = ", ".join(
        _short(f"{r['affordance_f1']:.3f}", r["affordance_f1"] < bench.TARGET_F1)
        for r in runs.values()
    )
    figure = (
        f"{success} (target {bench.TARGET_SUCCESS:.2f}); affordance F1 {f1} "
        f"(target {bench.TARGET_F1:.2f})"
    )
    return "`utamp2-perceived` (RGB-D) in physics", figure, "perceived.md"


def closed_loop_rgbd() -> tuple[str, str, str]:
    text = (RESULTS / "closed_loop_rgbd.md").read_text()
    targets = load_script("benchmarks/closed_loop.py").RGBD_TARGETS
    cells, levels, suites = [], [], set()
    for suite, p, n, closed in re.findall(
        r"^\| ([\w-]+) \| ([\d.]+) \| (\d+) \| [^|]+ \| ([\d.]+) \(\d+\) \|", text, re.M
    ):
        rate, runs = float(closed), int(n)
        short = float(p) in targets and rate < targets[float(p)]
        cells.append(_short(f"{round(rate * runs)}/{runs}", short))
        levels.append(p)
        suites.add(suite)
    if not cells:
        raise ValueError("docs/results/closed_loop_rgbd.md: no closed-loop rows found")
    shown = ", ".join(sorted(suites))
    what = f'closed loop with `perception="rgbd"`, {shown}, fault p = {" / ".join(levels)}'
    return what, ", ".join(cells), "closed_loop_rgbd.md"


def perception_cost() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "perception_cost.json").read_text())
    target = load_script("benchmarks/perception_cost.py").TARGET_MS
    ms = d["perception_ms_median"]
    figure = f"{_short(f'{ms:.1f} ms', ms > target)} (target {target:g} ms)"
    return "perception cost per macro step (median)", figure, "perception_cost.md"


def agents() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "agents.json").read_text())
    splits = list(d["splits"])
    train, test = splits[0], splits[-1]
    methods = d["methods"]
    planner = methods["planner (utamp2-rules)"]["success"][test]["rate"]
    learned = {"BC": "BC from", "slot MaskablePPO": "MaskablePPO, slot transformer"}
    cells, seeds = [], set()
    for short, prefix in learned.items():
        label = next(k for k in methods if k.startswith(prefix))
        m = methods[label]
        seeds.add(len(m["per_seed"]))
        to = m["summary"][test]["mean"]
        cells.append(
            f"{short} {m['summary'][train]['mean']:.2f} → {_short(f'{to:.2f}', to < planner)}"
        )
    (n,) = seeds
    what = f"learned agents, {train} → {test} ({n} seeds)"
    return what, f"{', '.join(cells)}; planner {planner:.2f}", "agents.md"


def _v2_physics(name: str, protocol: str) -> tuple[str, str, str]:
    d = json.loads((RESULTS / f"{name}.json").read_text())
    bench = load_script("benchmarks/v2_physics.py")
    rates = {s["split"]: s["success_rate_of_planned"] for s in d["splits"]}
    cells = ", ".join(f"{k} {_short(_pct(r), r < bench.TARGET)}" for k, r in rates.items())
    totals = bench.templates_total(d["splits"]).values()
    worst = min(c.get("ok", 0) / c["runs"] for c in totals if c.get("runs"))
    cells += "; every template ≥ " + _short(_pct(worst), worst < bench.TEMPLATE_TARGET)
    what = (
        f"procedural-v2 tasks, UTAMP-2x-rules in physics, {protocol}, planned runs that "
        f"succeed ({d['args']['seeds']} seeds)"
    )
    return what, cells, f"{name}.md"


def v2_physics() -> tuple[str, str, str]:
    return _v2_physics("v2_physics", "open loop")


def v2_physics_closed_loop() -> tuple[str, str, str]:
    return _v2_physics("v2_physics_closed_loop", "planner policy (closed loop)")


def agents_v2() -> tuple[str, str, str]:
    d = json.loads((RESULTS / "agents_v2.json").read_text())
    splits = list(d["splits"])
    train, test = splits[0], splits[-1]
    methods = d["methods"]
    planner = next(m["success"][test]["rate"] for m in methods.values() if "summary" not in m)
    cells = []
    for label, m in methods.items():
        if "summary" in m:
            s = m["summary"]
            to = _short(f"{s[test]['mean']:.2f}", s[test]["mean"] < planner)
            cells.append(f"{label.split(' ')[0]} {s[train]['mean']:.2f} → {to}")
    what = f"goal-conditioned agents, procedural-v2 {train} → {test}"
    return what, f"{', '.join(cells)}; planner {planner:.2f}", "agents_v2.md"


#: the rows of the open-world table, in order
OPEN_WORLD: tuple[Callable[[], tuple[str, str, str]], ...] = (
    physics_speed, procedural_eval, procedural_outcomes, v2_physics, v2_physics_closed_loop,
    perceived, closed_loop_rgbd, perception_cost, agents, agents_v2,
)  # fmt: skip


def open_world_block() -> str:
    rows = [
        "The open world (each figure from the file named, measured at the commit that file "
        "records; what is still short of its benchmark's target, or of the planner, is in bold):",
        "",
        "| what | figure | file in `docs/results/` | measured at |",
        "|---|---|---|---|",
    ]
    for row in OPEN_WORLD:
        what, figure, name = row()
        rows.append(f"| {what} | {figure} | `{name}` | `{recorded(name)['commit']}` |")
    return "\n".join(rows) + "\n"


def paper_block() -> str:
    noise = facts.same_field(facts.physics_summaries(RESULTS), "noise_levels")
    text = (
        "Success rate of the planning methods on the paper's two suites (`utamp eval`), "
        f"{facts.paper_conditions(RESULTS)}, next to the paper's figures; UTAMP-2-noisy "
        f"(attributes corrupted with p = {' / '.join(f'{p:g}' for p in noise)} before the "
        "rule parser) stands in for the paper's VLM-based UTAMP-2-VLM:"
    )
    return "\n".join([text, "", *facts.paper_rows(RESULTS)]) + "\n"


def blocks() -> dict[str, str]:
    """Each generated README block by name: its text from the results files."""
    return {"paper": paper_block(), "open-world": open_world_block()}


def rewrite(readme: str, generated: dict[str, str]) -> str:
    """`readme` with each marked block replaced by its generated text (a block named in
    `generated` but not marked in `readme` is an error)."""
    seen: set[str] = set()

    def sub(m: re.Match[str]) -> str:
        seen.add(m.group("name"))
        if m.group("name") not in generated:
            raise ValueError(f"README.md: no generator for block {m.group('name')!r}")
        return m.group("begin") + "\n" + generated[m.group("name")] + "\n" + m.group("end")

    out = BLOCK.sub(sub, readme)
    if missing := sorted(set(generated) - seen):
        raise ValueError(f"README.md has no markers for the block(s) {missing}")
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="only check; exit 1 when it differs")
    args = ap.parse_args(argv)
    old = README.read_text()
    new = rewrite(old, blocks())
    if args.check:
        if new != old:
            print("README.md's results blocks differ from docs/results: run "
                  "python docs/_scripts/readme.py", file=sys.stderr)  # fmt: skip
            return 1
        return 0
    if new != old:
        README.write_text(new)
        print("rewrote the results blocks of README.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
