"""The PyTorch trainer end to end on a tiny run, against the arps-train binary (skipped when it is
not built: cargo build --release --features train): init -> stream -> train -> checkpoint ->
exact resume; its first step's losses equal the CPU trainer's; export, curves."""

import gzip
import json
import os
import shutil
import subprocess

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="torch is not installed (pip install -r trainer/requirements.txt)")

from arps_torch import stream, train  # noqa: E402
from arps_torch.weights import read_checkpoint, read_weights, save_checkpoint  # noqa: E402
from conftest import REPO  # noqa: E402

BIN = os.environ.get("ARPS_TRAIN_BIN", os.path.join(REPO, "target", "release", "arps-train"))
pytestmark = pytest.mark.skipif(not os.path.exists(BIN), reason=f"{BIN} is not built")

INIT = ["--preset", "tiny", "--batch", "2", "--val-pairs", "4", "--pair-points", "256", "--seed", "3",
        "--loss", "sup,ctr,consistency,seg,means=0.1", "--ema", "0.9", "--log-every", "1",
        "--val-every-steps", "3", "--checkpoint-every-steps", "2"]


def run(*args):
    out = subprocess.run([BIN, *args], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out


def init(d):
    run("init", "--run", str(d), *INIT)
    return d


def lines(d):
    return [json.loads(line) for line in open(os.path.join(d, "log.jsonl"))]


def pytrain(d, steps):
    train.main(["--run", str(d), "--arps-train", BIN, "--generators", "2", "--steps", str(steps), "--device", "cpu",
                "--quiet"])


def test_stream_header_and_records(tmp_path):
    d = init(tmp_path / "r")
    g = stream.Generators(BIN, os.path.join(d, "config.json"), first_pair=4, workers=2)
    try:
        batches = [g.next() for _ in range(3)]
    finally:
        g.close()
    assert [list(b["index"]) for b in batches] == [[4, 5], [6, 7], [8, 9]]
    b = stream.to_batch(batches[0])
    assert b["source"].shape == (2, 32, 3) and b["seg_source"].shape == (2, 32, 4)
    assert torch.allclose(b["seg_source"].sum(-1), torch.ones(2, 32), atol=1e-5)
    # what the readers hand the training loop (pinned where a GPU is present), then moved: the same
    moved = stream.to_device(stream.to_batch(batches[0], "cpu", pin=True), "cpu")
    assert moved.keys() == b.keys() and all(torch.equal(moved[k], b[k]) for k in b)


def test_train_resume_export_curves(tmp_path):
    a = init(tmp_path / "a")
    b = tmp_path / "b"
    shutil.copytree(a, b)
    pytrain(a, 4)
    pytrain(b, 2)
    pytrain(b, 4)  # resumed: the same pairs, Adam state and average as the uninterrupted run
    ca, cb = read_checkpoint(os.path.join(a, "checkpoint.safetensors")), read_checkpoint(os.path.join(b, "checkpoint.safetensors"))
    assert ca["state"]["step"] == cb["state"]["step"] == 4 and ca["state"]["pairs_seen"] == 8
    for k in ca["params"]:
        assert np.array_equal(ca["params"][k], cb["params"][k]), k
        assert np.array_equal(ca["ema"][k], cb["ema"][k]), k
    kinds = [x["kind"] for x in lines(a)]
    assert kinds.count("step") == 4 and "val" in kinds and kinds[-1] == "end"
    out = tmp_path / "w.safetensors"
    run("export", "--run", str(a), "--latest", "--f16", "--out", str(out))
    run("curves", "--run", str(a), "--out", str(tmp_path / "c.svg"))
    assert (tmp_path / "c.svg").read_text().startswith("<svg")


def test_a_fork_at_another_network_n_and_batch(tmp_path):
    d = init(tmp_path / "r")
    pytrain(d, 2)
    # stored as the tree stores a run, its log gzipped: the resumed run's log goes on from it
    log = os.path.join(d, "log.jsonl")
    with open(log, "rb") as src, gzip.open(log + ".gz", "wb") as dst:
        dst.write(src.read())
    os.remove(log)
    train.main(["--run", str(d), "--arps-train", BIN, "--generators", "2", "--steps", "3", "--device", "cpu",
                "--quiet", "--network-points", "24", "--batch", "3", "--val-every-steps", "1"])
    st = read_checkpoint(os.path.join(d, "checkpoint.safetensors"))["state"]
    assert st["config"]["model"]["n_points"] == 24 and st["config"]["batch"] == 3
    # the best so far was measured at the old N: the fork's first validation is its best
    assert st["best_step"] == 3
    assert not os.path.exists(log + ".gz")
    assert [x["kind"] for x in lines(d)].count("start") == 2
    assert st["step"] == 3 and st["pairs_seen"] == 2 * 2 + 3
    out = tmp_path / "w.safetensors"
    run("export", "--run", str(d), "--latest", "--out", str(out))
    assert read_weights(str(out))[0]["n_points"] == 24


def test_a_larger_validation_set_starts_a_new_best(tmp_path):
    d = init(tmp_path / "r")
    pytrain(d, 3)
    path = os.path.join(d, "checkpoint.safetensors")
    ck = read_checkpoint(path)
    assert ck["state"]["best_step"] == 3 and ck["state"]["best_val"]["pairs"] == 4
    # a best no validation could beat: only forgetting it lets the new set's first one be the best
    ck["state"]["best_score"] = 1e9
    save_checkpoint(path, ck["state"], ck["adam"], ck["params"], ck["adam_m"], ck["adam_v"], ck["ema"])
    train.main(["--run", str(d), "--arps-train", BIN, "--generators", "2", "--steps", "4", "--device", "cpu",
                "--quiet", "--val-pairs", "6", "--val-every-steps", "1"])
    st = read_checkpoint(os.path.join(d, "checkpoint.safetensors"))["state"]
    assert st["config"]["val_pairs"] == 6 and st["best_step"] == 4 and st["best_val"]["pairs"] == 6
    with pytest.raises(SystemExit):
        train.main(["--run", str(d), "--arps-train", BIN, "--generators", "1", "--steps", "5", "--device", "cpu",
                    "--quiet", "--val-pairs", "0"])


def test_a_batch_of_zero_is_refused(tmp_path):
    d = init(tmp_path / "r")
    with pytest.raises(SystemExit):
        train.main(["--run", str(d), "--arps-train", BIN, "--generators", "1", "--steps", "1", "--device", "cpu",
                    "--quiet", "--batch", "0"])
    assert read_checkpoint(os.path.join(d, "checkpoint.safetensors"))["state"]["step"] == 0


def test_first_step_losses_equal_the_cpu_trainers(tmp_path):
    a = init(tmp_path / "a")
    c = tmp_path / "c"
    shutil.copytree(a, c)
    pytrain(a, 1)
    run("train", "--run", str(c), "--resume", "--steps", "1", "--quiet")
    sa = [x for x in lines(a) if x["kind"] == "step"][0]
    sc = [x for x in lines(c) if x["kind"] == "step"][0]
    la, lc = sa["loss"], sc["loss"]
    assert la["seg"] > 0.1 and la["consistency_pairs"] > 0, "the terms under test are live"
    for k in ("total", "sup", "ctr", "ctr_no_shift", "consistency", "consistency_pairs", "means", "seg", "gamma_entropy"):
        assert abs(la[k] - lc[k]) <= 1e-4 * max(1.0, abs(lc[k])), f"{k}: torch {la[k]} vs arps-train {lc[k]}"
    assert abs(sa["grad_norm"] - sc["grad_norm"]) <= 1e-4 * sc["grad_norm"]
    # the baseline validation (network only, pair units) agrees with the engine's registrar
    va = [x for x in lines(a) if x["kind"] == "val"][0]["val"]
    vc = [x for x in lines(c) if x["kind"] == "val"][0]["val"]
    for k in ("net_recall", "net_mre", "net_mte"):
        assert abs(va[k] - vc[k]) <= 1e-3 * max(1.0, abs(vc[k])), f"{k}: torch {va[k]} vs arps-train {vc[k]}"


def test_a_failing_compile_falls_back_to_eager(tmp_path, monkeypatch):
    """``--compile`` on a machine whose compiler breaks: the session notes it and trains on."""
    d = init(tmp_path / "r")

    def broken(fn, **_):
        def call(*args, **kwargs):
            raise RuntimeError("no compiler here")
        return call

    monkeypatch.setattr(torch, "compile", broken)
    train.main(["--run", str(d), "--arps-train", BIN, "--generators", "2", "--steps", "3", "--device", "cpu",
                "--quiet", "--compile"])
    log = lines(d)
    notes = [x for x in log if x["kind"] == "note"]
    assert len(notes) == 1 and "no compiler here" in notes[0]["compile_failed"]
    assert [x["kind"] for x in log].count("step") == 3


def test_an_error_in_the_eager_network_is_raised_not_noted(tmp_path, monkeypatch):
    """Without ``--compile`` there is nothing to fall back to: the error ends the session."""
    d = init(tmp_path / "r")

    eager = train.ArpsNet.network

    def broken(self, source, target):  # validation (no gradients) runs; a training step fails
        if torch.is_grad_enabled():
            raise RuntimeError("broken network")
        return eager(self, source, target)

    monkeypatch.setattr(train.ArpsNet, "network", broken)
    with pytest.raises(RuntimeError, match="broken network"):
        train.main(["--run", str(d), "--arps-train", BIN, "--generators", "2", "--steps", "3", "--device", "cpu",
                    "--quiet"])
    assert not [x for x in lines(d) if x["kind"] == "note"]


def test_a_grown_run_loads_computes_the_same_and_trains(tmp_path):
    """`arps-train grow` (wider feed-forward layers) writes a checkpoint this trainer resumes:
    the grown network's memberships equal the original's, and it trains on."""
    from arps_torch.model import ArpsNet

    a = init(tmp_path / "a")
    pytrain(a, 2)
    g = tmp_path / "g"
    run("grow", "--from", str(a), "--run", str(g), "--ffn-dim", "40")
    ca = read_checkpoint(os.path.join(a, "checkpoint.safetensors"))
    cg = read_checkpoint(os.path.join(g, "checkpoint.safetensors"))
    assert cg["state"]["config"]["model"]["ffn_dim"] == 40 and cg["state"]["step"] == 2
    nets = []
    for c in (ca, cg):
        m = ArpsNet(c["state"]["config"]["model"])
        m.load(c["params"])
        nets.append(m)
    gen = torch.Generator().manual_seed(0)
    src, tgt = torch.rand(2, 32, 3, generator=gen) - 0.5, torch.rand(2, 32, 3, generator=gen) - 0.5
    with torch.no_grad():
        oa, og = nets[0](src, tgt), nets[1](src, tgt)
    for k in ("gamma_source", "gamma_target"):
        assert torch.allclose(oa[k], og[k], atol=1e-6), k
    pytrain(g, 4)
    cg = read_checkpoint(os.path.join(g, "checkpoint.safetensors"))
    assert cg["state"]["step"] == 4
    w2 = cg["params"]["layers.0.self_attn.ffn2.weight"].reshape(16, 40)
    assert np.any(w2[:, 16:] != 0), "the new units start to count"


def test_a_slim_run_resumes_from_its_average(tmp_path):
    """`arps-train slim` keeps the moving average as the parameters and no Adam moments; this
    trainer resumes it with Adam restarted (t = 0) and the average started from the parameters."""
    a = init(tmp_path / "a")
    pytrain(a, 3)
    s = tmp_path / "s"
    run("slim", "--from", str(a), "--run", str(s))
    ca = read_checkpoint(os.path.join(a, "checkpoint.safetensors"))
    cs = read_checkpoint(os.path.join(s, "checkpoint.safetensors"))
    assert cs["ema"] is None and not cs["adam_m"] and not cs["adam_v"] and cs["adam"]["t"] == 0
    for name, v in ca["ema"].items():
        assert np.array_equal(cs["params"][name], v), name
    pytrain(s, 5)
    cs = read_checkpoint(os.path.join(s, "checkpoint.safetensors"))
    assert cs["state"]["step"] == 5 and cs["adam"]["t"] == 2 and cs["ema"] is not None
    assert all(np.any(v > 0) for v in cs["adam_v"].values())


def test_part_whole_pairs_are_set_on_resume(tmp_path):
    """``--part-whole`` replaces the run's share of part-against-whole training pairs; the
    generators read it from the run's config and the run trains on."""
    a = init(tmp_path / "a")
    train.main(["--run", str(a), "--arps-train", BIN, "--generators", "1", "--steps", "2", "--device", "cpu",
                "--quiet", "--part-whole", "0.5"])
    c = read_checkpoint(os.path.join(a, "checkpoint.safetensors"))
    assert c["state"]["config"]["part_whole"] == 0.5 and c["state"]["step"] == 2
    with pytest.raises(SystemExit):
        train.main(["--run", str(a), "--arps-train", BIN, "--steps", "3", "--device", "cpu", "--part-whole", "2"])
