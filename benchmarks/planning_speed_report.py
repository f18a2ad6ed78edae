"""The report of `planning_speed.py`: medians and ratios of the measurements, and the
Markdown table that prints them beside their targets."""

from __future__ import annotations

from typing import Any

from compare import med  # benchmarks/ is on sys.path when run

VERSIONS = ("this", "base")
TARGETS = {"cold_vs_base": 1.0, "cold_vs_driver": 0.15, "process_vs_driver": 0.5, "env": 1.0}


def summarise(plans: list[dict], procs: list[dict], env: list[dict]) -> dict[str, Any]:
    s: dict[str, Any] = {}
    for v in VERSIONS:
        s[v] = {
            "cold_s": med(r[v]["cold_s"] for r in plans),
            "cold_cpu_s": med(r[v]["cold_cpu_s"] for r in plans),
            "warm_s": med(r[v]["warm_s"] for r in plans),
            "warm_cpu_s": med(r[v]["warm_cpu_s"] for r in plans),
            "process_s": med(r[v]["s"] for r in procs),
            "process_cpu_s": med(r[v]["cpu_s"] for r in procs),
            "env_steps_per_s": med(r[v] for r in env),
            "env_cpu_steps_per_s": med(r[f"{v}_cpu"] for r in env),
        }
    s["driver"] = {
        "s": med(r["driver"]["s"] for r in plans),
        "cpu_s": med(r["driver"]["cpu_s"] for r in plans),
        "process_s": med(r["driver"]["s"] for r in procs),
        "process_cpu_s": med(r["driver"]["cpu_s"] for r in procs),
    }
    t, b, d = s["this"], s["base"], s["driver"]
    s["ratio"] = {
        "cold_vs_base": t["cold_s"] / b["cold_s"],
        "cold_vs_base_per_scene": med(r["this"]["cold_s"] / r["base"]["cold_s"] for r in plans),
        "cold_cpu_vs_base": t["cold_cpu_s"] / b["cold_cpu_s"],
        "cold_cpu_vs_base_per_scene": med(
            r["this"]["cold_cpu_s"] / r["base"]["cold_cpu_s"] for r in plans
        ),
        "warm_vs_base_per_scene": med(r["this"]["warm_s"] / r["base"]["warm_s"] for r in plans),
        "process_vs_base_per_scene": med(r["this"]["s"] / r["base"]["s"] for r in procs),
        "warm_vs_base": t["warm_s"] / b["warm_s"],
        "cold_vs_driver": t["cold_s"] / d["s"],
        "base_cold_vs_driver": b["cold_s"] / d["s"],
        "warm_vs_driver": t["warm_s"] / d["s"],
        "process_vs_driver": t["process_s"] / d["process_s"],
        "base_process_vs_driver": b["process_s"] / d["process_s"],
        "process_cpu_vs_driver": t["process_cpu_s"] / d["process_cpu_s"],
        "process_vs_base": t["process_s"] / b["process_s"],
        "env": t["env_steps_per_s"] / b["env_steps_per_s"],
        "env_cpu": t["env_cpu_steps_per_s"] / b["env_cpu_steps_per_s"],
        "env_per_round": med(r["this"] / r["base"] for r in env),
        "env_cpu_per_round": med(r["this_cpu"] / r["base_cpu"] for r in env),
    }
    same = [r["scene"] for r in plans if r["this"]["length"] != r["driver"]["length"]]
    s["plan_length_differs_from_driver"] = same
    return s


