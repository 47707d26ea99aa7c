"""benches/device.sh, the GPU check, in its small mode on this machine's Vulkan driver (lavapipe
here): it installs the abi3 wheel from dist/ (``make wheel``) into a private folder and checks
every effect's GPU frame against the CPU's, so the script a GPU machine runs cannot rot."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_device_script_runs_every_effect_from_the_wheel(tmp_path):
    wheels = sorted((ROOT / "dist").glob("skyfall-*-abi3-*.whl"))
    assert wheels, "no abi3 wheel in dist/: make test builds it (make wheel)"
    env = {**os.environ, "OUT": str(tmp_path), "PYTHON": sys.executable}
    run = subprocess.run(["bash", str(ROOT / "benches" / "device.sh"), "--small"], env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    report = json.loads((tmp_path / "gpu.json").read_text())
    # the frames came from the wheel, not from this checkout's python/ folder
    assert not report["env"]["skyfall_from"].startswith(str(ROOT))
    effects = {r["effect"]: r for r in report["parity"]}
    assert len(effects) == 7
    for name, r in effects.items():
        if name.startswith("far rain"):
            # the GPU's lookups are exact where the CPU interpolates them: a few values 2-3 codes off
            assert r["status"] == "pass" and r["ssim"] >= 0.99, (name, r)
        else:
            assert r["status"] == "pass" and r["max_code_diff"] <= 1, (name, r)
    assert all(t["cpu_s"] > 0 for t in report["timing"])
    md = (tmp_path / "gpu.md").read_text()
    assert "## Parity" in md and "## Timing" in md and report["env"]["adapter"]["name"] in md
