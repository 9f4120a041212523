"""The engine's ``ModelConfig`` (a JSON object, kept as a dict in the engine's field order) and
the names and shapes of its tensors (``ModelConfig::tensor_specs`` in ``src/model/config.rs``)."""

import json

FIELDS = [
    "preset", "n_points", "feature_dim", "heads", "ffn_dim", "layers", "top_h", "gaussians",
    "pos_hidden", "step_hidden", "head_hidden", "reference", "soft_temperature", "layer_norm_eps",
]


def check(cfg: dict) -> dict:
    """Returns ``cfg`` if it has every field with sane sizes, else raises ``ValueError``."""
    missing = [f for f in FIELDS if f not in cfg]
    if missing:
        raise ValueError(f"model config lacks {missing}")
    if cfg["reference"] not in ("soft", "top_h"):
        raise ValueError(f"model config: reference {cfg['reference']!r} (expected soft or top_h)")
    if (2 * cfg["feature_dim"]) % cfg["heads"] != 0:
        raise ValueError("model config: 2 * feature_dim must be divisible by heads")
    return cfg


def to_json(cfg: dict) -> str:
    """The config as the engine writes it (its field order, compact)."""
    return json.dumps({k: cfg[k] for k in FIELDS}, separators=(",", ":"))


def tensor_specs(cfg: dict):
    """``[(name, shape)]`` in the engine's order."""
    specs = []

    def linear(name, i, o):
        specs.append((f"{name}.weight", [o, i]))
        specs.append((f"{name}.bias", [o]))

    c = cfg["feature_dim"]
    d = 2 * c
    for l in range(cfg["layers"]):
        p = f"layers.{l}"
        prev = 3
        for i, h in enumerate(list(cfg["pos_hidden"]) + [c]):
            linear(f"{p}.pos.{i}", prev, h)
            prev = h
        for block in ("self_attn", "cross_attn"):
            b = f"{p}.{block}"
            for proj in ("q", "k", "v", "o"):
                linear(f"{b}.{proj}", d, d)
            specs.append((f"{b}.norm1.weight", [d]))
            specs.append((f"{b}.norm1.bias", [d]))
            linear(f"{b}.ffn1", d, cfg["ffn_dim"])
            linear(f"{b}.ffn2", cfg["ffn_dim"], d)
            specs.append((f"{b}.norm2.weight", [d]))
            specs.append((f"{b}.norm2.bias", [d]))
        linear(f"{p}.out", d, c)
        if cfg["reference"] == "soft":
            linear(f"{p}.score", c, 1)
        linear(f"{p}.step.0", 3 + c, cfg["step_hidden"])
        linear(f"{p}.step.1", cfg["step_hidden"], 1)
    prev = 2 * c
    for i, h in enumerate(list(cfg["head_hidden"]) + [cfg["gaussians"]]):
        linear(f"head.{i}", prev, h)
        prev = h
    return specs
