"""The engine's DGMR-ARPS network (``src/model``, ``src/train/model.rs``) in PyTorch, batched:
pre-centring, ``f0 = 0``, tokens ``[f ; pos(x)]``, post-norm self then cross attention, the
``out`` projection, the soft (or top-H) reference point, the step MLP and shifting, then the
membership head; the GMM parameters and the weighted Procrustes solve (``gmr``) run in float64
on the raw input coordinates, as in the engine. Parameters carry the engine's tensor names."""

import torch
import torch.nn.functional as F
from torch import nn

from .config import check, tensor_specs

GMM_EPS = 1e-8
MIN_VAR = 1e-8


class ArpsNet(nn.Module):
    """The network for one ``ModelConfig`` (dict). ``forward(source, target)`` takes
    ``[B, Ns, 3]`` and ``[B, Nt, 3]`` float32 clouds in engine-normalised units."""

    def __init__(self, cfg: dict):
        super().__init__()
        self.cfg = check(dict(cfg))
        self.specs = tensor_specs(self.cfg)
        self.index = {name: i for i, (name, _) in enumerate(self.specs)}
        self.tensors = nn.ParameterList([nn.Parameter(torch.zeros(shape)) for _, shape in self.specs])
        self._by_name = self._names()

    def _names(self):
        return {name: self.tensors[i] for name, i in self.index.items()}

    def _apply(self, fn, *args, **kwargs):
        out = super()._apply(fn, *args, **kwargs)
        self._by_name = self._names()  # ``.to(device)`` may replace the parameters
        return out

    def p(self, name: str) -> torch.Tensor:
        return self._by_name[name]

    def named(self):
        """``[(engine name, parameter)]`` in the engine's order."""
        return [(name, self.tensors[i]) for i, (name, _) in enumerate(self.specs)]

    def load(self, tensors: dict):
        """Copies ``{engine name: array}`` into the parameters (every tensor, exact shapes)."""
        names = {n for n, _ in self.specs}
        extra = set(tensors) - names
        if extra:
            raise ValueError(f"tensor {sorted(extra)[0]!r} is not part of the config")
        with torch.no_grad():
            for name, shape in self.specs:
                if name not in tensors:
                    raise ValueError(f"tensor {name!r} is missing")
                v = torch.as_tensor(tensors[name], dtype=torch.float32)
                if list(v.shape) != list(shape):
                    v = v.reshape(shape) if v.numel() == torch.Size(shape).numel() else None
                    if v is None:
                        raise ValueError(f"tensor {name!r} has the wrong size")
                self.p(name).copy_(v)

    def state(self) -> dict:
        """``{engine name: float32 CPU tensor}``."""
        return {n: p.detach().float().cpu().contiguous() for n, p in self.named()}

    def linear(self, x, name):
        return F.linear(x, self.p(f"{name}.weight"), self.p(f"{name}.bias"))

    def mlp(self, x, prefix, layers, relu_last):
        for i in range(layers):
            x = self.linear(x, f"{prefix}.{i}")
            if i + 1 < layers or relu_last:
                x = F.relu(x)
        return x

    def block(self, x, kv, name):
        cfg = self.cfg
        b, nq, d = x.shape
        h = cfg["heads"]
        q = self.linear(x, f"{name}.q").view(b, nq, h, d // h).transpose(1, 2)
        k = self.linear(kv, f"{name}.k").view(b, kv.shape[1], h, d // h).transpose(1, 2)
        v = self.linear(kv, f"{name}.v").view(b, kv.shape[1], h, d // h).transpose(1, 2)
        a = F.scaled_dot_product_attention(q, k, v).transpose(1, 2).reshape(b, nq, d)
        eps = cfg["layer_norm_eps"]
        r = F.layer_norm(x + self.linear(a, f"{name}.o"), (d,), self.p(f"{name}.norm1.weight"),
                         self.p(f"{name}.norm1.bias"), eps)
        f = self.linear(F.relu(self.linear(r, f"{name}.ffn1")), f"{name}.ffn2")
        return F.layer_norm(r + f, (d,), self.p(f"{name}.norm2.weight"), self.p(f"{name}.norm2.bias"), eps)

    def reference(self, f, layer):
        """Reference weights over the points, ``[B, N]``."""
        cfg = self.cfg
        if cfg["reference"] == "soft":
            s = self.linear(f, f"{layer}.score").squeeze(-1) / cfg["soft_temperature"]
            return torch.softmax(s, dim=-1)
        n = f.shape[1]
        h = min(cfg["top_h"], n)
        norms = (f.detach() ** 2).sum(-1)
        idx = torch.argsort(-norms, dim=-1, stable=True)[:, :h]
        w = torch.zeros_like(norms)
        return w.scatter(1, idx, 1.0 / h)

    def network(self, source, target):
        """Memberships and per-layer steps and shifts: ``dict(gamma_source [B, Ns, J],
        gamma_target, steps [B, L], shifts_source [B, L, 3], shifts_target)``. Clouds of one size
        run as one batch of 2B (the same weights, half the operations to issue); others apart."""
        cfg = self.cfg
        c = cfg["feature_dim"]
        lay = _Joint(source.shape[0]) if source.shape == target.shape else _Apart()
        x = lay.groups(centred(source), centred(target))
        f = [xi.new_zeros(xi.shape[:2] + (c,)) for xi in x]
        npos = len(cfg["pos_hidden"]) + 1
        steps, shifts = [], [[], []]
        for l in range(cfg["layers"]):
            p = f"layers.{l}"
            g = [torch.cat([fi, self.mlp(xi, f"{p}.pos", npos, True)], -1) for fi, xi in zip(f, x)]
            g1 = [self.block(gi, gi, f"{p}.self_attn") for gi in g]
            g2 = [self.block(gi, kv, f"{p}.cross_attn") for gi, kv in zip(g1, lay.swap(g1))]
            f = [self.linear(gi, f"{p}.out") for gi in g2]
            w = [self.reference(fi, p).unsqueeze(-1) for fi in f]
            mux = [(wi * xi).sum(1) for wi, xi in zip(w, x)]
            muf = [(wi * fi).sum(1) for wi, fi in zip(w, f)]
            (mxs, mxt), (mfs, mft) = lay.parts(mux), lay.parts(muf)
            alpha = self.mlp(torch.cat([mxs - mxt, mfs - mft], -1), f"{p}.step", 2, False)
            st = torch.sigmoid(alpha)
            d = [mi * si for mi, si in zip(mux, lay.both(st))]
            x = [xi - di.unsqueeze(1) for xi, di in zip(x, d)]
            for s, ds in enumerate(lay.parts(d)):
                shifts[s].append(ds)
            steps.append(st.squeeze(-1))
        nhead = len(cfg["head_hidden"]) + 1
        gammas = []
        for fi in f:
            colmax = fi.max(dim=1, keepdim=True).values.expand_as(fi)
            logits = self.mlp(torch.cat([fi, colmax], -1), "head", nhead, False)
            gammas.append(torch.softmax(logits.float(), dim=-1))
        gamma_source, gamma_target = lay.parts(gammas)
        return {
            "gamma_source": gamma_source,
            "gamma_target": gamma_target,
            "steps": torch.stack(steps, 1).float(),
            "shifts_source": torch.stack(shifts[0], 1).float(),
            "shifts_target": torch.stack(shifts[1], 1).float(),
        }

    def forward(self, source, target):
        """``network`` plus ``t12`` (``T_target_source``) and ``t21``, ``[B, 4, 4]`` float64."""
        out = self.network(source, target)
        out["t12"], out["t21"] = gmr_both(out["gamma_source"], out["gamma_target"], source, target)
        return out


class _Joint:
    """Source and target as one batch: ``[source; target]``, ``2B`` clouds of one size."""

    def __init__(self, b):
        self.b = b

    def groups(self, source, target):
        return [torch.cat([source, target])]

    def swap(self, g):
        """What each cloud attends to in cross attention: the other cloud."""
        return [torch.cat([g[0][self.b:], g[0][:self.b]])]

    def parts(self, g):
        """``(source's, target's)``."""
        return g[0][:self.b], g[0][self.b:]

    def both(self, t):
        """A per-pair tensor for both clouds."""
        return [torch.cat([t, t])]


class _Apart:
    """Source and target as two batches (clouds of different sizes)."""

    def groups(self, source, target):
        return [source, target]

    def swap(self, g):
        return [g[1], g[0]]

    def parts(self, g):
        return g[0], g[1]

    def both(self, t):
        return [t, t]


def centred(points):
    """The engine's pre-centring: the float64 mean, rounded to float32, subtracted."""
    mean = points.double().mean(1, keepdim=True).float()
    return points - mean


def gmm(points, gamma):
    """GMM parameters (``src/gmr.rs::gmm_params``) in float64: ``pi [B, J]``, ``mu [B, J, 3]``,
    ``var [B, J]``."""
    x = points.double()
    g = gamma.double()
    mass = g.sum(1)
    mu = torch.einsum("bnj,bnk->bjk", g, x) / (mass + GMM_EPS).unsqueeze(-1)
    d2 = ((x.unsqueeze(2) - mu.unsqueeze(1)) ** 2).sum(-1)
    var = ((g * d2).sum(1) / (mass + GMM_EPS)).clamp_min(MIN_VAR)
    pi = mass / x.shape[1]
    return pi, mu, var


def solve(pi_s, mu_s, mu_t, var_t):
    """Weighted Procrustes (``src/gmr.rs::solve``): ``T_target_source`` ``[B, 4, 4]`` float64.
    (The engine's fallbacks for degenerate inputs, rank-one and non-finite, are not mirrored.)"""
    total = pi_s.sum(-1, keepdim=True)
    cs = (pi_s.unsqueeze(-1) * mu_s).sum(1) / total
    ct = (pi_s.unsqueeze(-1) * mu_t).sum(1) / total
    w = (pi_s / total) / var_t.clamp_min(MIN_VAR)
    a = mu_s - cs.unsqueeze(1)
    b = mu_t - ct.unsqueeze(1)
    m = torch.einsum("bj,bjk,bjl->bkl", w, a, b)
    scale = m.abs().amax(dim=(1, 2), keepdim=True).clamp_min(1e-300)
    u, _, vh = torch.linalg.svd(m / scale)
    v = vh.transpose(1, 2)
    det = torch.linalg.det(v @ u.transpose(1, 2))
    dm = torch.ones_like(det).unsqueeze(-1).repeat(1, 3)
    dm = torch.cat([dm[:, :2], torch.where(det < 0, -1.0, 1.0).unsqueeze(-1)], 1)
    r = v @ torch.diag_embed(dm) @ u.transpose(1, 2)
    t = ct - (r @ cs.unsqueeze(-1)).squeeze(-1)
    out = torch.zeros(r.shape[0], 4, 4, dtype=torch.float64, device=r.device)
    out[:, :3, :3] = r
    out[:, :3, 3] = t
    out[:, 3, 3] = 1.0
    return out


def gmr(gamma_s, gamma_t, source, target):
    """``T_target_source`` from memberships of both clouds (raw coordinates), float64."""
    pi_s, mu_s, _ = gmm(source, gamma_s)
    _, mu_t, var_t = gmm(target, gamma_t)
    return solve(pi_s, mu_s, mu_t, var_t)


def gmr_both(gamma_s, gamma_t, source, target):
    """``(T_target_source, T_source_target)``: ``gmr`` both ways, as one batch of 2B when the
    clouds have one size."""
    if source.shape != target.shape:
        return gmr(gamma_s, gamma_t, source, target), gmr(gamma_t, gamma_s, target, source)
    b = source.shape[0]
    t = gmr(torch.cat([gamma_s, gamma_t]), torch.cat([gamma_t, gamma_s]), torch.cat([source, target]),
            torch.cat([target, source]))
    return t[:b], t[b:]
