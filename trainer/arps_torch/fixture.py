"""Writes the PyTorch side's equivalence fixture (``fixtures/equivalence/torch_*``): weights of the
tiny config in the engine's format, two clouds, and this model's memberships, steps, shifts and
``T_target_source``. ``tests/train_equivalence.rs`` checks that the engine reproduces them.

    python -m arps_torch.fixture --out fixtures/equivalence
"""

import argparse
import math
import os

import numpy as np
import torch
from safetensors.numpy import save

from .config import tensor_specs
from .model import ArpsNet
from .weights import weights_bytes, write_atomic

TINY = {
    "preset": "tiny", "n_points": 32, "feature_dim": 8, "heads": 2, "ffn_dim": 16, "layers": 2, "top_h": 8,
    "gaussians": 4, "pos_hidden": [8], "step_hidden": 8, "head_hidden": [8], "reference": "soft",
    "soft_temperature": 1.0, "layer_norm_eps": 1e-5,
}


def fixture_weights(cfg, seed=7):
    """Random weights with memberships far from uniform (the head is scaled up)."""
    g = torch.Generator().manual_seed(seed)
    out = {}
    for name, shape in tensor_specs(cfg):
        if ".norm" in name:
            base = 1.0 if name.endswith("weight") else 0.0
            out[name] = (base + 0.1 * torch.randn(shape, generator=g)).numpy()
        elif name.endswith("weight"):
            scale = (4.0 if name.startswith("head.") else 1.5) / math.sqrt(shape[1])
            out[name] = (scale * torch.randn(shape, generator=g)).numpy()
        else:
            out[name] = (0.1 * torch.randn(shape, generator=g)).numpy()
    return out


def fixture_clouds(seed=7):
    """A 44-point source and a 36-point target (a turned, shifted, noisy part of it)."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(44, 3))
    src = (u / np.linalg.norm(u, axis=1, keepdims=True)) * np.array([0.9, 0.6, 0.4])
    a = 0.5
    r = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    tgt = src[:36] @ r.T + np.array([0.1, -0.05, 0.2]) + 0.01 * rng.normal(size=(36, 3))
    return src.astype(np.float32), tgt.astype(np.float32)


def outputs(model, src, tgt):
    """The arrays a fixture stores for clouds ``src`` and ``tgt``."""
    with torch.no_grad():
        o = model(torch.from_numpy(src)[None], torch.from_numpy(tgt)[None])
    return {
        "source": src, "target": tgt,
        "gamma_source": o["gamma_source"][0].numpy(), "gamma_target": o["gamma_target"][0].numpy(),
        "steps": o["steps"][0].numpy(), "shifts_source": o["shifts_source"][0].numpy(),
        "shifts_target": o["shifts_target"][0].numpy(), "t12": o["t12"][0].numpy(),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="fixtures/equivalence")
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    # stored f16 (half the size); the outputs are this model's on the stored weights
    w = {k: v.astype(np.float16).astype(np.float32) for k, v in fixture_weights(TINY).items()}
    model = ArpsNet(TINY)
    model.load(w)
    src, tgt = fixture_clouds()
    write_atomic(os.path.join(a.out, "torch_tiny.safetensors"),
                 weights_bytes(TINY, w, {"fixture": "python -m arps_torch.fixture"}, f16=True))
    arrays = {k: np.ascontiguousarray(v) for k, v in outputs(model, src, tgt).items()}
    write_atomic(os.path.join(a.out, "torch_io.safetensors"),
                 save(arrays, metadata={"written_by": "python -m arps_torch.fixture", "torch": torch.__version__}))
    print(f"wrote {a.out}/torch_tiny.safetensors and torch_io.safetensors")


if __name__ == "__main__":
    main()
