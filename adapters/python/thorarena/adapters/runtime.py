"""Running a policy network: ONNX Runtime (`OnnxPolicy`) or TorchScript (`TorchScriptPolicy`).

Both take a float32 batch of observations `(n, input_dim)` and the episode step of each row,
and return the raw network output `(n, output_dim)` as float32. Neither package is a
dependency of `thorarena`: ONNX Runtime comes with `pip install 'thorarena[policies]'`,
TorchScript needs a `torch` you install yourself.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Protocol

import numpy as np

TIME_STEP_INPUT = "time_step"
"""An extra model input fed with the episode step (BeyondMimic's exporter adds one)."""


class Policy(Protocol):
    """A network an adapter can run: float32 `(n, input_dim)` in, `(n, output_dim)` out."""

    @property
    def input_dim(self) -> int | None:
        """Observation width the network takes, when known."""
        ...

    @property
    def output_dim(self) -> int | None:
        """Action width the network returns, when known."""
        ...

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        """Outputs for `inputs`; `steps` holds each row's episode step (some models take it)."""
        ...


def import_onnxruntime() -> Any:
    """The `onnxruntime` module, or an ImportError that says how to install it."""
    try:
        import onnxruntime
    except ImportError as e:
        raise ImportError(
            "ONNX policies need onnxruntime: pip install 'thorarena[policies]' "
            "(or pip install onnxruntime)"
        ) from e
    return onnxruntime


def _dim(value: Any) -> int | None:
    return value if isinstance(value, int) and value > 0 else None


class OnnxPolicy:
    """An ONNX model run by ONNX Runtime on the CPU.

    The observation input is `input_name` (default: the model's first input); an input named
    `time_step` is fed with the episode step as float32 `(n, 1)`, any other extra input is
    an error. A model exported with a fixed batch of 1 is run row by row; one with a dynamic
    batch is run once per call. `metadata` holds the model's custom metadata (string pairs).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        intra_op_threads: int = 1,
        input_name: str | None = None,
        output_name: str | None = None,
    ) -> None:
        ort = import_onnxruntime()
        options = ort.SessionOptions()
        options.intra_op_num_threads = intra_op_threads
        options.inter_op_num_threads = 1
        self.path = Path(path)
        self.session = ort.InferenceSession(
            str(self.path), sess_options=options, providers=["CPUExecutionProvider"]
        )
        inputs = {i.name: i for i in self.session.get_inputs()}
        first = next(iter(inputs))
        self.input_name = input_name or first
        if self.input_name not in inputs:
            raise ValueError(f"{self.path}: no input {self.input_name!r} (has {list(inputs)})")
        extra = set(inputs) - {self.input_name}
        unknown = extra - {TIME_STEP_INPUT}
        if unknown:
            raise ValueError(f"{self.path}: inputs {sorted(unknown)} are not known to the adapter")
        self.feeds_time_step = TIME_STEP_INPUT in extra
        outputs = [o.name for o in self.session.get_outputs()]
        self.output_name = output_name or outputs[0]
        if self.output_name not in outputs:
            raise ValueError(f"{self.path}: no output {self.output_name!r} (has {outputs})")
        self.output_names = [self.output_name]
        shape = inputs[self.input_name].shape
        self.batch = _dim(shape[0]) if len(shape) == 2 else None
        """Fixed batch size of the model, or None when the batch is dynamic."""
        self._input_dim = _dim(shape[-1])
        out_shape = next(o.shape for o in self.session.get_outputs() if o.name == self.output_name)
        self._output_dim = _dim(out_shape[-1])
        self.metadata: dict[str, str] = dict(self.session.get_modelmeta().custom_metadata_map)

    @property
    def input_dim(self) -> int | None:
        """Width of the observation input, when the model fixes it."""
        return self._input_dim

    @property
    def output_dim(self) -> int | None:
        """Width of the output, when the model fixes it."""
        return self._output_dim

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(inputs, dtype=np.float32)
        if self.batch is None or self.batch == len(x):
            return self._run(x, steps)
        if self.batch != 1:
            raise ValueError(f"{self.path}: fixed batch of {self.batch}, got {len(x)} rows")
        return np.concatenate([self._run(x[i : i + 1], steps[i : i + 1]) for i in range(len(x))])

    def _run(self, x: np.ndarray, steps: np.ndarray) -> np.ndarray:
        feeds = {self.input_name: x}
        if self.feeds_time_step:
            feeds[TIME_STEP_INPUT] = np.asarray(steps, dtype=np.float32).reshape(-1, 1)
        (out,) = self.session.run(self.output_names, feeds)
        return np.asarray(out, dtype=np.float32).reshape(len(x), -1)


class TorchScriptPolicy:
    """A TorchScript module (`torch.jit.load`) on the CPU, called as `module(obs)`."""

    def __init__(self, path: str | os.PathLike[str], *, intra_op_threads: int = 1) -> None:
        try:
            import torch
        except ImportError as e:
            raise ImportError(
                "TorchScript policies need torch (pip install torch); or export the policy to "
                "ONNX and run it with onnxruntime"
            ) from e
        torch.set_num_threads(intra_op_threads)
        self._torch = torch
        self.path = Path(path)
        self.module = torch.jit.load(str(self.path), map_location="cpu")
        self.module.eval()

    @property
    def input_dim(self) -> int | None:
        """Unknown for TorchScript (checked on the first call)."""
        return None

    @property
    def output_dim(self) -> int | None:
        """Unknown for TorchScript (checked on the first call)."""
        return None

    def __call__(self, inputs: np.ndarray, *, steps: np.ndarray) -> np.ndarray:
        torch = self._torch
        with torch.no_grad():
            out = self.module(torch.from_numpy(np.ascontiguousarray(inputs, dtype=np.float32)))
        return np.asarray(out.cpu().numpy(), dtype=np.float32).reshape(len(inputs), -1)


def load_policy(path: str | os.PathLike[str], *, intra_op_threads: int = 1) -> Policy:
    """`OnnxPolicy` for a `.onnx` file, `TorchScriptPolicy` for anything else (`.pt`, `.jit`)."""
    if Path(path).suffix.lower() == ".onnx":
        return OnnxPolicy(path, intra_op_threads=intra_op_threads)
    return TorchScriptPolicy(path, intra_op_threads=intra_op_threads)
