"""Adapters for published policies: each builds its policy's observation from ThorArena's
wire observation, runs the network on the active slots in one batch and writes raw actions.

    from thorarena.adapters import OnnxPolicy, Twist2Adapter

    adapter = Twist2Adapter(OnnxPolicy("twist2.onnx"))
    adapter.run(adapter.connect("demo"))

Modules:

- `base`: `Adapter`, per-slot state reset when an episode starts, batching over active slots,
  the session loop.
- `runtime`: running the network, `OnnxPolicy` (ONNX Runtime, `pip install
  'thorarena[policies]'`) and `TorchScriptPolicy`.
- `twist2`: TWIST2's 1432-dim observation (mimic, proprioception, 10-step history, future).
- `gmt`: GMT's 2154-dim observation (20 future frames, proprioception, 20-step history).
- `beyondmimic`: BeyondMimic ONNX exports, observation, joint order and action mapping from
  the file's metadata.
- `dump`: step-by-step comparison of another implementation's observations and actions.
- `rotations`: quaternion (w, x, y, z) helpers shared by the observation builders.
"""

from .base import Adapter, canonical_indices
from .beyondmimic import BeyondMimicAdapter, BeyondMimicMetadata
from .gmt import GmtAdapter
from .runtime import OnnxPolicy, Policy, TorchScriptPolicy, load_policy
from .twist2 import Twist2Adapter

__all__ = [
    "Adapter",
    "BeyondMimicAdapter",
    "BeyondMimicMetadata",
    "GmtAdapter",
    "OnnxPolicy",
    "Policy",
    "TorchScriptPolicy",
    "Twist2Adapter",
    "canonical_indices",
    "load_policy",
]
