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
//! dependent columns are removed by preCICE's **QR2** filter: Gram–Schmidt over the columns
//! newest first, and a column whose part orthogonal to the newer ones is shorter than `filter`
//! times its own length is dropped for good.
//!
//! The Gram–Schmidt runs on the Gram matrix `ΔRᵀΔR`, not on the columns: each column's dot
//! products with the older ones are taken once, when it is made, so an iteration costs
//! `O(m n)` (the new column's dots, `ΔRᵀ r`, one refinement) instead of the `O(m² n)` of a
//! modified Gram–Schmidt from scratch, which was nearly all of the coupler's time on a 2-D beam
//! of 728 particles (0.48 ms of its 0.5 ms per iteration). The factor `R` is the Cholesky
//! factor of the Gram matrix, column by column in the filter's order; the least-squares
//! coefficients solve the normal equations `RᵀR α = −ΔRᵀ r`, refined once against the true
//! residual `−r − ΔR α` (semi-normal equations, Björck 1987), which keeps them as accurate as
//! a QR of the columns while `cond(ΔR)² ε < 1`. The filter compares `R_jj² = G_jj − Σ R_ij²`
//! with `filter² G_jj`: at the smallest filter a scene accepts (1e-6) that difference is still
//! resolved to 1e-4 of itself.
//!
//! Pure arithmetic in a fixed order: the same trials give the same bits, and a restart from the
//! columns alone (the checkpoint) recomputes the same dot products, hence the same bits.

use std::collections::VecDeque;

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

/// One secant pair, with its Gram-matrix row.
#[derive(Clone, Debug)]
struct Column {
    /// Order of making (ids grow with age, newest highest).
    id: u64,
    dr: DVector<f64>,
    dxt: DVector<f64>,
    /// `dr · dr`.
    norm2: f64,
    /// `dr · dr'` for each older column `(id', dot)` alive when this one was made (and of the
    /// same length), oldest first.
    dots: Vec<(u64, f64)>,
}