def table(s: dict[str, Any], base: str, this: str, n_plans: int, n_procs: int, args: Any,
          run: str, command: str) -> str:  # fmt: skip
    t, b, d, q = s["this"], s["base"], s["driver"], s["ratio"]

    def ms(x: float) -> str:
        return f"{1000 * x:.1f}"

    def met(key: str, value: float, below: bool = True) -> str:
        ok = value <= TARGETS[key] if below else value >= TARGETS[key]
        return f"{'met' if ok else 'NOT met'} ({'<=' if below else '>='} {TARGETS[key]})"

    lines = [
        f"| figure | base `{base}` | this `{this}` | this / base | paired | driver "
        "| this / driver | target |",
        "|---|---|---|---|---|---|---|---|",
        f"| cold planning, fresh process (ms) | {ms(b['cold_s'])} | {ms(t['cold_s'])} "
        f"| **{q['cold_vs_base']:.2f}** | {q['cold_vs_base_per_scene']:.2f} | {ms(d['s'])} "
        f"| **{q['cold_vs_driver']:.2f}** "
        f"| this / base {met('cold_vs_base', q['cold_vs_base'])}; this / driver "
        f"{met('cold_vs_driver', q['cold_vs_driver'])} |",
        f"| cold planning, fresh process, CPU (ms) | {ms(b['cold_cpu_s'])} "
        f"| {ms(t['cold_cpu_s'])} | {q['cold_cpu_vs_base']:.2f} "
        f"| {q['cold_cpu_vs_base_per_scene']:.2f} | {ms(d['cpu_s'])} "
        f"| {t['cold_cpu_s'] / d['cpu_s']:.2f} | |",
        f"| cold planning, warm process (ms) | {ms(b['warm_s'])} | {ms(t['warm_s'])} "
        f"| {q['warm_vs_base']:.2f} | {q['warm_vs_base_per_scene']:.2f} | {ms(d['s'])} "
        f"| {q['warm_vs_driver']:.2f} | |",
        f"| `utamp plan SCENE --json`, whole process (ms) | {ms(b['process_s'])} "
        f"| {ms(t['process_s'])} | {q['process_vs_base']:.2f} "
        f"| {q['process_vs_base_per_scene']:.2f} | {ms(d['process_s'])} "
        f"| **{q['process_vs_driver']:.2f}** "
        f"| {met('process_vs_driver', q['process_vs_driver'])} |",
        f"| symbolic env steps/s | {b['env_steps_per_s']:,.0f} | {t['env_steps_per_s']:,.0f} "
        f"| **{q['env']:.2f}** | {q['env_per_round']:.2f} | | "
        f"| {met('env', q['env'], below=False)} |",
        f"| symbolic env steps/s, CPU (whole loop) | {b['env_cpu_steps_per_s']:,.0f} "
        f"| {t['env_cpu_steps_per_s']:,.0f} | {q['env_cpu']:.2f} | {q['env_cpu_per_round']:.2f} "
        "| | | |",
        "",
        f"Five-object {args.suite} scenes, UTAMP-2-GT, search `astar-blind`; medians over "
        "scenes of per-scene medians; *this / base* divides the two medians, *paired* is the "
        "median of the per-scene (env: per-round) ratios, steadier when the load drifts. "
        f"Cold: {n_plans} scenes x {args.repeats} plans per tree, "
        "each in a process forked from a worker that has imported the planner and planned "
        "nothing (warm process: the same scenes planned again and again in one process, a fresh "
        "`StatePlanner` each time). Driver: `fast-downward.py` with the same search on the "
        "same PDDL files (whole process: `--alias lama-first`, "
        f"{n_procs} scenes x {args.process_runs} runs). Env: the raw symbolic env, "
        f"{args.env_rounds} alternating rounds of {args.env_steps:,} masked random steps, "
        "steps/s inside `env.step` (CPU: steps per CPU second of the whole loop, the agent's "
        "choice and resets included). This tree reads its parsed domain and join orders "
        "from the user cache (`utamp_gym.symbolic.store`; the first plan of the run writes "
        "them), as every `utamp plan` after the first does. "
        f"The base's `utamp plan` takes {q['base_process_vs_driver']:.2f}x the driver's whole "
        f"process, its cold planning {q['base_cold_vs_driver']:.2f}x the driver. {run}",
        "",
        f"_Written by `{command}` at commit `{this}`._",
    ]
    return "\n".join(lines) + "\n"
