"""The CPU trainer's losses (``src/train/losses.rs``), batched: each term per pair, the batch's
value the mean over pairs (the CPU trainer averages per-pair gradients, the same thing). The
weights come from the run's ``LossConfig`` JSON (``sup``, ``ctr``, ``ctr_mode``, ``stp``,
``aff``, ``reg``, ``consistency``, ``consistency_kind``, ``means``, ``seg``); the targets the
losses need that depend on the data (the canonical partition, the consistency correspondences)
come precomputed in the stream, from the same Rust code the CPU trainer uses."""

import math

import torch

from .model import gmm

P_MIN = 1e-8
SPREAD_FLOOR = 0.01


def _eye(b, device):
    return torch.eye(4, dtype=torch.float64, device=device).expand(b, 4, 4)


def rigid_inverse(t):
    r = t[:, :3, :3]
    out = torch.zeros_like(t)
    out[:, :3, :3] = r.transpose(1, 2)
    out[:, :3, 3] = -(r.transpose(1, 2) @ t[:, :3, 3:]).squeeze(-1)
    out[:, 3, 3] = 1.0
    return out


def means_alignment(gamma_s, gamma_t, source, target, t_gt):
    """``(L, spread)`` per pair (``src/train/ops/alignment.rs``)."""
    pi_s, mu_s, _ = gmm(source, gamma_s)
    pi_t, mu_t, _ = gmm(target, gamma_t)
    w = 0.5 * (pi_s + pi_t)
    wsum = w.sum(-1, keepdim=True).clamp_min(1e-12)
    cs = (w.unsqueeze(-1) * mu_s).sum(1) / wsum
    ct = (w.unsqueeze(-1) * mu_t).sum(1) / wsum
    r = t_gt[:, :3, :3]
    d = mu_s @ r.transpose(1, 2) + t_gt[:, :3, 3].unsqueeze(1) - mu_t
    a = (w * (d ** 2).sum(-1)).sum(-1)
    s = 0.5 * (w * (((mu_s - cs.unsqueeze(1)) ** 2).sum(-1) + ((mu_t - ct.unsqueeze(1)) ** 2).sum(-1))).sum(-1)
    return a / (s + SPREAD_FLOOR), s


def consistency(gamma_s, gamma_t, corr, kind):
    """Mean over corresponding pairs of the divergence of membership rows, per pair (0 when a
    pair has no correspondences), and the number of correspondences."""
    mask = corr >= 0
    idx = corr.clamp_min(0).long()
    y = torch.gather(gamma_t, 1, idx.unsqueeze(-1).expand(-1, -1, gamma_t.shape[-1]))
    x = gamma_s
    if kind == "squared":
        div = ((x - y) ** 2).sum(-1)
    else:
        div = ((x - y) * (x.clamp_min(P_MIN).log() - y.clamp_min(P_MIN).log())).sum(-1)
    n = mask.sum(-1)
    val = (div.double() * mask).sum(-1) / n.clamp_min(1)
    return val, n.double()


def membership_kl(gamma, p):
    """``mean_i KL(p_i || gamma_i)`` per pair (``gamma`` clamped at 1e-8 in the log)."""
    p = p.double()
    g = gamma.double().clamp_min(P_MIN)
    terms = torch.where(p > 0, p * (p.clamp_min(1e-300).log() - g.log()), torch.zeros_like(p))
    return terms.sum(-1).mean(-1)


def chamfer_sq(a, b):
    d = torch.cdist(a, b) ** 2
    return d.min(2).values.mean(-1) + d.min(1).values.mean(-1)


def row_entropy(gamma):
    j = gamma.shape[-1]
    if j < 2:
        return torch.zeros(gamma.shape[0], dtype=torch.float64, device=gamma.device)
    g = gamma.double()
    h = torch.where(g > 0, -g * g.clamp_min(1e-300).log(), torch.zeros_like(g)).sum(-1)
    return h.mean(-1) / math.log(j)