impl Column {
    /// `dr · other.dr`, for an `other` older than `self`.
    fn dot_older(&self, other: &Column) -> f64 {
        match self.dots.binary_search_by_key(&other.id, |d| d.0) {
            Ok(k) => self.dots[k].1,
            Err(_) => self.dr.dot(&other.dr),
        }
    }
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
    /// Id of the next column made.
    next_id: u64,
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
            next_id: 0,
        }
    }

    /// A column from its two differences, with its dot products with every column alive.
    fn make_column(&mut self, dr: DVector<f64>, dxt: DVector<f64>) -> Column {
        let mut dots: Vec<(u64, f64)> = self
            .old
            .iter()
            .flatten()
            .chain(&self.now)
            .filter(|c| c.dr.len() == dr.len())
            .map(|c| (c.id, dr.dot(&c.dr)))
            .collect();
        dots.sort_unstable_by_key(|d| d.0);
        let id = self.next_id;
        self.next_id += 1;
        Column {
            id,
            norm2: dr.dot(&dr),
            dr,
            dxt,
            dots,
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
        // Remade oldest first, as they were made: the same dot products, the same bits.
        self.old.clear();
        self.now.clear();
        self.next_id = 0;
        let oldest_first = columns.old.iter().rev().chain([&columns.now]);
        for (k, step) in oldest_first.enumerate() {
            if k > 0 {
                let done = std::mem::take(&mut self.now);
                self.old.push_front(done);
            }
            for (dr, dxt) in step {
                let c = self.make_column(
                    DVector::from_column_slice(dr),
                    DVector::from_column_slice(dxt),
                );
                self.now.push(c);
            }
        }
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
            let (dr, dxt) = (&r - r_prev, &xt - xt_prev);
            let c = self.make_column(dr, dxt);
            self.now.push(c);
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
        // Gram–Schmidt on the Gram matrix with the QR2 filter: `rr[j]` is column j of R among
        // the kept columns (its last entry the diagonal).
        let mut rr: Vec<Vec<f64>> = Vec::new();
        let mut kept: Vec<(usize, usize)> = Vec::new();
        let mut drop: Vec<(usize, usize)> = Vec::new();
        for &at in &order {
            let c = column(self, at);
            if c.dr.len() != r.len() || c.dxt.len() != xt.len() {
                drop.push(at);
                continue;
            }
            let mut coeffs: Vec<f64> = Vec::with_capacity(kept.len() + 1);
            for (i, &newer) in kept.iter().enumerate() {
                // `kept` is newest first, so `c` is the older of the pair.
                let g = column(self, newer).dot_older(c);
                let s: f64 = (0..i).map(|l| rr[i][l] * coeffs[l]).sum();
                coeffs.push((g - s) / rr[i][i]);
            }
            let d = c.norm2 - coeffs.iter().map(|x| x * x).sum::<f64>();
            let norm0 = c.norm2.sqrt();
            let norm = d.max(0.0).sqrt();
            if !(norm0 > 0.0 && norm.is_finite() && norm >= self.filter * norm0) {
                drop.push(at);
                continue;
            }
            coeffs.push(norm);
            rr.push(coeffs);
            kept.push(at);
        }
        self.dropped += drop.len() as u32;
        let out = if kept.is_empty() {
            x.iter()
                .zip(xt)
                .map(|(x, xt)| x + self.omega0 * (xt - x))
                .collect()
        } else {
            // Normal equations RᵀR α = ΔRᵀ s, first with s = −r, then once on the residual.
            let solve = |b: &[f64]| -> Vec<f64> {
                let m = b.len();
                let mut z = vec![0.0; m];
                for i in 0..m {
                    let s: f64 = (0..i).map(|l| rr[i][l] * z[l]).sum();
                    z[i] = (b[i] - s) / rr[i][i];
                }
                let mut a = vec![0.0; m];
                for i in (0..m).rev() {
                    let s: f64 = (i + 1..m).map(|j| rr[j][i] * a[j]).sum();
                    a[i] = (z[i] - s) / rr[i][i];
                }
                a
            };
            let dr_dot = |v: &DVector<f64>| -> Vec<f64> {
                kept.iter().map(|&at| column(self, at).dr.dot(v)).collect()
            };
            let minus_r = -&r;
            let mut alpha = solve(&dr_dot(&minus_r));
            let mut s = minus_r;
            for (a, &at) in alpha.iter().zip(&kept) {
                s.axpy(-*a, &column(self, at).dr, 1.0);
            }
            for (a, d) in alpha.iter_mut().zip(solve(&dr_dot(&s))) {
                *a += d;
            }
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
    use nalgebra::DMatrix;

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

    /// Uniform numbers in [−0.5, 0.5) from a linear congruential sequence.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// `H(x) = x* + M (x − x*)` in `n` dimensions with `M = U T Uᵀ`, `U` orthonormal `n × rank`,
    /// `T` upper triangular with the eigenvalues 0.8, −0.6, 0.5, … on its diagonal: rank
    /// `rank`, not symmetric, contracting.
    fn affine(n: usize, rank: usize) -> (impl Fn(&[f64]) -> Vec<f64>, Vec<f64>) {
        let x_star: Vec<f64> = (0..n).map(|i| 0.3 + 0.1 * i as f64).collect();
        let mut rand = uniform(12345);
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
    fn the_input_is_the_least_squares_combination_of_a_householder_qr() {
        // Random columns in 40 dimensions, over two steps: next() against a dense least-squares
        // solve of ΔR α = −r by nalgebra's Householder QR, with nothing dropped.
        let n = 40;
        let mut rand = uniform(7);
        let mut vec = |scale: f64| -> Vec<f64> { (0..n).map(|_| scale * rand()).collect() };
        let mut model = IqnIls::new(1, 1e-2, 0.5);
        let (mut rs, mut xts) = (Vec::new(), Vec::new());
        for k in 0..7 {
            if k == 3 {
                model.start_step();
            }
            let (r, xt) = (vec(1.0), vec(2.0));
            model.observe(&r, &xt);
            rs.push(r);
            xts.push(xt);
        }
        // Step 1 kept its 3 trials' 2 columns; step 2 has 3 columns (its first trial starts
        // anew), and one more with the last trial.
        let (r, x, xt) = (vec(1.0), vec(1.0), vec(2.0));
        let (next, used) = model.next(&r, &x, &xt);
        assert_eq!(used, 6);
        assert_eq!(model.dropped(), 0);
        let mut dr_cols = Vec::new();
        let mut dxt_cols = Vec::new();
        let diff =
            |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(a, b)| a - b).collect() };
        for (a, b) in [(1, 0), (2, 1), (4, 3), (5, 4), (6, 5)] {
            dr_cols.push(diff(&rs[a], &rs[b]));
            dxt_cols.push(diff(&xts[a], &xts[b]));
        }
        dr_cols.push(diff(&r, &rs[6]));
        dxt_cols.push(diff(&xt, &xts[6]));
        let m = dr_cols.len();
        let a = DMatrix::from_fn(n, m, |i, j| dr_cols[j][i]);
        let b = DVector::from_iterator(n, r.iter().map(|v| -v));
        let qr = a.clone().qr();
        let qtb = qr.q().transpose() * &b;
        let alpha = qr.r().solve_upper_triangular(&qtb).expect("full rank");
        for i in 0..n {
            let want = xt[i] + (0..m).map(|j| alpha[j] * dxt_cols[j][i]).sum::<f64>();
            assert!(
                (next[i] - want).abs() <= 1e-12 * want.abs().max(1.0),
                "{i}: {} vs {want}",
                next[i]
            );
        }
    }

    #[test]
    fn restored_columns_give_the_same_bits() {
        let (h, _) = affine(6, 3);
        let mut straight = IqnIls::new(2, 1e-2, 0.5);
        solve(Some(&mut straight), &h, &[0.0; 6], 1e-12, 50);
        straight.start_step();
        let mut restored = IqnIls::new(2, 1e-2, 0.5);
        restored.restore(&straight.columns());
        let mut x = vec![0.1; 6];
        for _ in 0..4 {
            let xt = h(&x);
            let r: Vec<f64> = xt.iter().zip(&x).map(|(a, b)| a - b).collect();
            let (a, _) = straight.next(&r, &x, &xt);
            let (b, _) = restored.next(&r, &x, &xt);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a), bits(&b));
            x = a;
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
