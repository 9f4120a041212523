"""The PyTorch training loop: ``python -m arps_torch.train --run RUN --minutes M``.

A run directory is the CPU trainer's: ``checkpoint.safetensors`` (parameters, Adam moments, the
moving average, the ``RunState`` with the run's configuration; ``arps-train init`` writes the
first one), ``best.safetensors`` (engine weights of the best validation), ``log.jsonl`` (the CPU
trainer's line format: ``arps-train curves`` draws it). Data come from ``arps-train stream``
generator processes (``--generators``), from the run's data cursor (``pairs_seen``), so a resumed
run sees exactly the pairs an uninterrupted one would. Every term of the loss, Adam, warm-up,
clipping, the plateau schedule, the moving average and validation follow ``arps-train``.
"""

import argparse
import gzip
import json
import math
import os
import resource
import shutil
import sys
import time

import numpy as np
import torch

from . import TRAINER
from .losses import losses, unpack_parts
from .model import ArpsNet, gmr_both
from .stream import Generators, read_val, to_batch, to_device
from .weights import read_checkpoint, save_checkpoint, weights_bytes, write_atomic

ROT_THRESHOLD = 15.0
TRANS_THRESHOLD = 0.2


def cpu_seconds():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class JsonlLog:
    def __init__(self, path):
        # a run stored with its log gzipped gets it back as the plain file, so the log goes on
        gz = path + ".gz"
        if not os.path.exists(path) and os.path.exists(gz):
            with gzip.open(gz, "rb") as src, open(path + ".part", "wb") as dst:
                shutil.copyfileobj(src, dst)
            os.replace(path + ".part", path)
            os.remove(gz)
        self.f = open(path, "a")

    def write(self, obj):
        obj["time"] = round(time.time(), 3)
        self.f.write(json.dumps(obj, separators=(",", ":")) + "\n")
        self.f.flush()


class Adam:
    """``src/train/optim.rs``'s Adam, exactly (per-tensor float32 moments)."""

    def __init__(self, meta, params, m, v, device):
        self.lr = meta.get("lr", 1e-3)
        self.beta1, self.beta2 = meta.get("beta1", 0.9), meta.get("beta2", 0.999)
        self.eps, self.t = meta.get("eps", 1e-8), meta.get("t", 0)
        self.m = {n: torch.as_tensor(m[n], device=device).view_as(p).clone() if n in m else torch.zeros_like(p)
                  for n, p in params}
        self.v = {n: torch.as_tensor(v[n], device=device).view_as(p).clone() if n in v else torch.zeros_like(p)
                  for n, p in params}

    @torch.no_grad()
    def update(self, params):
        """One step over all tensors at once (``torch._foreach_*``: the same float32 arithmetic,
        element by element, as one op per tensor, in a handful of launches)."""
        self.t += 1
        c1 = 1.0 - self.beta1 ** self.t
        c2 = 1.0 - self.beta2 ** self.t
        step = self.lr / c1
        inv_c2 = 1.0 / c2
        ps = [p for _, p in params]
        gs = [p.grad for p in ps]
        ms = [self.m[n] for n, _ in params]
        vs = [self.v[n] for n, _ in params]
        torch._foreach_mul_(ms, self.beta1)
        torch._foreach_add_(ms, gs, alpha=1 - self.beta1)
        torch._foreach_mul_(vs, self.beta2)
        torch._foreach_addcmul_(vs, gs, gs, value=1 - self.beta2)
        den = torch._foreach_mul(vs, inv_c2)
        torch._foreach_sqrt_(den)
        torch._foreach_add_(den, self.eps)
        upd = torch._foreach_mul(ms, step)
        torch._foreach_div_(upd, den)
        torch._foreach_sub_(ps, upd)

    def meta(self):
        return {"lr": self.lr, "beta1": self.beta1, "beta2": self.beta2, "eps": self.eps, "t": self.t}


def effective_lr(st):
    w = st["config"]["warmup_steps"]
    if w == 0 or st["step"] >= w:
        return st["lr"]
    return st["lr"] * (st["step"] + 1) / w


def score(v):
    return v["net_recall"] - 0.002 * v["net_mre"]


