"""Reference values for oddball-decode's block-Toeplitz shrinkage LDA (`toeplitz_lda`, Sosulski &
Tangermann 2022, J. Neural Eng. 19 066019) from its authors' package `toeplitzlda` 0.4.0 (with
`blockmatrix` 0.3.0): `ToeplitzLDA(n_channels)` with its defaults (pooled within-class Ledoit-Wolf
covariance on standardised features, averaged along each channel x channel block diagonal (time lag),
linear taper (nt - |lag|) / nt, sample priors).

Run from the repository root in a throwaway venv (toeplitzlda/blockmatrix pin numpy<2 and a git URL in
their metadata but run on numpy 2, so they are installed without their dependencies):
    python3 -m venv /tmp/golden-toep && /tmp/golden-toep/bin/pip install -r tools/golden/decode_toeplitz/requirements.txt
    /tmp/golden-toep/bin/pip install --no-deps -r tools/golden/decode_toeplitz/requirements-nodeps.txt
    /tmp/golden-toep/bin/python tools/golden/decode_toeplitz/make_golden.py
Writes crates/oddball-decode/tests/fixtures/toeplitz_lda_golden.json (read by
crates/oddball-decode/tests/toeplitz_lda_golden.rs).

Feature layout. oddball's features are CHANNEL-MAJOR (index ch * n_times + t, an epoch (n_channels,
n_times) flattened row-major); toeplitzlda's default `data_is_channel_prime=True` expects TIME-MAJOR
vectors (index t * n_channels + ch). Epochs are generated as (n, n_channels, n_times), fed to Python as
`X.transpose(0, 2, 1).reshape(n, -1)`, and every feature-indexed output (coef, covariance rows and
columns) is permuted back to channel-major before it is written. Intercept, shrinkage and decision
values need no permutation. Inputs are rounded (4 decimals before any scaling) so the fixture holds the
exact input.

scikit-learn 1.9 removed `BaseEstimator._validate_data`, which `ToeplitzLDA.decision_function` calls, so
decisions are computed from `coef_` / `intercept_` exactly as that method does
(`s = X @ coef_.T + intercept_; s[:, 1] - s[:, 0]`); coef = coef_[1] - coef_[0], intercept =
intercept_[1] - intercept_[0] (class 1 = target). `ToeplitzLDA.fit` returns None.

The class does not store the Ledoit-Wolf gamma: it is recomputed by calling the package's own
`shrinkage` on the same class-mean-subtracted (p, n) matrix `fit` uses (`subtract_classwise_means`),
and the covariance that gives, after the package's own Toeplitz + taper steps, is asserted to equal
`model.stored_stm.mat` bit for bit, so the recorded gamma is the one used. `shrinkage` prints
"logger.warning('forcing gamma to 1')" on stdout when gamma clips; stdout is captured and checked.

Cases:
* basic: 80 epochs (20 targets) x 3 channels x 6 times, AR(1) noise over time mixed over channels,
  a target mean offset in a few features; gamma strictly inside (0, 1); 10 held-out test rows;
* clipped: white iid noise, n = 150 >> p = 8 (2 x 4), so the Ledoit-Wolf estimate exceeds 1 and is
  clipped to 1;
* one_channel: 1 channel x 8 times (every block is 1 x 1: a plain Toeplitz covariance);
* scaled: 4 channels x 5 times, channels 1 and 3 multiplied by 1e3 (exercises the standardisation).
"""
import contextlib
import io
import json
import pathlib

import blockmatrix
import numpy as np
import scipy
import sklearn
import toeplitzlda
from blockmatrix import SpatioTemporalMatrix, linear_taper
from toeplitzlda.classification import ToeplitzLDA
from toeplitzlda.classification.covariance import shrinkage, subtract_classwise_means

OUT = (
    pathlib.Path(__file__).resolve().parents[3]
    / "crates/oddball-decode/tests/fixtures/toeplitz_lda_golden.json"
)
CLIP_MSG = "logger.warning('forcing gamma to 1')"

rng = np.random.default_rng(20261125)


def arr(a):
    return np.asarray(a, dtype=float).tolist()


