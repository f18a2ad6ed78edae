"""Evaluation harness (`utamp eval`): sweeps, result rows, summaries, figures, VLM methods
and why-not explanations.

Entry points: `sweep.run_sweep` / `sweep.write_outputs`, `runner.run_task`,
`explain.explain_unsolvable`, `vlm_methods.run_utamp2_vlm` / `run_vlm_planner`.
"""
