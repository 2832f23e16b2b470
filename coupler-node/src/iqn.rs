//! Interface quasi-Newton with an inverse Jacobian from a least-squares model (IQN-ILS, Degroote,
//! Bathe & Vierendeels 2009, as in preCICE), on flat vectors.
//!
//! The fixed point is `x = H(x)` with `H` one pass of loads then solid. Each trial gives the
//! residual `r_k = H(x_k) − x_k` (in the *unknowns*: scaled positions and orientations) and the
//! full trial `x̃_k = H(x_k)` (every array the fluid reads). Successive trials give the columns
//! `ΔR = r_k − r_{k−1}`, `ΔX̃ = x̃_k − x̃_{k−1}`; the next input is
//!
//! ```text
//! x_{k+1} = x̃_k + ΔX̃ α,   α = argmin ‖ΔR α + r_k‖,
//! ```
//!
//! an affine combination of trials, so the surface vertices and velocities that travel with the
//! positions stay those of a combination of real solid states. Without columns (the first
//! iteration of the run) the input is `x_k + ω₀ r_k` with the constant `run.relaxation_initial`.
//!
//! Columns of the last `reuse` steps are kept besides the current step's (newest first). Nearly
//! dependent columns are removed by preCICE's **QR2** filter: modified Gram–Schmidt over the
//! columns newest first, and a column whose part orthogonal to the newer ones is shorter than
//! `filter` times its own length is dropped for good. Pure arithmetic in a fixed order: the
//! same trials give the same bits.

use std::collections::VecDeque;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// One secant pair.
#[derive(Clone, Debug)]
struct Column {
    dr: DVector<f64>,
    dxt: DVector<f64>,
}

/// The columns IQN-ILS keeps across steps: `(ΔR, ΔX̃)` pairs of the earlier steps (newest step
/// first) and of the step just finished.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IqnColumns {
    /// Earlier steps' columns, newest step first, each step's oldest first.
    pub old: Vec<Vec<(Vec<f64>, Vec<f64>)>>,
    /// The last step's columns, oldest first (they join `old` when the next step starts).
    pub now: Vec<(Vec<f64>, Vec<f64>)>,
}

/// The IQN-ILS state kept across iterations and steps.
#[derive(Clone, Debug)]
pub struct IqnIls {
    reuse: usize,
    filter: f64,
    omega0: f64,
    /// Columns of earlier steps, newest step first, each step's columns oldest first.
    old: VecDeque<Vec<Column>>,
    /// This step's columns, oldest first.
    now: Vec<Column>,
    /// Residual and full trial of the previous iteration of this step.
    last: Option<(DVector<f64>, DVector<f64>)>,
    /// Columns dropped by the filter in this step.
    dropped: u32,
}

impl IqnIls {
    /// An empty model: columns of `reuse` earlier steps, QR2 limit `filter`, first factor
    /// `omega0`.
    pub fn new(reuse: u32, filter: f64, omega0: f64) -> IqnIls {
        IqnIls {
            reuse: reuse as usize,
            filter,
            omega0,
            old: VecDeque::new(),
            now: Vec::new(),
            last: None,
            dropped: 0,
        }
    }

    /// A new step begins: this step's columns join the reused ones (the oldest step leaves).
    pub fn start_step(&mut self) {
        let now = std::mem::take(&mut self.now);
        self.old.push_front(now);
        self.old.truncate(self.reuse);
        self.last = None;
        self.dropped = 0;
    }

    /// Columns dropped by the filter since the step began.
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// The secant columns kept across steps, as plain vectors (the coupler's checkpoint; taken
    /// between steps, when nothing else is pending).
    pub fn columns(&self) -> IqnColumns {
        let plain = |cols: &[Column]| -> Vec<(Vec<f64>, Vec<f64>)> {
            cols.iter()
                .map(|c| (c.dr.as_slice().to_vec(), c.dxt.as_slice().to_vec()))
                .collect()
        };
        IqnColumns {
            old: self.old.iter().map(|cols| plain(cols)).collect(),
            now: plain(&self.now),
        }
    }

