//! Affine-invariant Riemannian geometry of symmetric positive-definite (SPD) matrices, and the two
//! classifiers built on it: minimum distance to mean ([`Mdm`]) and tangent-space projection
//! ([`TangentSpace`]), as pyRiemann 0.12 defines them.
//!
//! * Matrix functions of SPD matrices ([`sqrtm`], [`invsqrtm`], [`logm`]) and of symmetric matrices
//!   ([`expm`]) through the symmetric eigendecomposition `C = V Λ Vᵀ → V f(Λ) Vᵀ`.
//! * [`distance_riemann`]: `d(A, B) = ‖log(B^{-1/2} A B^{-1/2})‖_F = sqrt(Σ ln² λ_i)` with `λ_i` the
//!   generalized eigenvalues of `(A, B)`; dimensionless, symmetric, and invariant under
//!   `A ↦ M A Mᵀ, B ↦ M B Mᵀ` for any invertible `M`.
//! * [`mean_riemann`]: the Karcher mean by pyRiemann's `mean_riemann` gradient descent — start at the
//!   arithmetic mean, `J = Σ w_i log(M^{-1/2} C_i M^{-1/2})`, `M ← M^{1/2} exp(ν J) M^{1/2}`, step `ν`
//!   (start 1) times 0.95 while `ν‖J‖_F` decreases and halved otherwise, stop when `‖J‖_F ≤ tol` or
//!   `ν ≤ tol` (default `tol = 1e-8`, at most 50 iterations). Not converging is reported in
//!   [`RiemannMean::converged`], not as an error (pyRiemann warns and returns the iterate).
//! * Tangent space at a reference `C_ref`: `upper(log(C_ref^{-1/2} C C_ref^{-1/2}))`, where [`upper`]
//!   lists the upper triangle row by row (`(0,0), (0,1), …, (0,n−1), (1,1), …`) with off-diagonal
//!   entries × √2, so the Euclidean norm of the vector equals the Riemannian distance to `C_ref`.
//!   [`untangent_space`] inverts it: `C_ref^{1/2} exp(unupper(t)) C_ref^{1/2}`.
//! * [`MdmParams::fit`] → [`Mdm`]: one Riemannian mean per class; the score is
//!   `d²(C, M_non-target) − d²(C, M_target)` and P(target) its sigmoid (pyRiemann's softmax of `−d²`).
//! * [`TangentSpaceParams::fit`] → [`TangentSpace`]: reference = Riemannian mean of the training
//!   matrices; vectors of length `n(n+1)/2`.
//!
//! Covariances are in µV² (any unit works: distances, scores and tangent vectors are dimensionless).
//!
//! Written here: no well-kept Rust crate provides affine-invariant Riemannian means, tangent spaces
//! or MDM on SPD matrices; checked against pyRiemann 0.12 in `tests/linear_riemann_golden.rs`.

pub mod covariance;
mod features;
mod geometry;
mod mdm;
mod mean;
mod tangent_space;
pub mod xdawn;

