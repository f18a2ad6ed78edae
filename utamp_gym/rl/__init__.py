"""RL baselines: MaskablePPO (with the env's action masks), PPO and DQN (without).

`utamp_gym.rl.train.train` trains and writes a run directory, `utamp_gym.rl.policy`
loads a model as ``policy(obs, info) -> action`` (`load_rl_policy`) and scores it
(`evaluate_rl`), `utamp_gym.rl.cli.add_train_parser` adds ``utamp train``. Nothing heavy is
imported here: torch and stable-baselines3 load only when a model is trained or loaded.
"""
