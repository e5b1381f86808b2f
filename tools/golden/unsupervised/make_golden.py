"""Reference values for oddball-decode's unsupervised decoder (EM over the paradigm's constraint,
Kindermans, Verstraeten & Schrauwen 2012) from a dense numpy implementation of the same model.

Run from the repository root in a throwaway venv:
    python3 -m venv /tmp/golden && /tmp/golden/bin/pip install -r tools/golden/unsupervised/requirements.txt
    /tmp/golden/bin/python tools/golden/unsupervised/make_golden.py
Writes crates/oddball-decode/tests/fixtures/unsupervised_golden.json (read by
crates/oddball-decode/tests/unsupervised.rs).

The model (module doc of oddball_decode::unsupervised): x_i ~ N(mu_t, Sigma) when epoch i is attended,
N(mu_n, Sigma) otherwise; in every trial exactly one code of each choice set is attended (uniform prior).
The penalised log-likelihood is
    J = sum_slots log sum_c (1/K) prod_i N(x_i; mu_{y_i(c)}, Sigma) - (c/2) log|Sigma| - (1/2) tr(c D Sigma^-1)
        - (k0/2) sum_{class} (mu_class - m0)' Sigma^-1 (mu_class - m0)
(m0 the grand mean, k0 = 3 pseudo-epochs of prior on each class mean) with D = diag of the total (ML) covariance S, c = lam N / (1 - lam), lam = scikit-learn's
ledoit_wolf_shrinkage of the standardised features. Nothing here uses the Rust shortcuts
(Sherman-Morrison, the label-free total scatter): the M-step forms the shrunk weighted means
(sum r_i x_i + k0 m0) / (N_t + k0) and the within-class scatter W (plus the prior's k0 (mu - m0)(mu - m0)')
directly, Sigma = (c D + W) / (N + c), and the likelihood uses dense inverses
and slogdet; the E-step enumerates each slot's codes.

The block-Toeplitz variant (oddball_decode::unsupervised::Covariance::BlockToeplitz) is the same objective
with the covariance restricted to Sigma = s2 B_T: B_T the tapered block-Toeplitz form of
B = (1 - lam) S + lam D (per channel pair and time lag the mean of B's entries, times (T - |lag|) / T),
formed here from B reshaped to (channel, time, channel, time) and its diagonals, fixed; the M-step's scale
s2 = tr(B_T^-1 (c D + W)) / ((N + c) p) with W formed directly, as above. Written to
unsupervised_toeplitz_golden.json, on a problem of 2 channels x 3 time points (6 features), 6 trials.

Decoys (oddball_decode::unsupervised::Constraint::with_decoys): codes flashed but never attended. Their
epochs are in no slot; the likelihood takes them as non-targets (N(x_i; mu_n, Sigma), enumerated with
the slots' epochs) and the M-step gives them r_i = 0. Written to unsupervised_decoy_golden.json: the 3 x 3
problem below with code 7 flashed as often as the others, never attended.

Group flashes (oddball_decode::unsupervised::Constraint::groups): one of six choices attended per trial,
each code's flash showing a group of them (target when the group holds the attended choice); the slot's
choices' evidence sums the LLRs of the flashes showing each, an epoch's responsibility is its group's
posterior. Written to unsupervised_groups_golden.json (with a decoy too).

The problem: 4 trials, two choice sets (a 3 x 3 "speller": codes 1-3 rows, 4-6 columns), every code
flashed twice per trial (48 epochs), 5 features; attended epochs carry a mean shift. The EM starts
from given initial scores (a fixed random vector), runs 6 M-steps, and the fixture holds the
objective after each and the final posteriors.
"""
import json
import pathlib

import numpy as np
import sklearn
from sklearn.covariance import ledoit_wolf_shrinkage

FIXTURES = pathlib.Path(__file__).resolve().parents[3] / "crates/oddball-decode/tests/fixtures"