def losses(out, batch, cfg):
    """``(total, parts, keys)``: the weighted total (a scalar to differentiate, the batch mean),
    the terms' batch means named ``keys`` (as in the CPU trainer's log) followed by the mean step
    per layer, in one float64 tensor left on the device (``unpack_parts`` reads its host copy)."""
    b = batch["source"].shape[0]
    dev = batch["source"].device
    t_gt = batch["t_gt"]
    eye = _eye(b, dev)
    per = {}
    terms = []
    a = out["t12"] @ rigid_inverse(t_gt)
    bb = out["t21"] @ t_gt
    per["sup"] = ((a - eye) ** 2).sum((1, 2)) / 16 + ((bb - eye) ** 2).sum((1, 2)) / 16
    if cfg["sup"] != 0:
        terms.append((per["sup"], cfg["sup"]))
    layers = out["shifts_source"].shape[1]
    ctr = torch.zeros(b, dtype=torch.float64, device=dev)
    no_shift = torch.zeros(b, dtype=torch.float64, device=dev)
    for shifts, v in ((out["shifts_source"], batch["v_gt_source"]), (out["shifts_target"], batch["v_gt_target"])):
        no_shift = no_shift + (v.double() ** 2).sum(-1)
        cum = shifts.double().cumsum(1)
        err = ((cum - v.double().unsqueeze(1)) ** 2).sum(-1)
        if cfg.get("ctr_mode", "every_layer") == "every_layer":
            ctr = ctr + err.sum(-1) / layers
        else:
            ctr = ctr + err[:, -1]
    per["ctr"] = ctr
    per["ctr_no_shift"] = no_shift
    if cfg["ctr"] != 0:
        terms.append((ctr, cfg["ctr"]))
    per["stp"] = (out["steps"].double() ** 2).sum(-1)
    if cfg["stp"] != 0:
        terms.append((per["stp"], cfg["stp"]))
    per["aff"] = 3.0 / 16.0 * ((out["t12"] @ out["t21"] - eye) ** 2).sum((1, 2))
    if cfg["aff"] != 0:
        terms.append((per["aff"], cfg["aff"]))
    zero = torch.zeros(b, dtype=torch.float64, device=dev)
    per["reg"] = zero
    if cfg["reg"] != 0:
        t12 = out["t12"].float()
        moved = batch["source"] @ t12[:, :3, :3].transpose(1, 2) + t12[:, :3, 3].unsqueeze(1)
        per["reg"] = chamfer_sq(moved, batch["target"]).double()
        terms.append((per["reg"], cfg["reg"]))
    per["consistency"], per["consistency_pairs"] = zero, zero
    if cfg["consistency"] != 0:
        per["consistency"], per["consistency_pairs"] = consistency(
            out["gamma_source"], out["gamma_target"], batch["corr"], cfg.get("consistency_kind", "symmetric_kl"))
        terms.append((per["consistency"], cfg["consistency"]))
    per["means"], per["means_spread"] = means_alignment(
        out["gamma_source"], out["gamma_target"], batch["source"], batch["target"], t_gt)
    if cfg.get("means", 0) != 0:
        terms.append((per["means"], cfg["means"]))
    per["seg"] = zero
    if cfg.get("seg", 0) != 0:
        per["seg"] = 0.5 * (membership_kl(out["gamma_source"], batch["seg_source"])
                            + membership_kl(out["gamma_target"], batch["seg_target"]))
        terms.append((per["seg"], cfg["seg"]))
    per["gamma_entropy"] = 0.5 * (row_entropy(out["gamma_source"]) + row_entropy(out["gamma_target"]))
    total = sum((v * w for v, w in terms), zero)
    per["total"] = total
    keys = list(per)
    parts = torch.cat([torch.stack([per[k].detach().double().mean() for k in keys]),
                       out["steps"].detach().double().mean(0)])
    return total.mean(), parts, keys


def unpack_parts(keys, values):
    """The host copy of ``losses``' parts tensor as ``{term: float, "steps": [float per layer]}``."""
    parts = dict(zip(keys, values[:len(keys)]))
    parts["steps"] = list(values[len(keys):])
    return parts
