//! The predicted states the mixing groups read ([`Predicted`]), gathered from the ranks that own
//! them as the groups need them.

use super::Predicted;
use crate::fv::FluidSolver;
use crate::fv::state::extend_cell;

impl Predicted {
    /// Reads the cells of `cells` not read yet (collective: every rank computes every group in
    /// the same order, so every rank asks for the same cells).
    pub(super) fn extend(&mut self, solver: &mut FluidSolver, cells: &[usize]) {
        let mut missing: Vec<u32> = cells
            .iter()
            .map(|&c| c as u32)
            .filter(|c| self.reads.binary_search(c).is_err())
            .collect();
        if missing.is_empty() {
            return;
        }
        missing.sort_unstable();
        missing.dedup();
        let read = solver.cells_at(&missing);
        let nvar = self.nvar;
        let (mut reads, mut values) = (Vec::new(), Vec::new());
        let (mut i, mut j) = (0, 0);
        while i < self.reads.len() || j < missing.len() {
            if j == missing.len() || (i < self.reads.len() && self.reads[i] < missing[j]) {
                reads.push(self.reads[i]);
                extend_cell(&mut values, &self.values[i * nvar..(i + 1) * nvar]);
                i += 1;
            } else {
                reads.push(missing[j]);
                extend_cell(&mut values, &read[j * nvar..(j + 1) * nvar]);
                j += 1;
            }
        }
        self.reads = reads;
        self.values = values;
    }

    pub(super) fn u(&self, c: usize, q: usize) -> f64 {
        let k = self
            .reads
            .binary_search(&(c as u32))
            .expect("a mixing group reads only cells of its read set");
        self.values[k * self.nvar + q]
    }
}
