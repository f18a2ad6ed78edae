"""Perception: the symbolic state of a kitchen table from its physical state.

* `state` – `PhysicalState` and `Grasp`: plain data any simulator can fill in;
* `abstraction` – `perceive(scene, physical_state)`: the domain's fluent atoms (and the
  orientation-dependent `force` / `base` atoms), with a reason for every object that has no
  symbol (fallen off the table, toppled, resting inside another object, ...).

Layer: below `symbolic` (the problem generator abstracts a scene's declared state with the
same function) and below `sim` / `env` (the backend produces `PhysicalState`, the env
perceives it after every step).
"""
