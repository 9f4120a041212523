"""Reads the binary training-data stream that ``arps-train stream`` writes (layout documented in
``src/train/run/stream.rs``), and runs several generator processes whose batches, read
round-robin, are the CPU trainer's batches in the CPU trainer's order."""

import json
import queue
import subprocess
import threading

import numpy as np
import torch

MAGIC = b"ARPSSTRM"
VERSION = 1
DTYPES = {"u64": "<u8", "i32": "<i4", "f32": "<f4", "f64": "<f8"}


def _read_exact(f, n):
    buf = bytearray()
    while len(buf) < n:
        chunk = f.read(n - len(buf))
        if not chunk:
            return bytes(buf)
        buf += chunk
    return bytes(buf)


def read_header(f):
    """The header dict (checked), from a binary file object."""
    magic = _read_exact(f, 8)
    if magic != MAGIC:
        raise ValueError("not an arps stream (bad magic)")
    n = int.from_bytes(_read_exact(f, 4), "little")
    if n > 1 << 20:
        raise ValueError(f"stream header of {n} bytes is too long")
    h = json.loads(_read_exact(f, n))
    if h.get("version") != VERSION:
        raise ValueError(f"stream layout version {h.get('version')} (this trainer reads {VERSION})")
    return h


def record_dtype(h):
    """The numpy structured dtype of one record (packed, no padding)."""
    return np.dtype([(fd["name"], DTYPES[fd["dtype"]], tuple(fd["shape"])) for fd in h["fields"]])


def read_records(f, h, count):
    """``count`` records as a structured array (fewer at the end of the stream)."""
    dt = record_dtype(h)
    data = _read_exact(f, dt.itemsize * count)
    if len(data) % dt.itemsize:
        raise ValueError("stream ends inside a record")
    return np.frombuffer(data, dtype=dt)


def to_batch(recs, device="cpu", pin=False):
    """Records -> the tensors the model and losses take (with ``pin``, on the CPU in page-locked
    memory, ready for an asynchronous copy to a GPU: see ``to_device``)."""
    def t(k, dt=None):
        x = torch.from_numpy(np.ascontiguousarray(recs[k])).to(device=device, dtype=dt)
        if pin:
            try:
                return x.pin_memory()
            except RuntimeError:  # no page-locked memory to be had: an ordinary copy still works
                return x
        return x
    return {
        "index": torch.from_numpy(recs["index"].astype(np.int64)),
        "source": t("source", torch.float32),
        "target": t("target", torch.float32),
        "t_gt": t("t_gt", torch.float64),
        "v_gt_source": t("v_gt_source", torch.float32),
        "v_gt_target": t("v_gt_target", torch.float32),
        "seg_source": t("seg_source", torch.float32),
        "seg_target": t("seg_target", torch.float32),
        "corr": t("corr", torch.int64),
        "norm_source": t("norm_source", torch.float64),
        "norm_target": t("norm_target", torch.float64),
        "t_gt_pair": t("t_gt_pair", torch.float64),
    }


def to_device(batch, device):
    """A ``to_batch`` of CPU tensors moved to ``device`` (asynchronously from pinned memory; the
    stream orders the copies before the step's kernels). ``index`` stays on the CPU."""
    return {k: v if k == "index" else v.to(device, non_blocking=True) for k, v in batch.items()}


def stream_command(binary, config, first_pair=0, worker=0, workers=1, count=None, val=False, threads=1, bank=None):
    cmd = [binary, "stream", "--config", str(config), "--threads", str(threads)]
    if val:
        cmd += ["--val"]
    else:
        cmd += ["--first-pair", str(first_pair), "--worker", str(worker), "--workers", str(workers)]
    if count is not None:
        cmd += ["--count", str(count)]
    if bank:
        cmd += ["--bank", str(bank)]
    return cmd


def read_val(binary, config, count=None, bank=None, threads=1):
    """``(header, records)`` of the validation pairs (one process)."""
    p = subprocess.Popen(stream_command(binary, config, val=True, count=count, bank=bank, threads=threads),
                         stdout=subprocess.PIPE)
    h = read_header(p.stdout)
    recs = read_records(p.stdout, h, h["batches"])
    if p.wait() != 0 or len(recs) != h["batches"]:
        raise RuntimeError(f"validation stream failed (exit {p.returncode}, {len(recs)} of {h['batches']} pairs)")
    return h, recs


class Generators:
    """``workers`` generator processes from stream index ``first_pair``; ``next()`` gives the
    training batches (structured record arrays, or ``convert`` of them) in order. Each process
    gets a reader thread and a bounded queue (``prefetch`` batches), so generation, and the
    conversion, overlap training."""

    def __init__(self, binary, config, first_pair, workers, prefetch=8, bank=None, convert=None):
        self.convert = convert
        self.procs = [subprocess.Popen(stream_command(binary, config, first_pair, k, workers, bank=bank),
                                       stdout=subprocess.PIPE) for k in range(workers)]
        self.headers = [read_header(p.stdout) for p in self.procs]
        self.header = self.headers[0]
        self.queues = [queue.Queue(maxsize=prefetch) for _ in self.procs]
        self.stop = threading.Event()
        self.threads = [threading.Thread(target=self._pump, args=(k,), daemon=True) for k in range(workers)]
        for t in self.threads:
            t.start()
        self.next_worker = 0
        self.batches = 0

    def _pump(self, k):
        f, h, q = self.procs[k].stdout, self.headers[k], self.queues[k]
        try:
            while not self.stop.is_set():
                recs = read_records(f, h, h["batch"])
                if len(recs) < h["batch"]:
                    q.put(RuntimeError(f"generator {k} ended (exit {self.procs[k].poll()})"))
                    return
                q.put(self.convert(recs) if self.convert else recs)
        except Exception as e:  # surfaced to the training loop
            q.put(e)

    def next(self):
        item = self.queues[self.next_worker].get()
        if isinstance(item, Exception):
            raise item
        self.next_worker = (self.next_worker + 1) % len(self.procs)
        self.batches += 1
        return item

    def close(self):
        self.stop.set()
        for p in self.procs:
            p.kill()
        for p in self.procs:
            p.wait()
