"""Evaluation harness (`utamp eval`): sweeps, result rows, summaries, figures and why-not
explanations (the perceived and VLM methods it runs are `utamp_gym.methods`).

Entry points: `sweep.run_sweep` / `sweep.write_outputs`, `runner.run_task`,
`explain.explain_unsolvable`.
"""