def ar1_noise(n, n_channels, n_times, phi, mixing, scale=1.0):
    """(n, n_channels, n_times): stationary AR(1) over time per source, mixed over channels."""
    e = rng.normal(0.0, scale, size=(n, n_channels, n_times))
    z = np.empty_like(e)
    z[:, :, 0] = e[:, :, 0] / np.sqrt(1.0 - phi**2)  # stationary start
    for t in range(1, n_times):
        z[:, :, t] = phi * z[:, :, t - 1] + e[:, :, t]
    return np.einsum("ij,njt->nit", mixing, z)


def labels(n, n_targets, g=rng):
    y = np.zeros(n, dtype=int)
    y[g.choice(n, size=n_targets, replace=False)] = 1
    return y


def make_case(X, y, X_test, channel_scale=None):
    """X, X_test: (n, n_channels, n_times) epochs; y: 0/1 ints (1 = target)."""
    X, X_test = np.round(X, 4), np.round(X_test, 4)
    if channel_scale is not None:
        X = X * channel_scale[None, :, None]
        X_test = X_test * channel_scale[None, :, None]
    n, nc, nt = X.shape
    p = nc * nt
    # toeplitzlda input: time-major feature vectors
    Xtm = X.transpose(0, 2, 1).reshape(n, -1)
    Xtm_test = X_test.transpose(0, 2, 1).reshape(X_test.shape[0], -1)
    # channel-major index i = ch * nt + t  <-  time-major index t * nc + ch
    perm = np.array([t * nc + ch for ch in range(nc) for t in range(nt)])
    assert np.array_equal(Xtm[:, perm], X.reshape(n, -1))

    clf = ToeplitzLDA(n_channels=nc)
    out_fit = io.StringIO()
    with contextlib.redirect_stdout(out_fit):
        ret = clf.fit(Xtm, y)
    assert ret is None
    assert list(clf.classes_) == [0, 1]

    # The gamma fit used: the package's own shrinkage on the same class-mean-subtracted matrix.
    Xc, cl_mean = subtract_classwise_means(Xtm.T, y)
    assert Xc.shape == (p, n)
    assert np.array_equal(cl_mean, clf.stored_cl_mean)
    out_shr = io.StringIO()
    with contextlib.redirect_stdout(out_shr):
        C, gamma = shrinkage(Xc)
    stm = SpatioTemporalMatrix(C, n_chans=nc, n_times=nt, channel_prime=True)
    stm.force_toeplitz_offdiagonals()
    stm.taper_offdiagonals(taper_f=linear_taper)
    cov_tm = np.asarray(clf.stored_stm.mat)
    assert cov_tm.shape == (p, p)
    assert np.array_equal(stm.mat, cov_tm), "recomputed covariance differs from stored_stm.mat"
    clipped = CLIP_MSG in out_shr.getvalue()
    assert (CLIP_MSG in out_fit.getvalue()) == clipped
    assert clipped == (gamma == 1), (gamma, out_shr.getvalue())
    assert "forcing gamma to 0" not in out_shr.getvalue()
    gamma = float(gamma)

    # As ToeplitzLDA.decision_function: s = X @ coef_.T + intercept_; s[:, 1] - s[:, 0]
    s = Xtm_test @ clf.coef_.T + clf.intercept_
    decision = s[:, 1] - s[:, 0]
    coef_tm = clf.coef_[1] - clf.coef_[0]
    intercept = float(clf.intercept_[1] - clf.intercept_[0])
    assert np.allclose(Xtm_test @ coef_tm + intercept, decision, rtol=1e-12, atol=1e-12)

    # Sanity (not written): the weights solve the stored covariance against the class-mean difference,
    # and the prior term is log(n_t / n_nt).
    diff = cl_mean[:, 1] - cl_mean[:, 0]
    assert np.allclose(cov_tm @ coef_tm, diff, rtol=1e-9, atol=1e-9 * np.abs(diff).max())
    n_t = int(y.sum())
    b = -0.5 * (cl_mean[:, 1] + cl_mean[:, 0]) @ coef_tm + np.log(n_t / (n - n_t))
    assert np.isclose(b, intercept, rtol=1e-9, atol=1e-12)

    case = {
        "n_channels": nc,
        "n_times": nt,
        "x": arr(X.reshape(n, -1)),
        "y": [int(v) for v in y],
        "x_test": arr(X_test.reshape(X_test.shape[0], -1)),
        "coef": arr(coef_tm[perm]),
        "intercept": intercept,
        "shrinkage": gamma,
        "covariance": arr(cov_tm[np.ix_(perm, perm)]),
        "decision_test": arr(decision),
    }
    return case, clipped


