"""Files shared with the Rust side.

* The engine's weights (``src/weights.rs``): safetensors, tensors by engine name in ``f32``,
  ``f16`` or ``i8`` (2-D weights, with ``NAME.scale``: one scale per row, read as ``q * scale``;
  ``src/weights/int8.rs``), metadata ``format = arps-weights``, ``format_version = 1``, ``config`` (the
  ``ModelConfig`` JSON) and ``provenance`` (JSON).
* The CPU trainer's checkpoint (``src/train/run/checkpoint.rs``): flat ``f32`` tensors
  ``param/<name>``, ``adam_m/<name>``, ``adam_v/<name>`` and ``ema/<name>`` (when the run keeps a
  moving average), metadata ``arps_train_state`` (the ``RunState`` JSON) and ``adam``. The
  PyTorch trainer reads and writes exactly this, so ``arps-train`` resumes, exports and plots
  its runs and the other way round.
"""

import json
import os

import numpy as np
from safetensors.numpy import load, save

from . import config as C

FORMAT = "arps-weights"
FORMAT_VERSION = "1"
STATE_KEY = "arps_train_state"


def _metadata(path_or_bytes):
    data = path_or_bytes if isinstance(path_or_bytes, (bytes, bytearray)) else open(path_or_bytes, "rb").read()
    n = int.from_bytes(data[:8], "little")
    header = json.loads(data[8:8 + n])
    return header.get("__metadata__", {}) or {}, data


def read_weights(path):
    """``(config dict, provenance, {name: float32 array of the spec's shape})``."""
    meta, data = _metadata(path)
    if meta.get("format") != FORMAT:
        raise ValueError(f"{path}: metadata format is {meta.get('format')!r}, expected {FORMAT!r}")
    if meta.get("format_version") != FORMAT_VERSION:
        raise ValueError(f"{path}: format_version {meta.get('format_version')!r} is not supported")
    cfg = C.check(json.loads(meta["config"]))
    prov = json.loads(meta.get("provenance", "null"))
    arrays = load(bytes(data))
    tensors = {}
    for name, shape in C.tensor_specs(cfg):
        if name not in arrays:
            raise ValueError(f"{path}: tensor {name!r} is missing")
        a = arrays[name]
        if list(a.shape) != list(shape):
            raise ValueError(f"{path}: tensor {name!r} has shape {list(a.shape)}, config needs {shape}")
        if a.dtype == np.int8:
            scale = arrays.get(name + ".scale")
            if a.ndim != 2 or scale is None or list(scale.shape) != [shape[0]]:
                raise ValueError(f"{path}: int8 tensor {name!r} needs a 2-D shape and a scale per row")
            tensors[name] = a.astype(np.float32) * scale.astype(np.float32)[:, None]
        else:
            tensors[name] = a.astype(np.float32)
    scales = sum(1 for n in tensors if n + ".scale" in arrays and arrays[n].dtype == np.int8)
    if len(arrays) != len(tensors) + scales:
        raise ValueError(f"{path}: tensors beyond the config")
    return cfg, prov, tensors


def weights_bytes(cfg, tensors, provenance=None, f16=False):
    """The engine's weights file for ``{name: array}`` (f16 or f32)."""
    dtype = np.float16 if f16 else np.float32
    arrays = {}
    for name, shape in C.tensor_specs(cfg):
        a = np.asarray(tensors[name], dtype=np.float32).reshape(shape)
        if not np.all(np.isfinite(a)):
            raise ValueError(f"tensor {name!r} is not finite")
        arrays[name] = a.astype(dtype)
    meta = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "config": C.to_json(cfg),
        "provenance": json.dumps(provenance, separators=(",", ":")),
    }
    return save(arrays, metadata=meta)


def write_atomic(path, data: bytes):
    """Writes ``data`` to ``path`` atomically (temporary file, fsync, rename)."""
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def read_checkpoint(path):
    """``dict(state, adam, params, adam_m, adam_v, ema)`` (maps name -> flat float32 array;
    ``ema`` is None when the checkpoint holds no average)."""
    meta, data = _metadata(path)
    if STATE_KEY not in meta:
        raise ValueError(f"{path}: checkpoint has no run state")
    arrays = load(bytes(data))
    out = {"state": json.loads(meta[STATE_KEY]), "adam": json.loads(meta["adam"]),
           "params": {}, "adam_m": {}, "adam_v": {}, "ema": {}}
    for key, a in arrays.items():
        prefix, _, name = key.partition("/")
        if prefix == "param":
            prefix = "params"
        if prefix in ("params", "adam_m", "adam_v", "ema"):
            if a.dtype != np.float32:
                raise ValueError(f"{path}: checkpoint tensor {key} is not f32")
            out[prefix][name] = a.reshape(-1)
    out["ema"] = out["ema"] or None
    return out


def checkpoint_bytes(state, adam, params, adam_m, adam_v, ema=None):
    """A checkpoint in the CPU trainer's format."""
    arrays = {}
    for prefix, m in (("param", params), ("adam_m", adam_m), ("adam_v", adam_v), ("ema", ema or {})):
        for name, a in m.items():
            arrays[f"{prefix}/{name}"] = np.ascontiguousarray(np.asarray(a, dtype=np.float32).reshape(-1))
    meta = {STATE_KEY: json.dumps(state), "adam": json.dumps(adam)}
    return save(arrays, metadata=meta)


def save_checkpoint(path, state, adam, params, adam_m, adam_v, ema=None):
    """Writes the checkpoint atomically, and ``<path without .safetensors>.json`` (the state,
    informational) as the CPU trainer does."""
    write_atomic(path, checkpoint_bytes(state, adam, params, adam_m, adam_v, ema))
    write_atomic(os.path.splitext(path)[0] + ".json", json.dumps(state, indent=2).encode())
