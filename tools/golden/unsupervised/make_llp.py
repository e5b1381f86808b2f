"""Reference values for oddball-decode's learning from label proportions (LLP, Hubner et al. 2017) and
its mixture with the EM (MIX, Hubner et al. 2018): oddball_decode::unsupervised::{LlpParams, Llp, Mix}.

Run from the repository root in a throwaway venv:
    python3 -m venv /tmp/golden && /tmp/golden/bin/pip install -r tools/golden/unsupervised/requirements.txt
    /tmp/golden/bin/python tools/golden/unsupervised/make_llp.py
Writes crates/oddball-decode/tests/fixtures/llp_golden.json (read by crates/oddball-decode/tests/llp.rs).

The problem: 5 features, two groups (sequence types) with known target proportions pi_1 = 3/8
(64 epochs, 24 targets) and pi_2 = 2/18 (72 epochs, 8 targets); targets carry a mean shift.
Computed directly, without the Rust shortcuts:
  * LLP class means: np.linalg.lstsq of A [mu_t; mu_n] = M, A's rows [pi_g, 1 - pi_g], M's rows the
    group means; their variance traces sum_g C_kg^2 tr(S_g) / n_g, C = pinv(A), S_g group g's ML
    covariance (np.cov(bias=True));
  * the LDA: B = (1 - lam) S + lam D (S the ML total covariance, D its diagonal, lam scikit-learn's
    ledoit_wolf_shrinkage of the standardised rows, clamped to [1e-4, 0.99], c = lam N / (1 - lam)),
    Sigma = B - q dmu dmu' with q = pbar (1 - pbar) N / (N + c), pbar the epochs' target share,
    w = solve(Sigma, dmu) formed densely, LLR = (x - (mu_t + mu_n)/2) w;
  * EM-side means from fixed soft responsibilities r (a stand-in for an EM posterior) with k0 = 2
    pseudo-epochs at the grand mean: mu_t = (sum r x + k0 m0) / (sum r + k0), and 1 - r for mu_n;
    variance traces tr(S_w) sum r^2 / (sum r + k0)^2, S_w the r-weighted within-class covariance;
  * MIX: per class gamma = v_LLP / (v_EM + v_LLP), means gamma mu_EM + (1 - gamma) mu_LLP, the same LDA.
"""
import json
import pathlib

import numpy as np
import sklearn
from sklearn.covariance import ledoit_wolf_shrinkage

FIXTURES = pathlib.Path(__file__).resolve().parents[3] / "crates/oddball-decode/tests/fixtures"


def lda(X, mu_t, mu_n, pbar):
    n, p = X.shape
    xc = X - X.mean(axis=0)
    S = xc.T @ xc / n
    D = np.diag(np.diag(S))
    lam = ledoit_wolf_shrinkage(xc / np.sqrt(np.diag(S)), assume_centered=True)
    lam = min(max(lam, 1e-4), 0.99)
    c = lam * n / (1 - lam)
    B = (1 - lam) * S + lam * D
    dmu = mu_t - mu_n
    q = pbar * (1 - pbar) * n / (n + c)
    sigma = B - q * np.outer(dmu, dmu)
    w = np.linalg.solve(sigma, dmu)
    return w, float(-w @ (0.5 * (mu_t + mu_n))), float(lam)


def main():
    rng = np.random.default_rng(20261128)
    p = 5
    groups = [3 / 8, 2 / 18]
    sizes = [64, 72]
    group_of, attended = [], []
    for g, (pi, n_g) in enumerate(zip(groups, sizes)):
        k = round(pi * n_g)
        att = np.zeros(n_g, dtype=bool)
        att[:k] = True
        att = rng.permutation(att)
        group_of += [g] * n_g
        attended += att.tolist()
    order = rng.permutation(len(group_of))
    group_of = np.array(group_of)[order]
    attended = np.array(attended)[order]
    n = len(group_of)
    mu_t_true = np.array([1.2, 0.8, 0.0, -0.6, 0.3])
    mu_n_true = np.array([0.1, -0.2, 0.0, 0.1, 0.0])
    mix = np.eye(p) + 0.3 * rng.normal(size=(p, p))
    X = rng.normal(size=(n, p)) @ mix.T + np.where(attended[:, None], mu_t_true, mu_n_true)
    X = np.round(X, 4)

    # LLP.
    A = np.array([[pi, 1 - pi] for pi in groups])
    M = np.array([X[group_of == g].mean(axis=0) for g in range(len(groups))])
    sol, *_ = np.linalg.lstsq(A, M, rcond=None)
    C = np.linalg.pinv(A)
    tr_g = np.array([np.trace(np.cov(X[group_of == g].T, bias=True)) for g in range(len(groups))])
    n_g = np.array([(group_of == g).sum() for g in range(len(groups))])
    v_llp = (C**2 * (tr_g / n_g)[None, :]).sum(axis=1)
    pbar = float((n_g * np.array(groups)).sum() / n)
    w_llp, b_llp, lam = lda(X, sol[0], sol[1], pbar)

    # EM-side means from fixed soft responsibilities.
    k0 = 2.0
    r = np.clip(np.where(attended, 0.75, 0.12) + 0.1 * rng.normal(size=n), 0.0, 1.0)
    r = np.round(r, 4)
    m0 = X.mean(axis=0)
    zt, zn = r.sum() + k0, (1 - r).sum() + k0
    em_t = ((r[:, None] * X).sum(0) + k0 * m0) / zt
    em_n = (((1 - r)[:, None] * X).sum(0) + k0 * m0) / zn
    tr_w = ((r[:, None] * (X - em_t) ** 2).sum() + ((1 - r)[:, None] * (X - em_n) ** 2).sum()) / n
    v_em = np.array([tr_w * (r**2).sum() / zt**2, tr_w * ((1 - r) ** 2).sum() / zn**2])

    gamma = v_llp / (v_em + v_llp)
    mix_t = gamma[0] * em_t + (1 - gamma[0]) * sol[0]
    mix_n = gamma[1] * em_n + (1 - gamma[1]) * sol[1]
    w_mix, b_mix, _ = lda(X, mix_t, mix_n, pbar)

    fixture = {
        "versions": {"numpy": np.__version__, "scikit-learn": sklearn.__version__},
        "groups": groups,
        "x": X.tolist(),
        "group_of_epoch": group_of.tolist(),
        "shrinkage": lam,
        "llp": {
            "target": sol[0].tolist(),
            "non_target": sol[1].tolist(),
            "variance": v_llp.tolist(),
            "coef": w_llp.tolist(),
            "intercept": b_llp,
            "llr": (X @ w_llp + b_llp).tolist(),
        },
        "responsibilities": r.tolist(),
        "mean_prior": k0,
        "em": {"target": em_t.tolist(), "non_target": em_n.tolist(), "variance": v_em.tolist()},
        "mix": {
            "gamma": gamma.tolist(),
            "variance": (gamma**2 * v_em + (1 - gamma) ** 2 * v_llp).tolist(),
            "target": mix_t.tolist(),
            "non_target": mix_n.tolist(),
            "coef": w_mix.tolist(),
            "intercept": b_mix,
            "llr": (X @ w_mix + b_mix).tolist(),
        },
        "truth": {"target": mu_t_true.tolist(), "non_target": mu_n_true.tolist()},
    }
    out = FIXTURES / "llp_golden.json"
    out.write_text(json.dumps(fixture, indent=1) + "\n")
    print(f"wrote {out} ({out.stat().st_size} B): shrinkage {lam:.6f}, gamma {gamma}")
    print("LLP target", sol[0], "\nLLP non-target", sol[1])


main()
