#!/usr/bin/env python
"""Pre-registered fusion experiment on the peer's three members (LDA-shrink / XdawnCov+TS+LR / XdawnCov+MDM).
Designs: singles, z2 (LDA+TSLR), D1 z3, D2 stack3, D3 cvw3, D4 z2rm. Deterministic, 1 thread."""
import os, sys, json, warnings
for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[v] = "1"
# ../shared beside the checkout, as the tests find it (override with P300_DATA / PEER_DIR)
_SHARED = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "..", "shared")
os.environ.setdefault("P300_DATA", os.path.join(_SHARED, "data"))
sys.path.insert(0, os.environ.get("PEER_DIR", os.path.join(_SHARED, "peer")))
import numpy as np
import peer_eval as pe
from sklearn.linear_model import LogisticRegression
from sklearn.model_selection import StratifiedKFold, LeaveOneGroupOut
from sklearn.preprocessing import StandardScaler
warnings.filterwarnings("ignore")
np.random.seed(0)

PIPES = pe.make_pipelines()
MEMBERS = ["LDA-shrink", "XdawnCov+TS+LR", "XdawnCov+MDM"]
DESIGNS = ["LDA", "TSLR", "MDM", "z2", "z3", "stack3", "cvw3", "z2rm"]


def folds(y, groups):
    """5-fold stratified shuffled CV (seed 0); if groups given, leave-one-group(character)-out."""
    if groups is None:
        return list(StratifiedKFold(5, shuffle=True, random_state=0).split(np.zeros(len(y)), y))
    return list(LeaveOneGroupOut().split(np.zeros(len(y)), y, groups))


def member_scores(F, y, tr, te):
    """Fit the 3 members on rows tr (labels y[tr]); return (train-score sd per member, scores on rows te (n_te,3))."""
    sd, S = [], []
    for m in MEMBERS:
        kind, make = PIPES[m]
        mod = make().fit(F[kind][tr], y[tr])
        sd.append(np.std(mod.score(F[kind][tr])))
        S.append(mod.score(F[kind][te]))
    return np.array(sd), np.column_stack(S)


def dprime(s, y):
    a, b = s[y == 1], s[y == 0]
    return (a.mean() - b.mean()) / np.sqrt(0.5 * (a.var(ddof=1) + b.var(ddof=1)))


def fit_designs(F, y, tr, te, groups):
    """Train every design on rows tr, return {design: test scores on rows te} plus learned weights."""
    ytr = y[tr]
    sd, S = member_scores(F, y, tr, te)
    Z = S / sd
    out = {"LDA": S[:, 0], "TSLR": S[:, 1], "MDM": S[:, 2],
           "z2": Z[:, 0] + Z[:, 1], "z3": Z.sum(1), "z2rm": Z[:, 1] + Z[:, 2]}
    # inner CV on the training rows -> out-of-fold member scores
    g = None if groups is None else groups[tr]
    oof = np.zeros((len(tr), 3))
    for itr, ite in folds(ytr, g):
        _, oof[ite] = member_scores(F, y, tr[itr], tr[ite])
    sc = StandardScaler().fit(oof)
    lr = LogisticRegression().fit(sc.transform(oof), ytr)
    out["stack3"] = lr.decision_function(sc.transform(S))
    w = np.clip([dprime(oof[:, k], ytr) for k in range(3)], 0, None)
    out["cvw3"] = Z @ w
    return out, {"stack_coef": lr.coef_[0].tolist(), "stack_intercept": float(lr.intercept_[0]),
                 "cvw_dprime": w.tolist(), "train_sd": sd.tolist()}


def feats(fe, X):
    return {"vec": fe.vec(X), "riem": fe.riem(X)}


def concat(Fa, Fb):
    return {k: np.concatenate([Fa[k], Fb[k]]) for k in Fa}


def split_eval(Ftr, ytr, Fte, yte, gtr=None):
    """Train on whole training set, score test set; also the training-only CV AUC of each design."""
    F = concat(Ftr, Fte)
    y = np.concatenate([ytr, yte])
    ntr = len(ytr)
    tr, te = np.arange(ntr), np.arange(ntr, len(y))
    test_scores, weights = fit_designs(F, y, tr, te, gtr)
    # training-only outer CV (design incl. its own inner CV nested)
    fold_auc = {d: [] for d in DESIGNS}
    for otr, ote in folds(ytr, gtr):
        sc, _ = fit_designs(F, y, tr[otr], tr[ote], gtr)
        for d in DESIGNS:
            fold_auc[d].append(pe.auc(ytr[ote], sc[d]))
    cv = {d: float(np.mean(v)) for d, v in fold_auc.items()}
    return test_scores, weights, cv


