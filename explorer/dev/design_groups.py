"""
The round trip's groups (docs/design.md): the median of the per-mirror median CIEDE2000 and the share
within 1, per kind of mirror, from the per-mirror list that ``python3 -m explorer bench --design 50``
prints (docs/design_round_trip.txt).

Usage: python3 -m explorer.dev.design_groups docs/design_round_trip.txt
"""

import re
import sys

import numpy as np

rows = []
for line in open(sys.argv[1]):
    m = re.match(r"\s*(\d+)\s+(.*?)\s+->\s+median ΔE2000 ([\d.]+)", line)
    if m:
        t = dict(kv.split("=") for kv in m.group(2).split()); t = {k: float(v) for k, v in t.items()}
        rows.append((t, float(m.group(3))))
def group(name, pred):
    sel = np.array([d for t, d in rows if pred(t)])
    print(f"| {name}: {len(sel)} | {np.median(sel):.2f} | {100*np.mean(sel<=1):.0f} % |")
dense = lambda t: t["nh"] >= 1 and t["nh"] > min(t["n1"], t["n2"])
group("all", lambda t: True)
group("host denser than a layer (nh ≥ 1, nh > min(n1, n2))", dense)
group("Λ > 600 nm, no such host", lambda t: t["Lambda"] > 600 and not dense(t))
group("Λ ≤ 600 nm, no such host", lambda t: t["Lambda"] <= 600 and not dense(t))
group("Λ ≤ 600 nm, host n1 (nh < 1)", lambda t: t["Lambda"] <= 600 and t["nh"] < 1)
group("N ≤ 10", lambda t: t["N"] <= 10)
group("N ≥ 100", lambda t: t["N"] >= 100)
