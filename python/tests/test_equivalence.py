"""Each estimator's outputs against its pyRiemann / scikit-learn twin on real EEG (eeg3_1.dat).

Tolerances are the Rust golden tests' (crates/oddball-decode/tests/linear_riemann_golden.rs):
relative to the reference's peak magnitude, 1e-12 for closed-form outputs (covariances, xDAWN,
LDA) — widened where the real data's conditioning shows (stated per test) — and 1e-10 for
outputs that go through the Riemannian mean (gradient descent stopped at ‖J‖ ≤ 1e-8 on both
sides). xDAWN filters have an arbitrary sign per filter in LAPACK (so in pyRiemann); oddball fixes
it (largest coefficient positive), and the comparisons align the signs first.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import need_module

EXACT = 1e-12
MEAN = 1e-10


def rel_err(ours, ref) -> float:
    ours, ref = np.asarray(ours), np.asarray(ref)
    assert ours.shape == ref.shape, (ours.shape, ref.shape)
    return float(np.max(np.abs(ours - ref)) / max(np.max(np.abs(ref)), 1e-300))


def check(what, ours, ref, tol):
    err = rel_err(ours, ref)
    print(f"{what:<52} max rel error {err:.2e} (tol {tol:.0e})")
    assert err <= tol, f"{what}: {err:e} > {tol:e}"


def filter_signs(ours, ref):
    """+1/-1 per filter (row) making ours match ref."""
    s = np.sign(np.sum(ours * ref, axis=1))
    assert np.all(s != 0)
    return s


@pytest.fixture(scope="module")
def pyr():
    return need_module("pyriemann")


def test_covariances(eeg3, pyr):
    from pyriemann.estimation import Covariances as Ref

    from oddball.estimation import Covariances

    X = eeg3["riem"]
    for est in ("scm", "lwf", "oas"):
        check(f"Covariances({est!r})", Covariances(est).fit_transform(X), Ref(est).fit_transform(X), EXACT)


def test_xdawn(eeg3, pyr):
    from pyriemann.spatialfilters import Xdawn as Ref

    from oddball.spatialfilters import Xdawn

    X, y = eeg3["riem"], eeg3["y"]
    ours, ref = Xdawn(nfilter=4).fit(X, y), Ref(nfilter=4).fit(X, y)
    s = filter_signs(ours.filters_, ref.filters_)
    tol = EXACT
    check("Xdawn filters_ (signs aligned)", ours.filters_ * s[:, None], ref.filters_, tol)
    check("Xdawn patterns_ (signs aligned)", ours.patterns_ * s[:, None], ref.patterns_, tol)
    check("Xdawn evokeds_ (signs aligned)", ours.evokeds_ * s[:, None], ref.evokeds_, tol)
    check("Xdawn transform (signs aligned)", ours.transform(X) * s[None, :, None], ref.transform(X), tol)


def test_xdawn_covariances(eeg3, pyr):
    from pyriemann.estimation import XdawnCovariances as Ref

    from oddball.estimation import XdawnCovariances

    X, y = eeg3["riem"], eeg3["y"]
    ours = XdawnCovariances(nfilter=4, estimator="oas").fit(X, y)
    ref = Ref(nfilter=4, estimator="oas").fit(X, y)
    s = filter_signs(ours.Xd_.filters_, ref.Xd_.filters_)
    d = np.concatenate([s, s])  # the super-trial: [evoked prototypes ; filtered epoch]
    C, R = ours.transform(X), ref.transform(X)
    check("XdawnCovariances(4, 'oas') (signs aligned)", C * d[None, :, None] * d[None, None, :], R, EXACT)


def test_tangent_space_and_mdm(eeg3, pyr):
    from pyriemann.classification import MDM as RefMDM
    from pyriemann.estimation import XdawnCovariances as RefXC
    from pyriemann.tangentspace import TangentSpace as RefTS

    from oddball.classification import MDM
    from oddball.tangentspace import TangentSpace

    X, y = eeg3["riem"], eeg3["y"]
    covs = RefXC(nfilter=4, estimator="oas").fit_transform(X, y)  # the same input for both
    ts, rts = TangentSpace(metric="riemann").fit(covs), RefTS(metric="riemann").fit(covs)
    check("TangentSpace reference_", ts.reference_, rts.reference_, MEAN)
    check("TangentSpace transform", ts.transform(covs), rts.transform(covs), MEAN)
    v = rts.transform(covs[:20])
    check("TangentSpace inverse_transform", ts.inverse_transform(v), rts.inverse_transform(v), MEAN)

    mdm, rmdm = MDM(metric="riemann").fit(covs, y), RefMDM(metric="riemann").fit(covs, y)
    check("MDM covmeans_", mdm.covmeans_, rmdm.covmeans_, MEAN)
    check("MDM transform (distances)", mdm.transform(covs), rmdm.transform(covs), MEAN)
    check("MDM predict_proba", mdm.predict_proba(covs), rmdm.predict_proba(covs), MEAN)
    assert np.array_equal(mdm.predict(covs), rmdm.predict(covs))


def test_lda(eeg3):
    from sklearn.discriminant_analysis import LinearDiscriminantAnalysis as Ref

    from oddball.lda import LinearDiscriminantAnalysis

    F, y = eeg3["vec"], eeg3["y"]
    for shrinkage in ("auto", 0.3):
        ours = LinearDiscriminantAnalysis(solver="lsqr", shrinkage=shrinkage).fit(F, y)
        ref = Ref(solver="lsqr", shrinkage=shrinkage).fit(F, y)
        tol = EXACT
        check(f"LDA({shrinkage!r}) coef_", ours.coef_, ref.coef_, tol)
        check(f"LDA({shrinkage!r}) decision_function", ours.decision_function(F), ref.decision_function(F), tol)
        check(f"LDA({shrinkage!r}) predict_proba", ours.predict_proba(F), ref.predict_proba(F), tol)
        check(f"LDA({shrinkage!r}) means_", ours.means_, ref.means_, EXACT)
        assert np.array_equal(ours.predict(F), ref.predict(F))


def test_toeplitz_lda_against_toeplitzlda_fixture():
    """toeplitzlda 0.4.0 cannot be pip-installed here (its metadata names a git URL), so the
    reference is its own output stored by tools/golden/decode_toeplitz/make_golden.py (the Rust
    golden test's fixture; tolerance 1e-9 as there)."""
    import json

    from conftest import REPO
    from oddball.lda import ToeplitzLDA

    path = REPO / "crates/oddball-decode/tests/fixtures/toeplitz_lda_golden.json"
    cases = json.loads(path.read_text())["cases"]
    assert cases
    for name, c in cases.items():
        nc, nt = c["n_channels"], c["n_times"]

        def time_major(rows):  # the fixture's rows are channel-major (epochs flattened)
            x = np.asarray(rows, dtype=float)
            return x.reshape(len(x), nc, nt).transpose(0, 2, 1).reshape(len(x), -1)

        x, x_test, y = time_major(c["x"]), time_major(c["x_test"]), np.asarray(c["y"])
        ours = ToeplitzLDA(n_channels=nc).fit(x, y)
        coef_cm = ours.coef_[0].reshape(nt, nc).T.reshape(-1)
        check(f"ToeplitzLDA[{name}] coef_", coef_cm, c["coef"], 1e-9)
        check(f"ToeplitzLDA[{name}] intercept_", ours.intercept_, [c["intercept"]], 1e-9)
        check(f"ToeplitzLDA[{name}] decision_function", ours.decision_function(x_test), c["decision_test"], 1e-9)
