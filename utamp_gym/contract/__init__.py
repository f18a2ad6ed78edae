"""The types a physics backend and perception exchange, below both `sim` and `perception`.

* `state` – `PhysicalState` and `Grasp` (what a simulator reports), `TABLE`, `FLOOR` and the
  toppling threshold `TILT_DEG`;
* `views` – `ViewBundle`, `View`, `Intrinsics`, `RobotState` (what a look at the table gives);
* `tracking` – `PoseTracker` and `PoseTracking`: a pose estimator that perception builds and
  the backend calls while it acts (`perception.tracking`).

The backend protocol itself is `utamp_gym.backend`. This package imports only numpy and
`utamp_gym.scene`.
"""
