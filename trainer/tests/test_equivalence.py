"""PyTorch vs the engine, on the fixtures in fixtures/equivalence (see tests/train_equivalence.rs)."""

import os

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="torch is not installed (pip install -r trainer/requirements.txt)")

from safetensors.numpy import load_file  # noqa: E402

from arps_torch import fixture  # noqa: E402
from arps_torch.model import ArpsNet  # noqa: E402
from arps_torch.weights import read_weights  # noqa: E402
from conftest import REPO  # noqa: E402

FIX = os.path.join(REPO, "fixtures", "equivalence")
KEYS = ["gamma_source", "gamma_target", "steps", "shifts_source", "shifts_target", "t12"]


def model_of(path):
    cfg, _, tensors = read_weights(path)
    m = ArpsNet(cfg)
    m.load(tensors)
    return m


def test_reproduces_the_engine_fixture():
    m = model_of(os.path.join(FIX, "rust_tiny.safetensors"))
    io = load_file(os.path.join(FIX, "rust_io.safetensors"))
    assert io["source"].shape[0] != io["target"].shape[0], "the fixture has clouds of different sizes"
    got = fixture.outputs(m, io["source"], io["target"])
    assert io["gamma_source"].max() - 1 / m.cfg["gaussians"] > 0.1, "memberships nearly uniform"
    for k in KEYS:
        d = np.abs(got[k] - io[k]).max()
        assert d <= 1e-4, f"{k} differs from the engine by {d:e}"


def test_torch_fixture_is_current():
    m = model_of(os.path.join(FIX, "torch_tiny.safetensors"))
    io = load_file(os.path.join(FIX, "torch_io.safetensors"))
    got = fixture.outputs(m, io["source"], io["target"])
    for k in KEYS:
        assert np.abs(got[k] - io[k]).max() <= 1e-4, f"{k}: rerun python -m arps_torch.fixture"


def test_clouds_of_one_size_run_as_one_batch_with_the_same_outputs(monkeypatch):
    """The trainer's clouds all have N points, so the network runs source and target as one batch
    of 2B and ``gmr_both`` solves both ways at once; both must give what the clouds give apart
    (the engine-fixture tests above cover clouds of different sizes, which always run apart)."""
    import arps_torch.model as model
    m = model_of(os.path.join(FIX, "rust_tiny.safetensors"))
    g = torch.Generator().manual_seed(3)
    n = m.cfg["n_points"]
    src = torch.rand(3, n, 3, generator=g) * 2 - 1
    tgt = torch.rand(3, n, 3, generator=g) * 2 - 1
    together = m(src, tgt)
    monkeypatch.setattr(model, "_Joint", lambda b: model._Apart())
    apart = m.network(src, tgt)
    apart["t12"] = model.gmr(apart["gamma_source"], apart["gamma_target"], src, tgt)
    apart["t21"] = model.gmr(apart["gamma_target"], apart["gamma_source"], tgt, src)
    assert together["gamma_source"].max() - 1 / m.cfg["gaussians"] > 0.05, "memberships nearly uniform"
    for k in KEYS + ["t21"]:
        d = (together[k].double() - apart[k].double()).abs().max().item()
        assert d <= 1e-6, f"{k} differs by {d:e} when the clouds run as one batch"


def test_gmr_recovers_a_known_transform():
    from arps_torch.model import gmr
    g = torch.Generator().manual_seed(1)
    src = torch.rand(2, 64, 3, generator=g) * 2 - 1
    a = 0.7
    r = torch.tensor([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]], dtype=torch.float32)
    t = torch.tensor([0.3, -0.2, 0.1])
    tgt = src @ r.T + t
    gamma = torch.softmax(3 * torch.randn(2, 64, 6, generator=g), -1)
    est = gmr(gamma, gamma, src, tgt)
    want = torch.eye(4, dtype=torch.float64)
    want[:3, :3] = r.double()
    want[:3, 3] = t.double()
    assert (est - want).abs().max() < 1e-5


def test_weights_round_trip(tmp_path):
    from arps_torch.weights import weights_bytes
    cfg, prov, tensors = read_weights(os.path.join(REPO, "models", "web.safetensors"))
    assert prov["trainer"].startswith("arps-train")
    for f16 in (False, True):
        p = tmp_path / f"w{int(f16)}.safetensors"
        p.write_bytes(weights_bytes(cfg, tensors, {"x": 1}, f16=f16))
        cfg2, prov2, back = read_weights(str(p))
        assert cfg2 == cfg and prov2 == {"x": 1}
        for k, v in tensors.items():
            # f32 is exact; the shipped model is int8 (q * scale), so f16 rounds it a little
            assert np.allclose(back[k], v, rtol=1e-3, atol=1e-6) if f16 else np.array_equal(back[k], v), k
    bad = dict(tensors)
    bad.pop(next(iter(bad)))
    with pytest.raises(KeyError):
        weights_bytes(cfg, bad)


def test_checkpoint_round_trip(tmp_path):
    from arps_torch.weights import read_checkpoint, save_checkpoint
    params = {"a": np.arange(5, dtype=np.float32), "b": np.ones(3, np.float32)}
    m = {k: v * 0.5 for k, v in params.items()}
    v = {k: v * 0.25 for k, v in params.items()}
    state = {"step": 3, "config": {"batch": 2}}
    p = str(tmp_path / "checkpoint.safetensors")
    save_checkpoint(p, state, {"lr": 1e-3, "t": 3}, params, m, v)
    ck = read_checkpoint(p)
    assert ck["state"] == state and ck["adam"]["t"] == 3 and ck["ema"] is None
    for k in params:
        assert np.array_equal(ck["params"][k], params[k]) and np.array_equal(ck["adam_v"][k], v[k])
    assert os.path.exists(str(tmp_path / "checkpoint.json"))


def test_compiled_network_matches_eager():
    """``train --compile``: the compiled network (forward and its gradients) computes what the
    eager one does, to float32 rounding (about 40 s on a CPU, most of it compiling)."""
    m = model_of(os.path.join(FIX, "torch_tiny.safetensors"))
    io = load_file(os.path.join(FIX, "torch_io.safetensors"))
    src = torch.as_tensor(io["source"]).unsqueeze(0).repeat(2, 1, 1)
    tgt = torch.as_tensor(io["target"]).unsqueeze(0).repeat(2, 1, 1)
    src[1] = src[1].flip(0)

    def run(fn):
        for _, p in m.named():
            p.grad = None
        out = fn(src, tgt)
        sum(v.double().sin().sum() for v in out.values()).backward()
        return {k: v.detach() for k, v in out.items()}, {n: p.grad.clone() for n, p in m.named() if p.grad is not None}

    eager, g_eager = run(m.network)
    compiled, g_comp = run(torch.compile(m.network, dynamic=False))
    for k in eager:
        assert torch.isfinite(compiled[k]).all()
        assert (compiled[k] - eager[k]).abs().max() <= 1e-5, k
    assert g_eager.keys() == g_comp.keys() and len(g_eager) > 10
    for n in g_eager:
        scale = max(1.0, g_eager[n].abs().max().item())
        assert (g_comp[n] - g_eager[n]).abs().max() <= 1e-4 * scale, n
