"""Franka Panda layer: assets, Pinocchio kinematics/IK, MuJoCo model, collision checks, motion.

Modules (import them directly; this package imports nothing heavy):
`assets` (example-robot-data files), `kinematics` (FK/IK), `panda_mjcf` (`add_panda`),
`collision` (`CollisionChecker`), `motion` (OMPL planning and trajectory timing).
"""
