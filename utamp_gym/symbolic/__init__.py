"""The symbolic layer: PDDL, problems, and the symbolic world model of the envs.

* `pddl`, `pddl_model`, `problem`, `export`, `validate`, `reach`, `slots` – the domains, a
  scene's problem and its grounding;
* the world model the envs step in symbolic grounding and mask with in both groundings:
  `universe` (the grounded action universe, stored by `universe_store`), `atoms` (a scene's
  initial atoms), `geometric` (U-TAMP-1's object-centric preconditions), `state` (the
  symbolic state and its mask), `outcome` (the symbolic outcome model), `poses` (symbolic
  object poses) and `scene_cache` (their per-scene caches). They moved here from
  ``utamp_gym.env``, whose old paths forward with a `DeprecationWarning` for one release.
"""
