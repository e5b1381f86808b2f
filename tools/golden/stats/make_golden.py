"""Golden values for oddball-decode's Wilcoxon signed-rank test (stats.rs) from scipy.stats.wilcoxon.

Run: python make_golden.py > ../../../crates/oddball-decode/tests/fixtures/wilcoxon_golden.json
(pinned in requirements.txt). Each case holds the paired samples x, y and scipy's statistic and
p-value for the three alternatives, with scipy's defaults (zero_method='wilcox', correction=False,
method='auto': exact for n <= 50 without ties or zeros, an exact sign-flip permutation test for
n <= 13 with them, the normal approximation otherwise).
"""
import json

import numpy as np
import scipy
from scipy import stats

rng = np.random.default_rng(20261125)
cases = []


def add(name, x, y):
    x = [float(v) for v in x]
    y = [float(v) for v in y]
    out = {"name": name, "x": x, "y": y}
    for alt in ("two-sided", "greater", "less"):
        r = stats.wilcoxon(x, y, alternative=alt)
        out[alt] = {"statistic": float(r.statistic), "pvalue": float(r.pvalue)}
    cases.append(out)


for n in (5, 9, 20, 50):  # exact, no ties
    x = rng.normal(0.85, 0.05, n)
    y = x - rng.normal(0.01, 0.03, n)
    add(f"exact n={n}", x, y)
for n in (51, 80):  # asymptotic
    x = rng.normal(0.8, 0.05, n)
    add(f"normal n={n}", x, x - rng.normal(0.005, 0.02, n))
# ties and zeros, small: exact permutation
add("ties n=8", [1, 2, 3, 4, 5, 6, 7, 8], [0, 1, 1, 2, 7, 4, 5, 6])
add("zeros n=10", [0.9, 0.8, 0.7, 0.95, 0.85, 0.75, 0.65, 0.9, 0.8, 0.7],
    [0.9, 0.7, 0.72, 0.9, 0.85, 0.7, 0.6, 0.91, 0.78, 0.66])
add("AUC-like ties n=13", np.round(rng.uniform(0.6, 1.0, 13), 2), np.round(rng.uniform(0.6, 1.0, 13), 2))
# ties, larger: normal approximation with the tie correction
add("ties n=30", np.round(rng.uniform(0, 1, 30), 1), np.round(rng.uniform(0, 1, 30), 1))
add("one pair", [0.9], [0.8])
print(json.dumps({"scipy": scipy.__version__, "cases": cases}, indent=1))
