"""Perception: the symbolic state of a kitchen table from its physical state.

* its input types, `PhysicalState`, `Grasp` and `ViewBundle`, live in `utamp_gym.contract`
  (plain data any simulator can fill in; ``perception.state`` / ``perception.views`` are
  deprecated aliases);
* `abstraction` – `perceive(scene, physical_state)`: the domain's fluent atoms (and the
  orientation-dependent `force` / `base` atoms), with a reason for every object that has no
  symbol (fallen off the table, toppled, resting inside another object, ...).

Layer: above `contract`, below `symbolic` (the problem generator abstracts a scene's
declared state with the same function) and beside `sim`, which it never imports, nor does
`sim` import it: the backend produces `PhysicalState` and renders views, the env perceives
the state after every step, and `tracking` fits poses to the backend's views.
"""