def block_toeplitz(b, n_channels):
    """Per channel pair and time lag, the mean of b's entries times (T - |lag|) / T."""
    p = b.shape[0]
    t = p // n_channels
    b4 = b.reshape(n_channels, t, n_channels, t).copy()
    out = np.zeros_like(b4)
    for a in range(n_channels):
        for c in range(n_channels):
            blk = b4[a, :, c, :]
            for lag in range(-(t - 1), t):
                m = np.diagonal(blk, offset=lag).mean() * (t - abs(lag)) / t
                idx = np.arange(max(0, -lag), min(t, t - lag))
                out[a, idx, c, idx + lag] = m
    return out.reshape(p, p)


def golden(seed, n_trials_, shift_, n_channels, out_name, decoys=(), groups=None):
    rng = np.random.default_rng(seed)
    decoys = list(decoys)
    if groups is None:
        sets = [[1, 2, 3], [4, 5, 6]]
        n_codes = 6 + len(decoys)
    else:
        # Group flashes: one set of choices 0..K-1; code c shows the choices groups[c].
        n_choice = 1 + max(max(g) for g in groups.values())
        sets = [list(range(n_choice))]
        n_codes = len(groups) + len(decoys)
    n_sets, k_choices = len(sets), len(sets[0])
    n_trials, reps, p = n_trials_, 2, len(shift_)
    codes, trials, attended = [], [], []
    truth = []
    for t in range(n_trials):
        if groups is None:
            row, col = rng.integers(0, 3), rng.integers(0, 3)
            truth.append([sets[0][row], sets[1][col]])
        else:
            truth.append([int(rng.integers(0, n_choice))])
        for _ in range(reps):
            for c in rng.permutation(n_codes) + 1:
                codes.append(int(c))
                trials.append(t)
                if groups is None:
                    attended.append(int(c) in truth[-1])
                else:
                    attended.append(truth[-1][0] in groups.get(int(c), []))
    codes = np.array(codes)
    trials = np.array(trials)
    attended = np.array(attended)
    n = len(codes)
    mix = np.eye(p) + 0.3 * rng.normal(size=(p, p))
    shift = np.array(shift_)
    X = rng.normal(size=(n, p)) @ mix.T + np.outer(attended, shift)
    X = np.round(X, 4)
    init = np.round(rng.normal(size=n), 4)

    # Label-free statistics.
    xc = X - X.mean(axis=0)
    S = xc.T @ xc / n
    D = np.diag(np.diag(S))
    lam = ledoit_wolf_shrinkage(xc / np.sqrt(np.diag(S)), assume_centered=True)
    lam = min(max(lam, 1e-4), 0.99)
    cst = lam * n / (1 - lam)
    if n_channels is not None:
        BT = block_toeplitz((1 - lam) * S + lam * D, n_channels)
    k0 = 3.0
    m0 = X.mean(axis=0)

    # Slots: (trial, set); each epoch's member[i][c]: whether choice c of its slot makes it a target.
    def locate(code):
        if groups is not None:
            return 0, groups[code]
        for s, cs in enumerate(sets):
            if code in cs:
                return s, [cs.index(code)]
    # A decoy is in no slot (-1): a known non-target.
    slot = np.array([-1 if codes[i] in decoys else trials[i] * n_sets + locate(codes[i])[0] for i in range(n)])
    member = np.zeros((n, k_choices), dtype=bool)
    for i in range(n):
        if codes[i] not in decoys:
            member[i, locate(codes[i])[1]] = True
    n_slots = n_trials * n_sets


    def e_step(llr):
        post = np.zeros((n_slots, k_choices))
        lse = 0.0
        for s in range(n_slots):
            e = np.array([llr[(slot == s) & member[:, c]].sum() for c in range(k_choices)])
            m = e.max()
            z = np.exp(e - m).sum()
            lse += m + np.log(z) - np.log(k_choices)
            post[s] = np.exp(e - m) / z
        return post, lse


    def log_normal(x, mu, sigma):
        inv = np.linalg.inv(sigma)
        _, logdet = np.linalg.slogdet(sigma)
        d = x - mu
        return -0.5 * (p * np.log(2 * np.pi) + logdet + np.einsum("ij,jk,ik->i", d, inv, d))


    def objective(mu_t, mu_n, sigma):
        # Enumerate each slot's codes exactly: per slot, log sum_c (1/K) prod_i N(x_i; mu_{y_i(c)}, Sigma).
        lt = log_normal(X, mu_t, sigma)
        ln = log_normal(X, mu_n, sigma)
        total = 0.0
        for s in range(n_slots):
            idx = slot == s
            terms = [
                np.where(member[idx, c], lt[idx], ln[idx]).sum() - np.log(k_choices)
                for c in range(k_choices)
            ]
            m = max(terms)
            total += m + np.log(np.exp(np.array(terms) - m).sum())
        total += ln[slot == -1].sum()
        _, logdet = np.linalg.slogdet(sigma)
        inv = np.linalg.inv(sigma)
        pen = -0.5 * cst * logdet - 0.5 * np.trace(cst * D @ inv)
        pen -= 0.5 * k0 * ((mu_t - m0) @ inv @ (mu_t - m0) + (mu_n - m0) @ inv @ (mu_n - m0))
        return total + pen


    post, _ = e_step(init)
    objectives = []
    for it in range(6):
        r = np.where(slot >= 0, (post[slot] * member).sum(axis=1), 0.0)
        mu_t = ((r[:, None] * X).sum(0) + k0 * m0) / (r.sum() + k0)
        mu_n = (((1 - r)[:, None] * X).sum(0) + k0 * m0) / ((1 - r).sum() + k0)
        dt, dn = X - mu_t, X - mu_n
        W = (r[:, None] * dt).T @ dt + ((1 - r)[:, None] * dn).T @ dn
        W += k0 * (np.outer(mu_t - m0, mu_t - m0) + np.outer(mu_n - m0, mu_n - m0))
        if n_channels is None:
            sigma = (cst * D + W) / (n + cst)
        else:
            s2 = np.trace(np.linalg.solve(BT, cst * D + W)) / ((n + cst) * p)
            sigma = s2 * BT
        objectives.append(float(objective(mu_t, mu_n, sigma)))
        w = np.linalg.solve(sigma, mu_t - mu_n)
        llr = (X - 0.5 * (mu_t + mu_n)) @ w
        post, _ = e_step(llr)

    fixture = {
        "versions": {"numpy": np.__version__, "scikit-learn": sklearn.__version__},
        "sets": sets,
        "x": X.tolist(),
        "codes": codes.tolist(),
        "trials": trials.tolist(),
        "init": init.tolist(),
        "shrinkage": float(lam),
        "mean_prior": k0,
        "objective": objectives,
        "posterior": post.tolist(),
        "llr": llr.tolist(),
        "truth": truth,
    }
    if n_channels is not None:
        fixture["n_channels"] = n_channels
    decoded = [[sets[s][int(np.argmax(post[n_sets * t + s]))] for s in range(n_sets)]
               for t in range(n_trials)]
    if decoys:
        fixture["decoys"] = decoys
    if groups is not None:
        fixture["groups"] = {str(c): g for c, g in groups.items()}
    if decoys or groups is not None:
        # The numpy model's own choices (six M-steps from a random start need not find the truth).
        fixture["decoded"] = decoded
    OUT = FIXTURES / out_name
    OUT.write_text(json.dumps(fixture, indent=1) + "\n")
    print(f"wrote {OUT} ({OUT.stat().st_size} B): shrinkage {lam:.6f}, objective {objectives}")
    print("truth", truth, "decoded", decoded)


golden(20261125, 4, [1.5, 1.0, 0.5, 0.0, -0.5], None, "unsupervised_golden.json")
golden(20261128, 6, [0.0, 2.0, 1.0, 0.0, 1.6, 0.8], 2, "unsupervised_toeplitz_golden.json")
golden(20261129, 4, [2.0, 1.5, 1.0, 0.0, -1.0], None, "unsupervised_decoy_golden.json", decoys=[7])
# Group flashes of 1 to 3 of six choices (target shares 1/6 to 1/2) and a decoy (code 7).
golden(20261130, 6, [2.0, 1.5, 1.0, 0.0, -1.0], None, "unsupervised_groups_golden.json", decoys=[7],
       groups={1: [0, 1], 2: [2, 3, 4], 3: [5], 4: [0, 2, 5], 5: [1, 3], 6: [4]})
