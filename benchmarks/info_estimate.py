"""How close ``dda info``'s cost estimate comes to the run it describes (issue 22: within a
factor of 2 on the packaged scenes and the examples).

For each scene file: ``dda info``'s estimate, then ``dda run`` in a fresh process timed from
outside (the interpreter's start and imports excluded: the time from the first step to the
last file written, as the estimate counts it), and their ratio.

    python benchmarks/info_estimate.py [SCENE.toml ...]
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = [ROOT / "dda" / "scenes" / "demo.toml", ROOT / "examples" / "brittle_block.toml"]

RUN = """
import sys, time
import dda
loaded = dda.load_scene(sys.argv[1])
start = time.perf_counter()
loaded.run(out=sys.argv[2], progress=False)
print(time.perf_counter() - start)
"""


def estimate(scene: Path) -> float:
    out = subprocess.run([sys.executable, "-m", "dda", "info", str(scene)], check=True,
                         capture_output=True, text=True, cwd=scene.parent).stdout
    return float(re.search(r"about ([0-9.e+]+) s", out).group(1))


def actual(scene: Path) -> float:
    with tempfile.TemporaryDirectory() as folder:
        out = subprocess.run([sys.executable, "-c", RUN, str(scene), folder], check=True,
                             capture_output=True, text=True, cwd=scene.parent).stdout
    return float(out.split()[-1])


def main(paths) -> None:
    print(f"{'scene':<22} {'estimate s':>11} {'run s':>8} {'ratio':>6}")
    for scene in paths:
        start = time.perf_counter()
        e, a = estimate(scene), actual(scene)
        print(f"{scene.name:<22} {e:>11.3g} {a:>8.3g} {e / a:>6.2f}"
              f"   ({time.perf_counter() - start:.0f} s to measure)")


if __name__ == "__main__":
    main([Path(p).resolve() for p in sys.argv[1:]] or SCENES)