    /// Puts back the columns of [`IqnIls::columns`]; the next step iterates as the original
    /// run's did.
    pub fn restore(&mut self, columns: &IqnColumns) {
        let model = |cols: &[(Vec<f64>, Vec<f64>)]| -> Vec<Column> {
            cols.iter()
                .map(|(dr, dxt)| Column {
                    dr: DVector::from_column_slice(dr),
                    dxt: DVector::from_column_slice(dxt),
                })
                .collect()
        };
        self.old = columns.old.iter().map(|cols| model(cols)).collect();
        self.now = model(&columns.now);
        self.last = None;
        self.dropped = 0;
    }

    /// Takes trial `k` without computing an input (its input came from elsewhere, e.g. a
    /// predictor): only adds the column to the previous trial.
    pub fn observe(&mut self, r: &[f64], xt: &[f64]) {
        let r = DVector::from_column_slice(r);
        let xt = DVector::from_column_slice(xt);
        if let Some((r_prev, xt_prev)) = &self.last
            && r_prev.len() == r.len()
            && xt_prev.len() == xt.len()
        {
            self.now.push(Column {
                dr: &r - r_prev,
                dxt: &xt - xt_prev,
            });
        }
        self.last = Some((r, xt));
    }

    /// The next input after trial `k`: `r` its residual in the unknowns, `x` its full input, `xt`
    /// the full trial. Returns the input and the number of columns it used.
    pub fn next(&mut self, r: &[f64], x: &[f64], xt: &[f64]) -> (Vec<f64>, u32) {
        self.observe(r, xt);
        let r = DVector::from_column_slice(r);
        // Newest first: this step's columns (newest last in storage), then earlier steps'.
        let mut order: Vec<(usize, usize)> = (0..self.now.len()).rev().map(|i| (0, i)).collect();
        for (s, cols) in self.old.iter().enumerate() {
            order.extend((0..cols.len()).rev().map(|i| (s + 1, i)));
        }
        fn column(this: &IqnIls, (s, i): (usize, usize)) -> &Column {
            if s == 0 {
                &this.now[i]
            } else {
                &this.old[s - 1][i]
            }
        }
        // Modified Gram–Schmidt with the QR2 filter.
        let mut q: Vec<DVector<f64>> = Vec::new();
        let mut r_cols: Vec<Vec<f64>> = Vec::new();
        let mut kept: Vec<(usize, usize)> = Vec::new();
        let mut drop: Vec<(usize, usize)> = Vec::new();
        for &at in &order {
            let c = column(self, at);
            if c.dr.len() != r.len() || c.dxt.len() != xt.len() {
                drop.push(at);
                continue;
            }
            let mut v = c.dr.clone();
            let norm0 = v.norm();
            let mut coeffs = Vec::with_capacity(q.len() + 1);
            for qj in &q {
                let rij = qj.dot(&v);
                v.axpy(-rij, qj, 1.0);
                coeffs.push(rij);
            }
            let norm = v.norm();
            if !(norm0 > 0.0 && norm.is_finite() && norm >= self.filter * norm0) {
                drop.push(at);
                continue;
            }
            coeffs.push(norm);
            q.push(v / norm);
            r_cols.push(coeffs);
            kept.push(at);
        }
        self.dropped += drop.len() as u32;
        let out = if kept.is_empty() {
            x.iter()
                .zip(xt)
                .map(|(x, xt)| x + self.omega0 * (xt - x))
                .collect()
        } else {
            let m = kept.len();
            let mut rr = DMatrix::<f64>::zeros(m, m);
            for (j, coeffs) in r_cols.iter().enumerate() {
                for (i, c) in coeffs.iter().enumerate() {
                    rr[(i, j)] = *c;
                }
            }
            let rhs = DVector::from_iterator(m, q.iter().map(|qi| -qi.dot(&r)));
            let alpha = rr
                .solve_upper_triangular(&rhs)
                .expect("the filter keeps only nonzero diagonals");
            let mut next = DVector::from_column_slice(xt);
            for (a, &at) in alpha.iter().zip(&kept) {
                next.axpy(*a, &column(self, at).dxt, 1.0);
            }
            next.as_slice().to_vec()
        };
        // Remove the dropped columns for good, highest index first within each step.
        drop.sort_unstable();
        for &(s, i) in drop.iter().rev() {
            if s == 0 {
                self.now.remove(i);
            } else {
                self.old[s - 1].remove(i);
            }
        }
        (out, kept.len() as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Iterates `x ← H(x)` with the model until `max |H(x) − x| ≤ tol`; returns the trials
    /// needed and the last trial.
    fn solve(
        model: Option<&mut IqnIls>,
        h: &dyn Fn(&[f64]) -> Vec<f64>,
        x0: &[f64],
        tol: f64,
        max: usize,
    ) -> (usize, Vec<f64>) {
        let mut model = model;
        let mut x = x0.to_vec();
        for k in 0..max {
            let xt = h(&x);
            let r: Vec<f64> = xt.iter().zip(&x).map(|(a, b)| a - b).collect();
            if r.iter().fold(0.0f64, |m, v| m.max(v.abs())) <= tol {
                return (k + 1, xt);
            }
            x = match model.as_deref_mut() {
                Some(m) => m.next(&r, &x, &xt).0,
                None => xt,
            };
        }
        panic!("no convergence in {max} trials");
    }

    /// `H(x) = x* + M (x − x*)` in `n` dimensions with `M = U T Uᵀ`, `U` orthonormal `n × rank`,
    /// `T` upper triangular with the eigenvalues 0.8, −0.6, 0.5, … on its diagonal: rank
    /// `rank`, not symmetric, contracting.
    fn affine(n: usize, rank: usize) -> (impl Fn(&[f64]) -> Vec<f64>, Vec<f64>) {
        let x_star: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
        let mut seed: u64 = 12345;
        let mut rand = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut u: Vec<Vec<f64>> = Vec::new();
        for _ in 0..rank {
            let mut v: Vec<f64> = (0..n).map(|_| rand()).collect();
            for q in &u {
                let d: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(q).for_each(|(x, q)| *x -= d * q);
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            u.push(v.iter().map(|x| x / norm).collect());
        }
        let eig = [0.8, -0.6, 0.5, 0.7, -0.4, 0.3, 0.6, -0.5];
        let mut m = vec![vec![0.0; n]; n];
        for j in 0..rank {
            for l in j..rank {
                let t = if l == j { eig[j] } else { 0.3 };
                for a in 0..n {
                    for b in 0..n {
                        m[a][b] += u[j][a] * t * u[l][b];
                    }
                }
            }
        }
        let xs = x_star.clone();
        let h = move |x: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|a| xs[a] + (0..n).map(|b| m[a][b] * (x[b] - xs[b])).sum::<f64>())
                .collect()
        };
        (h, x_star)
    }

    /// The accelerated answer is `x*` and the plain iteration's answer, to 1e-12.
    fn check_answer(x: &[f64], h: &dyn Fn(&[f64]) -> Vec<f64>, x_star: &[f64], what: &str) {
        let (_, plain) = solve(None, h, &vec![0.0; x.len()], 1e-14, 5000);
        for i in 0..x.len() {
            assert!((x[i] - x_star[i]).abs() <= 1e-12, "{what}");
            assert!((x[i] - plain[i]).abs() <= 1e-12, "{what}");
        }
    }

    #[test]
    fn full_rank_affine_map_converges_in_rank_plus_two_trials() {
        // Krylov space of dimension n: GMRES is exact after n steps, and IQN-ILS's input after
        // step k is H of GMRES's k-th iterate (Walker & Ni 2011), so trial n + 1 has no residual.
        // (The default filter 1e-2 drops the eighth column of the 8-D case, one trial more.)
        for n in [1, 2, 3, 5, 8] {
            let (h, x_star) = affine(n, n);
            let mut model = IqnIls::new(0, 1e-4, 0.5);
            let (trials, x) = solve(Some(&mut model), &h, &vec![0.0; n], 1e-12, 50);
            assert!(trials <= n + 2, "rank {n}: {trials} trials");
            check_answer(&x, &h, &x_star, &format!("rank {n}"));
        }
    }

    #[test]
    fn low_rank_affine_map_converges_in_rank_plus_three_trials() {
        // In 12 dimensions a rank-m map has a Krylov space of dimension m + 1 (the first
        // residual is not in the range of M): one trial more than at full rank.
        for rank in [1, 2, 3, 5] {
            let (h, x_star) = affine(12, rank);
            let mut model = IqnIls::new(0, 1e-2, 0.5);
            let (trials, x) = solve(Some(&mut model), &h, &[0.0; 12], 1e-12, 50);
            assert!(trials <= rank + 3, "rank {rank}: {trials} trials");
            let (plain_trials, _) = solve(None, &h, &[0.0; 12], 1e-12, 5000);
            assert!(plain_trials > 2 * trials, "{plain_trials} vs {trials}");
            check_answer(&x, &h, &x_star, &format!("rank {rank}"));
        }
    }

    #[test]
    fn mildly_nonlinear_map_converges_to_the_plain_answer() {
        // A contracting map with a quadratic and a sine term: plain iteration converges slowly.
        let h = |x: &[f64]| -> Vec<f64> {
            vec![
                0.5 + 0.7 * x[1] - 0.1 * x[0] * x[0],
                0.2 + 0.6 * x[0] + 0.05 * x[2].sin(),
                -0.3 + 0.5 * x[0] - 0.3 * x[1] + 0.2 * x[2],
            ]
        };
        let x0 = [0.0, 0.0, 0.0];
        let mut model = IqnIls::new(0, 1e-2, 0.5);
        let (trials, x) = solve(Some(&mut model), &h, &x0, 1e-12, 50);
        let (plain_trials, plain) = solve(None, &h, &x0, 1e-14, 5000);
        assert!(trials <= 12, "{trials} trials");
        assert!(plain_trials > 2 * trials, "{plain_trials} vs {trials}");
        for i in 0..3 {
            assert!((x[i] - plain[i]).abs() <= 1e-12, "{x:?} vs {plain:?}");
        }
    }

    #[test]
    fn reused_columns_solve_the_next_step_of_the_same_map_at_once() {
        let (h, x_star) = affine(6, 3);
        let mut model = IqnIls::new(2, 1e-2, 0.5);
        let (first, _) = solve(Some(&mut model), &h, &[0.0; 6], 1e-12, 50);
        model.start_step();
        // Same map, another start: the old columns span the Jacobian's range already.
        let (second, x) = solve(Some(&mut model), &h, &[0.1; 6], 1e-12, 50);
        assert!(second < first, "{second} vs {first}");
        assert!(second <= 3, "{second}");
        for i in 0..6 {
            assert!((x[i] - x_star[i]).abs() <= 1e-12);
        }
    }

    #[test]
    fn qr2_drops_a_repeated_column() {
        let mut model = IqnIls::new(1, 1e-2, 0.5);
        // Two trials along the same residual direction give parallel columns.
        model.observe(&[1.0, 0.0], &[1.0, 0.0]);
        model.observe(&[2.0, 0.0], &[2.0, 0.0]);
        model.start_step();
        model.observe(&[1.0, 1.0], &[1.0, 0.0]);
        let (_, used) = model.next(&[3.0, 1.0], &[0.0, 0.0], &[3.0, 0.0]);
        // Columns: now (2, 0), old (1, 0): parallel, the older one is dropped.
        assert_eq!(used, 1);
        assert_eq!(model.dropped(), 1);
        assert_eq!(model.old[0].len(), 0);
    }
}