def record_validation(st, v):
    st["validations"] += 1
    st["last_val_elapsed"] = st["elapsed"]
    st["last_val_step"] = st["step"]
    s = score(v)
    improved = st["best_score"] is None or s > st["best_score"]
    if improved:
        st.update(best_score=s, best_step=st["step"], best_pairs_seen=st["pairs_seen"], best_elapsed=st["elapsed"],
                  best_val=v, bad_validations=0)
    else:
        st["bad_validations"] += 1
        if st["bad_validations"] >= max(st["config"]["plateau_patience"], 1):
            st["lr"] = max(st["lr"] * 0.5, st["config"]["min_lr"])
            st["bad_validations"] = 0
    return improved


def rotation_error_deg(a, b):
    r = a[:, :3, :3].transpose(1, 2) @ b[:, :3, :3]
    c = ((r.diagonal(dim1=1, dim2=2).sum(-1) - 1) / 2).clamp(-1, 1)
    return torch.rad2deg(torch.arccos(c))


@torch.no_grad()
def validate(model, recs, device, chunk=64):
    """Network-only metrics on the validation records (pair units, as ``arps-train`` reports)."""
    t0 = time.time()
    res, tes, steps = [], [], []
    for i in range(0, len(recs), chunk):
        b = to_batch(recs[i:i + chunk], device)
        out = model(b["source"], b["target"])
        t_pair = torch.linalg.inv(b["norm_target"]) @ out["t12"] @ b["norm_source"]
        ok = torch.isfinite(t_pair).all(-1).all(-1)
        re = torch.where(ok, rotation_error_deg(t_pair, b["t_gt_pair"]), torch.full_like(ok, 180.0, dtype=torch.float64))
        te = torch.where(ok, (t_pair[:, :3, 3] - b["t_gt_pair"][:, :3, 3]).norm(dim=-1),
                         torch.full_like(ok, math.inf, dtype=torch.float64))
        res.append(re.cpu())
        tes.append(te.cpu())
        steps.append(out["steps"].double().cpu())
    re, te = torch.cat(res), torch.cat(tes)
    recall = ((re < ROT_THRESHOLD) & (te < TRANS_THRESHOLD)).double().mean()
    return {"pairs": len(recs), "net_recall": float(recall), "net_mre": float(re.mean()), "net_mte": float(te.mean()),
            "icp_recall": None, "icp_mre": None, "steps": [float(s) for s in torch.cat(steps).mean(0)],
            "seconds": time.time() - t0}


