"""A/B of the windshield's step: ``python benches/windshield_step_ab.py BASE_PYTHON HEAD_PYTHON [ROUNDS]``.

Each round runs one fresh process of each version (order swapped every round) that times: a 1/30 s
step of ``benches/bench_windshield.py``'s glass (2 mm/h, stepped until 3000 drops lie on it; median
of 15), a 1/30 s step of a settled ``rain`` glass (a state saved by ``benches/windshield_steady.py
simulate`` at /tmp/ws/states/rain_s1_p056.npz; median of 9), and 4 wiper periods of the ``rain``
preset from dry glass. Prints a markdown table of the medians and the per-round ratios.
"""

import json, subprocess, sys, numpy as np
W = r'''
import time, json, sys
sys.path.insert(0, "benches")
from skyfall import windshield as ws
def med(f, n):
    ts = []
    for _ in range(n):
        t = time.perf_counter(); f(); ts.append(time.perf_counter() - t)
    ts.sort(); return ts[len(ts)//2]
w = ws.Windshield(2.0, wipers=2, wiper_period_s=1.5, seed=0)
while len(w.drops()[0]) < 3000:
    w.step(1.0 / 30.0)
a = med(lambda: w.step(1.0/30.0), 15)
s = ws.Windshield.load("/tmp/ws/states/rain_s1_p056.npz")
b = med(lambda: s.step(1.0/30.0), 9)
c = ws.Windshield(10.0, wipers=2, wiper_period_s=1.5, car_speed_m_s=14.0, seed=2)
t = time.perf_counter(); [c.step(1.5) for _ in range(4)]; d = time.perf_counter() - t
print(json.dumps({"bench glass (3000 drops), 1/30 s step": a, "settled rain glass, 1/30 s step": b, "rain preset, 4 periods from dry": d}))
'''
base = sys.argv[1]; head = sys.argv[2]
res = {"base": [], "head": []}
for r in range(int(sys.argv[3]) if len(sys.argv) > 3 else 4):
    for lab, py in (("base", base), ("head", head)) if r % 2 == 0 else (("head", head), ("base", base)):
        out = subprocess.run([py, "-c", W], capture_output=True, text=True, check=True, cwd=str(__import__("pathlib").Path(__file__).parent.parent)).stdout
        res[lab].append(json.loads(out.strip().splitlines()[-1]))
        print(lab, res[lab][-1], flush=True)
keys = list(res["base"][0])
print("| row | base | head | head/base per round (median, range) |")
print("|---|---|---|---|")
for k in keys:
    b = np.array([x[k] for x in res["base"]]); h = np.array([x[k] for x in res["head"]]); q = h / b
    unit = (1e3, "ms") if b.mean() < 1 else (1, "s")
    print(f"| {k} | {np.median(b)*unit[0]:.2f} {unit[1]} | {np.median(h)*unit[0]:.2f} {unit[1]} | {np.median(q):.2f} ({q.min():.2f}-{q.max():.2f}) |")
