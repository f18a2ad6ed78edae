"""The Gymnasium envs: a Panda stacks a kitchen table's objects on the tray (U-TAMP-2 actions).

Import the modules directly; this package imports nothing and registers nothing
(`registry.register_envs()` does, explicitly):

* `registry` – env ids from the definition files in ``envs/`` and `register_envs()`;
* `kitchen` – `UTampKitchenEnv` (its docstring documents spaces, reward and options);
* `episode`, `observe`, `info` – what an episode is about (its scene and goal, fixed at
  reset), the observation the agent gets, and the info dicts' fixed structure;
* `task`, `render` – reward and spaces, the schematic renderer (the physics backend
  protocol is `utamp_gym.backend`; the symbolic world model the env steps in, universe,
  atoms, state, poses and outcome model, is `utamp_gym.symbolic`: ``env.universe``,
  ``env.state`` ... are deprecated aliases);
* `grounding`, `physics`, `symbolic_backend` – what the env asks of its grounding, the
  physics grounding (perception, faults) and symbolic grounding as a backend;
* `objects`, `object_space`, `object_maps`, `object_goal` – the object-centric interface
  (`ObjectInterface`), its spaces and action coding, its per-universe and per-scene tables,
  and the goal entries of its observation;
* `wrappers` (`SymbolicActionWrapper`); `planner_policy` is a deprecated alias (the
  policies live in `utamp_gym.agents`).
"""