pub use features::*;
pub use geometry::*;
pub use mdm::*;
pub use mean::*;
pub use tangent_space::*;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{sym_eigenvalues, to_array2};
    use crate::DecodeError;
    use nalgebra::DMatrix;
    use ndarray::{array, Array3};
    use ndarray::{Array1, Array2, ArrayView2, Axis};
    use proptest::prelude::*;

    fn dm(a: ArrayView2<f64>) -> DMatrix<f64> {
        crate::linalg::to_dmatrix(a)
    }

    /// SPD `B Bᵀ + 0.1 I` from `n²` entries of `B`.
    fn spd_from(n: usize, entries: &[f64]) -> Array2<f64> {
        let b = DMatrix::from_row_slice(n, n, &entries[..n * n]);
        let mut c = &b * b.transpose();
        for i in 0..n {
            c[(i, i)] += 0.1;
        }
        to_array2(&c)
    }

    fn rel_err(a: ArrayView2<f64>, b: ArrayView2<f64>) -> f64 {
        let peak = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter()
            .zip(b.iter())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / peak
    }

    fn is_spd(a: ArrayView2<f64>) -> bool {
        let m = dm(a);
        (&m - m.transpose()).amax() <= 1e-12 * m.amax()
            && crate::linalg::sym_eigenvalues("t", &m).unwrap().min() > 0.0
    }

    /// Strategy: a side n in 2..=5 and k SPD matrices of that side.
    fn spd_set(k: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Vec<Array2<f64>>> {
        (2usize..=5, k).prop_flat_map(|(n, k)| {
            prop::collection::vec(prop::collection::vec(-2.0f64..2.0, n * n), k)
                .prop_map(move |bs| bs.iter().map(|b| spd_from(n, b)).collect())
        })
    }

    fn stack(ms: &[Array2<f64>]) -> Array3<f64> {
        let n = ms[0].nrows();
        Array3::from_shape_fn((ms.len(), n, n), |(k, i, j)| ms[k][[i, j]])
    }

    proptest! {
        // No regression files: failures print the minimal input instead.
        #![proptest_config(ProptestConfig {
            cases: 64,
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn mean_is_spd_and_stationary(ms in spd_set(1..=6)) {
            let covs = stack(&ms);
            let r = mean_riemann(covs.view(), &MeanRiemannParams::default()).unwrap();
            prop_assert!(is_spd(r.mean.view()));
            if r.converged {
                // First-order condition: Σ log(M^{-1/2} C_i M^{-1/2}) ≈ 0 (to the stopping tolerance).
                let ts = TangentSpace::from_reference(r.mean.view()).unwrap();
                let v = ts.transform(covs.view()).unwrap();
                let g = v.sum_axis(Axis(0)) / ms.len() as f64;
                prop_assert!(g.iter().all(|x| x.abs() < 1e-7), "gradient {g}");
            }
        }

        #[test]
        fn expm_of_logm_round_trips(ms in spd_set(1..=1)) {
            let c = &ms[0];
            let l = logm(c.view()).unwrap();
            let back = expm(l.view()).unwrap();
            prop_assert!(is_spd(back.view()));
            let cond = {
                let e = sym_eigenvalues("t", &dm(c.view())).unwrap();
                e.max() / e.min()
            };
            prop_assert!(rel_err(back.view(), c.view()) < 1e-13 * cond.max(1.0) + 1e-12);
            let s = sqrtm(c.view()).unwrap();
            let is = invsqrtm(c.view()).unwrap();
            prop_assert!(rel_err(s.dot(&s).view(), c.view()) < 1e-12 * cond.max(1.0));
            let eye = Array2::eye(c.nrows());
            prop_assert!(rel_err(s.dot(&is).view(), eye.view()) < 1e-12 * cond.max(1.0));
        }

        #[test]
        fn distance_is_symmetric_and_affine_invariant(
            ms in spd_set(2..=2),
            m_entries in prop::collection::vec(-1.0f64..1.0, 25),
        ) {
            let (a, b) = (&ms[0], &ms[1]);
            let n = a.nrows();
            let dab = distance_riemann(a.view(), b.view()).unwrap();
            let dba = distance_riemann(b.view(), a.view()).unwrap();
            prop_assert!((dab - dba).abs() <= 1e-10 * (1.0 + dab));
            prop_assert!(distance_riemann(a.view(), a.view()).unwrap() < 1e-7);
            // M = R + 2.5 I is invertible and modestly conditioned for |R_ij| < 1, n ≤ 5.
            let mut m = DMatrix::from_row_slice(n, n, &m_entries[..n * n]);
            for i in 0..n {
                m[(i, i)] += 2.5;
            }
            prop_assume!(m.clone().svd(false, false).singular_values.min() > 0.2);
            let cong = |x: &Array2<f64>| to_array2(&(&m * dm(x.view()) * m.transpose()));
            let d2 = distance_riemann(cong(a).view(), cong(b).view()).unwrap();
            prop_assert!((d2 - dab).abs() <= 1e-8 * (1.0 + dab), "{d2} vs {dab}");
        }

        #[test]
        fn tangent_space_round_trips(ms in spd_set(3..=3)) {
            let reference = &ms[0];
            let covs = stack(&ms[1..]);
            let v = tangent_space(covs.view(), reference.view()).unwrap();
            let back = untangent_space(v.view(), reference.view()).unwrap();
            for k in 0..2 {
                prop_assert!(is_spd(back.index_axis(Axis(0), k)));
                prop_assert!(rel_err(back.index_axis(Axis(0), k), covs.index_axis(Axis(0), k)) < 1e-9);
                // The vector's norm is the Riemannian distance to the reference.
                let d = distance_riemann(covs.index_axis(Axis(0), k), reference.view()).unwrap();
                let norm = v.row(k).dot(&v.row(k)).sqrt();
                prop_assert!((norm - d).abs() <= 1e-9 * (1.0 + d));
            }
        }
    }

    #[test]
    fn upper_order_and_weights() {
        let s = array![[1.0, 2.0, 3.0], [2.0, 4.0, 5.0], [3.0, 5.0, 6.0]];
        let u = upper(s.view()).unwrap();
        let r2 = std::f64::consts::SQRT_2;
        assert_eq!(
            u.to_vec(),
            vec![1.0, 2.0 * r2, 3.0 * r2, 4.0, 5.0 * r2, 6.0]
        );
        let back = unupper(u.view()).unwrap();
        assert!(rel_err(back.view(), s.view()) < 1e-15);
        assert!(unupper(Array1::zeros(5).view()).is_err());
    }

    #[test]
    fn mean_of_identical_matrices_and_of_two_commuting() {
        let a = array![[2.0, 0.0], [0.0, 8.0]];
        let b = array![[8.0, 0.0], [0.0, 2.0]];
        let r = mean_riemann(stack(&[a.clone(), a.clone()]).view(), &Default::default()).unwrap();
        assert!(rel_err(r.mean.view(), a.view()) < 1e-14 && r.converged);
        // Commuting matrices: the mean is the elementwise geometric mean, here 4·I.
        let r = mean_riemann(stack(&[a, b]).view(), &Default::default()).unwrap();
        assert!(rel_err(r.mean.view(), (4.0 * Array2::<f64>::eye(2)).view()) < 1e-9);
    }

    #[test]
    fn mdm_classifies_by_nearest_mean_and_serializes() {
        let a = array![[2.0, 0.3], [0.3, 1.0]];
        let b = array![[1.0, -0.2], [-0.2, 3.0]];
        let covs = stack(&[a.clone(), a.clone() * 1.1, b.clone(), b.clone() * 0.9]);
        let mdm = MdmParams::default()
            .fit(covs.view(), &[false, false, true, true])
            .unwrap();
        let s = mdm.decision_function(covs.view()).unwrap();
        assert!(s[0] < 0.0 && s[1] < 0.0 && s[2] > 0.0 && s[3] > 0.0);
        let d = mdm.distances(covs.view()).unwrap();
        assert!((d[[2, 0]].powi(2) - d[[2, 1]].powi(2) - s[2]).abs() < 1e-12);
        let json = serde_json::to_string(&mdm).unwrap();
        let back: Mdm = serde_json::from_str(&json).unwrap();
        // serde_json's float parsing may be off by an ulp.
        let again = back.decision_function(covs.view()).unwrap();
        assert!(again
            .iter()
            .zip(s.iter())
            .all(|(a, b)| (a - b).abs() < 1e-12));
        let ts = TangentSpaceParams::default().fit(covs.view()).unwrap();
        let back: TangentSpace =
            serde_json::from_str(&serde_json::to_string(&ts).unwrap()).unwrap();
        let (a, b) = (
            back.transform(covs.view()).unwrap(),
            ts.transform(covs.view()).unwrap(),
        );
        assert!(a.iter().zip(b.iter()).all(|(a, b)| (a - b).abs() < 1e-12));
    }

    #[test]
    fn errors() {
        let not_spd = array![[1.0, 2.0], [2.0, 1.0]];
        assert!(matches!(
            logm(not_spd.view()),
            Err(DecodeError::NotPositiveDefinite { .. })
        ));
        assert!(matches!(
            distance_riemann(not_spd.view(), Array2::eye(2).view()),
            Err(DecodeError::NotPositiveDefinite { .. })
        ));
        let covs = stack(&[Array2::eye(2), Array2::eye(2)]);
        assert!(matches!(
            MdmParams::default().fit(covs.view(), &[true, true]),
            Err(DecodeError::NeedBothClasses { .. })
        ));
        let ts = TangentSpace::from_reference(Array2::eye(2).view()).unwrap();
        assert!(matches!(
            ts.transform(Array3::zeros((1, 3, 3)).view()),
            Err(DecodeError::ShapeMismatch { .. })
        ));
        let bad: std::result::Result<Mdm, _> = serde_json::from_str(
            r#"{"metric":"Riemann","mean_nontarget":{"v":1,"dim":[2,2],"data":[1,2,2,1]},"mean_target":{"v":1,"dim":[2,2],"data":[1,0,0,1]}}"#,
        );
        assert!(bad.is_err());
    }
}