def provenance(run, st):
    c = st["config"]
    return {
        "trainer": TRAINER, "run": os.path.basename(os.path.normpath(run)), "step": st["best_step"],
        "pairs_seen": st["best_pairs_seen"], "wall_clock_s": round(st["best_elapsed"], 1), "validation": st["best_val"],
        "data": {"procedural": True, "bank": c["bank"], "bank_fraction": c["bank_fraction"],
                 "val_fraction": c["val_fraction"], "pair_points": c["pair_points"],
                 "pose_angle_deg": c.get("pose_angle_deg", 0.0), "curriculum": c["curriculum"],
                 "val_pairs": c["val_pairs"]},
        "losses": c["loss"],
        "optimiser": {"adam_lr": c["lr"], "warmup_steps": c["warmup_steps"], "clip_norm": c["clip_norm"],
                      "batch": c["batch"], "plateau_patience": c["plateau_patience"], "ema_decay": c.get("ema_decay")},
        "seed": c["seed"],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--run", required=True, help="run directory (checkpoint.safetensors from arps-train init)")
    ap.add_argument("--arps-train", default="target/release/arps-train", help="the arps-train binary")
    ap.add_argument("--generators", type=int, default=max(1, (os.cpu_count() or 2) - 2))
    ap.add_argument("--bank", help="read the run's bank from here (e.g. a packed bank); the run keeps its own path")
    ap.add_argument("--minutes", type=float, help="train this many wall-clock minutes")
    ap.add_argument("--steps", type=int, help="train until the run's step count reaches this")
    ap.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    ap.add_argument("--amp", choices=["off", "bf16"], default="off",
                    help="bf16 autocast for the network (GMR and the losses stay float64)")
    ap.add_argument("--tf32", action="store_true", help="allow TF32 matmuls on the GPU")
    ap.add_argument("--checkpoint-every-minutes", type=float, help="override the run's checkpoint interval")
    ap.add_argument("--val-every-minutes", type=float, help="override the run's validation interval")
    ap.add_argument("--val-every-steps", type=int, help="override: validate every S steps")
    ap.add_argument("--batch", type=int, help="override the run's pairs per step")
    ap.add_argument("--lr", type=float, help="replace the run's current lr")
    ap.add_argument("--val-pairs", type=int,
                    help="validate on this many held-out pairs from now on (the best so far, measured on the old "
                         "set, is forgotten)")
    ap.add_argument("--part-whole", type=float,
                    help="replace the share of training pairs that are a part of a shape against the whole of it "
                         "(arps-train train --part-whole; validation keeps the protocol)")
    ap.add_argument("--network-points", type=int,
                    help="replace the run's network N (a fork that fine-tunes at another N; the weights do not depend on it)")
    ap.add_argument("--compile", action="store_true",
                    help="torch.compile the network's forward and backward (static shapes; the first step compiles)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    torch.backends.cuda.matmul.allow_tf32 = a.tf32
    torch.backends.cudnn.allow_tf32 = a.tf32
    ckpt_path = os.path.join(a.run, "checkpoint.safetensors")
    best_path = os.path.join(a.run, "best.safetensors")
    ck = read_checkpoint(ckpt_path)
    st = ck["state"]
    cfg = st["config"]
    if a.batch is not None:
        if a.batch < 1:
            ap.error(f"--batch {a.batch}: a step needs at least one pair")
        cfg["batch"] = a.batch
    if a.network_points is not None:
        if a.network_points < 1:
            ap.error(f"--network-points {a.network_points} must be positive")
        if a.network_points != cfg["model"]["n_points"]:
            # a fork at another N: the best so far was measured at the old N
            cfg["model"]["n_points"] = a.network_points
            st.update(best_score=None, best_val=None, bad_validations=0)
    if a.val_pairs is not None:
        if a.val_pairs < 1:
            ap.error(f"--val-pairs {a.val_pairs}: validation needs at least one pair")
        if a.val_pairs != cfg["val_pairs"]:
            # another validation set: scores on the old one do not compare with it
            cfg["val_pairs"] = a.val_pairs
            st.update(best_score=None, best_val=None, bad_validations=0)
    if a.part_whole is not None:
        if not 0.0 <= a.part_whole <= 1.0:
            ap.error(f"--part-whole {a.part_whole}: expected a share in [0, 1]")
        cfg["part_whole"] = a.part_whole
    if a.checkpoint_every_minutes is not None:
        cfg["checkpoint_every_minutes"] = a.checkpoint_every_minutes
        cfg["checkpoint_every_steps"] = None
    if a.val_every_minutes is not None:
        cfg["val_every_minutes"] = a.val_every_minutes
    if a.val_every_steps is not None:
        cfg["val_every_steps"] = a.val_every_steps or None
    if a.lr is not None:
        st["lr"] = a.lr
        st["bad_validations"] = 0
    st["sessions"] += 1
    st["trainer"] = TRAINER
    dev = torch.device(a.device)
    model = ArpsNet(cfg["model"]).to(dev)
    model.load({n: ck["params"][n] for n, _ in model.specs})
    params = model.named()
    compiled = a.compile
    network = torch.compile(model.network, dynamic=False) if compiled else model.network
    adam = Adam(ck["adam"], params, ck["adam_m"], ck["adam_v"], dev)
    ema_decay = cfg.get("ema_decay")
    ema = None
    if ema_decay:
        src = ck["ema"] or {n: p.detach().cpu().numpy() for n, p in params}
        ema = {n: torch.as_tensor(src[n], device=dev).view_as(p).clone() for n, p in params}
    # the stream's config: the run's, as stored now (the generators read it from a file)
    stream_cfg = os.path.join(a.run, "stream-config.json")
    write_atomic(stream_cfg, json.dumps({**cfg, "bank": a.bank or cfg["bank"]}, indent=1).encode())
    logf = JsonlLog(os.path.join(a.run, "log.jsonl"))
    say = (lambda s: None) if a.quiet else (lambda s: print(f"[{time.strftime('%H:%M:%S')}] {s}", file=sys.stderr, flush=True))
    t0 = time.time()
    vh, val = read_val(a.arps_train, stream_cfg, count=cfg["val_pairs"], threads=max(1, a.generators))
    say(f"run {a.run} session {st['sessions']}: step {st['step']}, pairs seen {st['pairs_seen']}, "
        f"{len(val)} validation pairs in {time.time() - t0:.1f} s, device {dev}")
    logf.write({"kind": "start", "session": st["sessions"], "step": st["step"], "pairs_seen": st["pairs_seen"],
                "elapsed": st["elapsed"], "lr": st["lr"], "threads": a.generators, "config": cfg,
                "trainer": TRAINER, "device": str(dev), "amp": a.amp, "compile": a.compile})
    # the readers convert each batch to (pinned) CPU tensors off the training thread
    pin = dev.type == "cuda"
    gens = Generators(a.arps_train, stream_cfg, st["pairs_seen"], a.generators, bank=None,
                      convert=lambda recs: to_batch(recs, "cpu", pin=pin))
    if gens.header["batch"] != cfg["batch"]:
        raise RuntimeError("generator batch differs from the run's")

    def eval_model():
        if ema is None:
            return model
        m = ArpsNet(cfg["model"]).to(dev)
        m.load({n: v.cpu() for n, v in ema.items()})
        return m

    session = time.time()
    elapsed0, cpu0 = st["elapsed"], st.get("cpu", 0.0) - cpu_seconds()

    def do_validate():
        st["cpu"] = cpu0 + cpu_seconds()
        em = eval_model()
        v = validate(em, val, dev)
        v_raw = validate(model, val, dev) if ema is not None else None
        improved = record_validation(st, v)
        if improved:
            write_atomic(best_path, weights_bytes(cfg["model"], em.state(), provenance(a.run, st)))
        logf.write({"kind": "val", "step": st["step"], "pairs_seen": st["pairs_seen"], "elapsed": st["elapsed"],
                    "cpu": st["cpu"], "lr": st["lr"], "val": v, "score": score(v), "improved": improved,
                    "best_score": st["best_score"], "val_raw": v_raw, "ema_decay": ema_decay})
        say(f"val @{st['step']}: net recall {v['net_recall']:.3f} MRE {v['net_mre']:.2f} MTE {v['net_mte']:.3f} "
            f"best {st['best_score']:.4f} @{st['best_step']} lr {st['lr']:.2e} ({v['seconds']:.1f} s)")

    def save():
        st["adam_t"] = adam.t
        st["cpu"] = cpu0 + cpu_seconds()
        cpu = lambda d: {n: t.detach().cpu().numpy() for n, t in d.items()}
        save_checkpoint(ckpt_path, st, {**adam.meta(), "lr": adam.lr}, cpu(dict(params)), cpu(adam.m), cpu(adam.v),
                        cpu(ema) if ema is not None else None)
        logf.write({"kind": "checkpoint", "step": st["step"], "pairs_seen": st["pairs_seen"], "elapsed": st["elapsed"]})

    if st["validations"] == 0 and st["step"] == 0:
        do_validate()
    window, w_gn, w_clipped, w_skipped, w_time, w_data, w_steps = [], 0.0, 0, 0, 0.0, 0.0, 0
    last_ckpt = time.time()
    stop_file = os.path.join(a.run, "STOP")
    stopped_by_file = False
    clip = cfg.get("clip_norm")
    autocast = torch.autocast(dev.type, dtype=torch.bfloat16, enabled=a.amp == "bf16")
    try:
        while True:
            if (a.steps is not None and st["step"] >= a.steps) or (
                    a.minutes is not None and time.time() - session >= a.minutes * 60):
                break
            if os.path.exists(stop_file):
                stopped_by_file = True
                os.remove(stop_file)
                break
            ts = time.time()
            b = to_device(gens.next(), dev)
            data_s = time.time() - ts
            adam.lr = effective_lr(st)
            for _, p in params:
                p.grad = None
            with autocast:
                try:
                    net = network(b["source"], b["target"])
                except Exception as e:  # a compiler that fails here must not end a GPU session
                    if not compiled:
                        raise
                    say(f"--compile failed ({type(e).__name__}: {e}); training uncompiled")
                    logf.write({"kind": "note", "step": st["step"], "pairs_seen": st["pairs_seen"],
                                "elapsed": st["elapsed"], "compile_failed": f"{type(e).__name__}: {e}"})
                    compiled, network = False, model.network
                    net = network(b["source"], b["target"])
            net = {k: v.float() for k, v in net.items()}
            net["t12"], net["t21"] = gmr_both(net["gamma_source"], net["gamma_target"], b["source"], b["target"])
            total, parts_t, keys = losses(net, b, cfg["loss"])
            total.backward()
            for _, p in params:
                if p.grad is None:
                    p.grad = torch.zeros_like(p)
            grads = [p.grad for _, p in params]
            # the global norm in float64, as the CPU trainer sums it; it and the loss terms reach
            # the host in one transfer, the step's only device sync
            flat = torch.cat([g.reshape(-1) for g in grads]).double()
            gn_t = (flat * flat).sum().sqrt()
            host = torch.cat([gn_t.view(1), parts_t]).cpu().tolist()
            gn, parts = host[0], unpack_parts(keys, host[1:])
            skipped = not (math.isfinite(gn) and all(math.isfinite(v) for k, v in parts.items() if k != "steps"))
            clipped = False
            if not skipped:
                if clip and gn > clip:
                    torch._foreach_mul_(grads, clip / gn)
                    clipped = True
                adam.update(params)
                if ema is not None:
                    with torch.no_grad():
                        emas = [ema[n] for n, _ in params]
                        torch._foreach_mul_(emas, ema_decay)
                        torch._foreach_add_(emas, [p for _, p in params], alpha=1 - ema_decay)
            else:
                st["skipped_steps"] += 1
            st["step"] += 1
            st["adam_t"] = adam.t
            st["pairs_seen"] += cfg["batch"]
            st["elapsed"] = elapsed0 + time.time() - session
            dt = time.time() - ts
            if not skipped:
                window.append(parts)
                w_gn += gn
            w_clipped += clipped
            w_skipped += skipped
            w_time += dt
            w_data += data_s
            w_steps += 1
            if st["step"] % cfg["log_every_steps"] == 0:
                n = max(len(window), 1)
                keys = [k for k in (window[0] if window else {}) if k != "steps"]
                m = {k: round(sum(w[k] for w in window) / n, 6) for k in keys}
                if window:
                    m["steps"] = [round(sum(w["steps"][i] for w in window) / n, 6) for i in range(len(window[0]["steps"]))]
                pps = w_steps * cfg["batch"] / max(w_time, 1e-9)
                st["cpu"] = cpu0 + cpu_seconds()
                logf.write({"kind": "step", "step": st["step"], "pairs_seen": st["pairs_seen"],
                            "elapsed": round(st["elapsed"], 1), "cpu": round(st["cpu"], 1), "lr": adam.lr, "loss": m,
                            "grad_norm": w_gn / n, "clipped": w_clipped, "skipped": w_skipped,
                            "skipped_total": st["skipped_steps"], "pairs_per_s": round(pps, 2),
                            "data_fraction": round(w_data / max(w_time, 1e-9), 3)})
                say(f"step {st['step']} pairs {st['pairs_seen']} loss {m.get('total', float('nan')):.4f} "
                    f"gn {w_gn / n:.3f} lr {adam.lr:.2e} {pps:.1f} pairs/s (data {w_data / max(w_time, 1e-9):.0%})")
                window, w_gn, w_clipped, w_skipped, w_time, w_data, w_steps = [], 0.0, 0, 0, 0.0, 0.0, 0
            if cfg.get("val_every_steps"):
                val_due = st["step"] % cfg["val_every_steps"] == 0
            else:
                val_due = st["elapsed"] - st["last_val_elapsed"] >= cfg["val_every_minutes"] * 60
            if val_due:
                do_validate()
            if cfg.get("checkpoint_every_steps"):
                ck_due = st["step"] % cfg["checkpoint_every_steps"] == 0
            else:
                ck_due = time.time() - last_ckpt >= cfg["checkpoint_every_minutes"] * 60
            if ck_due:
                save()
                last_ckpt = time.time()
    finally:
        gens.close()
    save()
    logf.write({"kind": "end", "cpu": st["cpu"], "step": st["step"], "pairs_seen": st["pairs_seen"],
                "elapsed": st["elapsed"], "stopped_by_file": stopped_by_file, "best_score": st["best_score"],
                "best_step": st["best_step"]})
    say(f"step {st['step']}, {st['pairs_seen']} pairs seen, {st['elapsed'] / 60:.1f} min, best score "
        f"{st['best_score']} at step {st['best_step']} -> {ckpt_path}")


if __name__ == "__main__":
    main()
