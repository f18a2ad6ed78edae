"""RL baselines: MaskablePPO (with the env's action masks), PPO and DQN (without).

`utamp_gym.rl.train.train` trains one seed and writes a run directory (`utamp_gym.rl.config`:
what defines a run; `utamp_gym.rl.runs`: its files; `utamp_gym.rl.seeds.train_seeds`: several
seeds and their aggregate), `utamp_gym.rl.policy` loads a model as ``policy(obs, info) ->
action`` (`load_rl_policy`) and scores it (`evaluate_rl`), `utamp_gym.rl.saved` reads and
writes the env a model was trained on (inside its zip), `utamp_gym.rl.harness` runs a saved
model as the evaluation method ``rl:PATH``, `utamp_gym.rl.policies` holds the SB3 policy
classes (they read only their trained observation entries), and `utamp_gym.rl.cli.add_train_parser`
adds ``utamp train``. Nothing heavy is imported here: torch and stable-baselines3 load only when
a model is trained or loaded.
"""