def main():
    res = {}
    # eeg2
    e1, e2 = pe.load_oddball("eeg2_1.dat"), pe.load_oddball("eeg2_2.dat")
    fe = pe.Features(e1["fs"])
    f1, f2 = feats(fe, e1["X"]), feats(fe, e2["X"])
    for nm, (a, fa, b, fb, trn) in {"eeg2 1->2": (e1, f1, e2, f2, "eeg2_1"),
                                    "eeg2 2->1": (e2, f2, e1, f1, "eeg2_2")}.items():
        s, w, cv = split_eval(fa, a["y"], fb, b["y"])
        res[nm] = {"train_set": trn, "test_auc": {d: pe.auc(b["y"], s[d]) for d in DESIGNS}, "weights": w, "train_cv_auc": cv}
        print(nm, json.dumps(res[nm]), flush=True)
    # Muse
    mtr, mte = pe.load_muse([1, 2]), pe.load_muse([3])
    fe = pe.Features(mtr["fs"])
    s, w, cv = split_eval(feats(fe, mtr["X"]), mtr["y"], feats(fe, mte["X"]), mte["y"])
    res["Muse s1+2->s3"] = {"train_set": "Muse s1+2", "test_auc": {d: pe.auc(mte["y"], s[d]) for d in DESIGNS},
                            "weights": w, "train_cv_auc": cv}
    print("Muse", json.dumps(res["Muse s1+2->s3"]), flush=True)
    # speller (inner/outer CV: leave-one-character-out, since 4 chars < 5 folds)
    d1, d2 = pe.load_speller("eeg3_1.dat"), pe.load_speller("eeg3_2.dat")
    fe = pe.Features(d1["fs"])
    g1, g2 = feats(fe, d1["X"]), feats(fe, d2["X"])
    for nm, (a, fa, b, fb, trn) in {"eeg3 fwd": (d1, g1, d2, g2, "eeg3_1"), "eeg3 rev": (d2, g2, d1, g1, "eeg3_2")}.items():
        s, w, cv = split_eval(fa, a["y"], fb, b["y"], gtr=a["char_idx"])
        acc = {d: pe.char_accuracy(s[d], b)[0] for d in DESIGNS}
        reps = {}
        for d in DESIGNS:
            ok = [x == 1.0 for x in acc[d]]
            reps[d] = next((r + 1 for r in range(len(ok)) if all(ok[r:])), None)
        res[nm] = {"train_set": trn, "test_auc": {d: pe.auc(b["y"], s[d]) for d in DESIGNS}, "weights": w,
                   "train_cv_auc": cv, "acc_by_reps": acc, "reps_to_4of4": reps}
        print(nm, json.dumps(res[nm]), flush=True)
    out = os.environ.get("FUSION_OUT", "fusion_results.json")
    with open(out, "w") as f:
        json.dump(res, f, indent=1)
    report(res)


def report(res):
    splits = list(res)
    print("\n## test AUC")
    print(f"{'design':8s} " + " ".join(f"{s:>14s}" for s in splits) + "  reps fwd/rev")
    for d in DESIGNS:
        print(f"{d:8s} " + " ".join(f"{res[s]['test_auc'][d]:14.5f}" for s in splits)
              + f"  {res['eeg3 fwd']['reps_to_4of4'][d]}/{res['eeg3 rev']['reps_to_4of4'][d]}")
    print("\n## training-only CV AUC (mean of outer-fold AUCs) per training set")
    print(f"{'design':8s} " + " ".join(f"{res[s]['train_set']:>10s}" for s in splits) + "      mean")
    for d in DESIGNS:
        v = [res[s]["train_cv_auc"][d] for s in splits]
        print(f"{d:8s} " + " ".join(f"{x:10.4f}" for x in v) + f"  {np.mean(v):8.4f}")
    print("\n## char accuracy by reps")
    for s in ("eeg3 fwd", "eeg3 rev"):
        for d in DESIGNS:
            print(f"{s:9s} {d:8s} " + " ".join(f"{100*a:4.0f}" for a in res[s]["acc_by_reps"][d]))
    print("\n## weights (stack coef on standardized OOF scores [LDA,TSLR,MDM]; cvw d')")
    for s in splits:
        w = res[s]["weights"]
        print(f"{s:14s} stack {np.round(w['stack_coef'], 3).tolist()}  cvw {np.round(w['cvw_dprime'], 3).tolist()}")


if __name__ == "__main__":
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1):
        main()
