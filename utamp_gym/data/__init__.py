"""Datasets of planner demonstrations: Minari (both tracks) and a LeRobot export.

`utamp_gym.data.macro` records planner-policy episodes of the macro-action envs,
`utamp_gym.data.lowlevel` the same plans as joint commands through the dm_control track,
`utamp_gym.data.minari_io` writes and reads them as Minari datasets, and
`utamp_gym.data.lerobot` converts a Minari dataset with the `lerobot` package where it is
installed. ``utamp demos`` (`utamp_gym.data.cli`) runs them; recording runs on an executor of
`utamp_gym.distributed` (local worker processes or Ray), one task per episode. Nothing heavy is
imported here.
"""
