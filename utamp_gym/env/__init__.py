"""The Gymnasium envs: a Panda stacks a kitchen table's objects on the tray (U-TAMP-2 actions).

Import the modules directly; this package imports nothing and registers nothing
(`registry.register_envs()` does, explicitly):

* `registry` – env ids from the definition files in ``envs/`` and `register_envs()`;
* `kitchen` – `UTampKitchenEnv` (its docstring documents spaces, reward and options);
* `universe` / `atoms` – the grounded action universe and the scenes' initial atoms;
* `state`, `poses`, `task`, `render` – symbolic state and mask, symbolic poses, reward and
  spaces, the schematic renderer (the physics backend protocol is `utamp_gym.backend`);
* `grounding`, `physics`, `symbolic_backend` – what the env asks of its grounding, the
  physics grounding (perception, faults) and symbolic grounding as a backend;
* `wrappers` (`SymbolicActionWrapper`), `dm_adapter` (`DmEnvAdapter`); `planner_policy` is
  a deprecated alias (the policies live in `utamp_gym.agents`).
"""