cases = {}

# --- basic: 3 ch x 6 t, AR(1) over time mixed over channels, target offset in a few features ---------
nc, nt = 3, 6
mixing = np.array([[1.0, 0.0, 0.0], [0.6, 0.8, 0.0], [0.3, 0.5, 0.8]])
y = labels(80, 20)
y_test = np.array([1, 0, 0, 1, 0, 0, 0, 1, 0, 0])
offset = np.zeros((nc, nt))
offset[1, 2:4] = [1.2, 1.6]
offset[2, 3] = 1.0
X = ar1_noise(80, nc, nt, 0.7, mixing, scale=2.0) + y[:, None, None] * offset
X_test = ar1_noise(10, nc, nt, 0.7, mixing, scale=2.0) + y_test[:, None, None] * offset
cases["basic"] = make_case(X, y, X_test)

# --- clipped: white iid noise, n >> p --------------------------------------------------------------
# For iid standardised noise the Ledoit-Wolf estimate scatters around ~1.3 (n = 150, p = 8); this case
# has its own generator, seeded so that the unclipped estimate is ~2.0, well clear of 1.
rng_clip = np.random.default_rng(3)
nc, nt = 2, 4
y = labels(150, 30, rng_clip)
X = rng_clip.normal(0.0, 1.0, size=(150, nc, nt))
X[y == 1, 0, 1] += 0.5
X_test = rng_clip.normal(0.0, 1.0, size=(6, nc, nt))
cases["clipped"] = make_case(X, y, X_test)

# --- one_channel: 1 ch x 8 t ------------------------------------------------------------------------
nc, nt = 1, 8
y = labels(60, 15)
X = ar1_noise(60, nc, nt, 0.8, np.eye(1), scale=1.5)
X[y == 1, 0, 3:6] += [0.8, 1.5, 0.8]
X_test = ar1_noise(8, nc, nt, 0.8, np.eye(1), scale=1.5)
X_test[[1, 4], 0, 3:6] += [0.8, 1.5, 0.8]
cases["one_channel"] = make_case(X, y, X_test)

# --- scaled: 4 ch x 5 t, channels 1 and 3 x 1e3 -------------------------------------------------------
nc, nt = 4, 5
mixing = np.eye(nc) + 0.3 * rng.normal(size=(nc, nc))
y = labels(70, 14)
X = ar1_noise(70, nc, nt, 0.5, mixing)
X[y == 1, :, 2] += [0.5, 0.9, 0.7, 0.2]
X_test = ar1_noise(8, nc, nt, 0.5, mixing)
X_test[[0, 5], :, 2] += [0.5, 0.9, 0.7, 0.2]
cases["scaled"] = make_case(X, y, X_test, channel_scale=np.array([1.0, 1e3, 1.0, 1e3]))

assert 0.0 < cases["basic"][0]["shrinkage"] < 1.0 and not cases["basic"][1]
assert cases["clipped"][1] and cases["clipped"][0]["shrinkage"] == 1.0
assert not cases["scaled"][1] and not cases["one_channel"][1]

out = {
    "versions": {
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "scikit-learn": sklearn.__version__,
        "toeplitzlda": toeplitzlda.__version__,
        "blockmatrix": blockmatrix.__version__,
    },
    "cases": {name: c for name, (c, _) in cases.items()},
}
for name, (c, clipped) in cases.items():
    n = len(c["y"])
    print(
        f"{name}: {n} epochs ({sum(c['y'])} targets) x {c['n_channels']} ch x {c['n_times']} t, "
        f"shrinkage {c['shrinkage']:.6f}{' (clipped)' if clipped else ''}, "
        f"intercept {c['intercept']:.6f}, |coef|max {np.abs(c['coef']).max():.4g}, "
        f"{len(c['decision_test'])} test decisions [{min(c['decision_test']):.3f}, {max(c['decision_test']):.3f}]"
    )
OUT.parent.mkdir(parents=True, exist_ok=True)
OUT.write_text(json.dumps(out, separators=(",", ":")))
print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")
