"""arps_torch: a PyTorch trainer for the arps DGMR-ARPS network.

* ``config``: the engine's ``ModelConfig`` (JSON) and its tensor names and shapes.
* ``model``: ``ArpsNet``, the engine's forward pass op for op (batched), and ``gmr`` (f64).
* ``weights``: the engine's safetensors weights format and the CPU trainer's checkpoint format.
* ``losses``: the CPU trainer's losses (``LossConfig``).
* ``stream``: reads ``arps-train stream`` (the binary training-data layout) and runs generators.
* ``train``: the training loop (``python -m arps_torch.train``).
"""

__version__ = "0.1.0"
TRAINER = f"arps_torch {__version__}"
