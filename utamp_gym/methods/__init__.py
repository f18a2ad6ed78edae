"""Planning methods that detect what they plan with: perceived planning and the VLM pipeline.

* `perceived` – ``utamp2-perceived``: attributes perceived in rendered RGB-D views, turned
  into affordances by the rules, planned with Fast Downward (`plan_perceived`,
  `perceive_scene`, `attribute_accuracy`);
* `vlm` – ``utamp2-vlm`` and ``vlm-planner`` (`run_utamp2_vlm`, `run_vlm_planner`), with
  `vlm_client` (the OpenAI-compatible endpoint), `image` (the scene image shown),
  `plan_mapping` (a VLM's plan steps to U-TAMP-2 actions) and the packaged ``prompts/``;
* `attributes` – the attributes these methods are scored on.

The evaluation (`utamp_gym.eval`) runs them; they import nothing from it. They moved here
from ``utamp_gym.eval``, whose old paths forward with a `DeprecationWarning` for one release.
"""
