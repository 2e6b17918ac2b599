"""Checkpoints of a run: the committed state, the step control and the writer in one file.

:meth:`dda.Simulation.run` writes one every ``checkpoint_every`` steps, on Ctrl-C or SIGTERM
and at the end; :meth:`dda.Simulation.resume` reads it back. The file is a pickle: only resume
checkpoints you wrote yourself.
"""

from __future__ import annotations

import os
import pickle
from pathlib import Path

__all__ = ["CHECKPOINT_VERSION", "checkpoint_payload", "write_checkpoint", "read_checkpoint"]

# layout of the checkpoint files (2: Simulation.damping; 3: the penetration guard;
# 4: Model, StepState and StepControl)
CHECKPOINT_VERSION = 4


def checkpoint_payload(simulation, writer, end: float, path, every: int) -> bytes:
    """The bytes of a checkpoint; a ``ValueError`` saying what to do when the simulation
    cannot be saved (a lambda or a local function in its scene)."""
    data = {"version": CHECKPOINT_VERSION, "simulation": simulation, "writer": writer,
            "end": end, "checkpoint": (str(path), every)}
    try:
        return pickle.dumps(data, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as exc:  # pickle raises several types for what it cannot save
        raise ValueError(
            f"Simulation.run: checkpoint cannot save this simulation ({exc}); give the "
            "scene module-level functions instead of lambdas or local functions (for "
            "shaking, loads and prescribed motions), or a recorded accelerogram"
        ) from None


def write_checkpoint(path, payload: bytes) -> None:
    """Write ``payload`` to a temporary name and rename it: an interruption never leaves a
    half-written checkpoint."""
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(payload)
    os.replace(tmp, path)


def read_checkpoint(path) -> dict:
    """The checkpoint's contents: ``simulation``, ``writer``, ``end`` and ``checkpoint``."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"Simulation.resume: no checkpoint file {path}")
    try:
        data = pickle.loads(path.read_bytes())
    except ModuleNotFoundError as exc:
        raise ValueError(
            f"Simulation.resume: {path} needs the module {exc.name!r} (a friction law or a "
            "function of its scene), which Python cannot find from here: run from the folder "
            "the run was started in (the scene file's, for a law named by import path), or "
            "put the module's folder on PYTHONPATH") from None
    except Exception as exc:
        raise ValueError(f"Simulation.resume: {path} is not a readable checkpoint "
                         f"({type(exc).__name__}: {exc})") from None
    if not isinstance(data, dict) or data.get("version") != CHECKPOINT_VERSION:
        raise ValueError(f"Simulation.resume: {path} is not a checkpoint of this version "
                         f"of dda (layout {CHECKPOINT_VERSION})")
    return data
