"""The Gymnasium envs: a Panda stacks a kitchen table's objects on the tray (U-TAMP-2 actions).

Import the modules directly; this package imports nothing and registers nothing
(`registry.register_envs()` does, explicitly):

* `registry` – env ids from the definition files in ``envs/`` and `register_envs()`;
* `kitchen` – `UTampKitchenEnv` (its docstring documents spaces, reward and options);
* `task`, `render` – reward and spaces, the schematic renderer (the physics backend
  protocol is `utamp_gym.backend`; the symbolic world model the env steps in, universe,
  atoms, state, poses and outcome model, is `utamp_gym.symbolic`: ``env.universe``,
  ``env.state`` ... are deprecated aliases);
* `wrappers` (`SymbolicActionWrapper`), `planner_policy` (`PlannerPolicy`).
"""
