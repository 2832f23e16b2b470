//! [`WrittenRows`]: where a block geometry's computation wrote into its arrays (module
//! `block`), so that the next computation into the same buffers zeroes, and a block's share
//! reads, only that.

/// Where along each row along x of a window's arrays a computation wrote (with any value), per
/// array: Λ, then λ along x, y and z; every value of an array outside those spans is zero (its
/// arrays start from zero). What lets a block's share ([`crate::cutcell::block_part`]) read, and
/// the next computation into the same buffers zero, only those spans instead of every value of
/// the window. Empty: not known (every value may be written).
#[derive(Clone, Debug, Default)]
pub(crate) struct WrittenRows {
    /// Values per row of each array.
    row: [usize; 4],
    /// Per array and row (`j + ny k` over the array's rows), the span `lo..hi` of the row's
    /// values written (none: `lo >= hi`).
    spans: [Vec<(u32, u32)>; 4],
}

impl WrittenRows {
    /// Marks value `at` of `array` (0: Λ, 1 + axis: λ along `axis`) written.
    #[inline]
    pub(crate) fn mark(&mut self, array: usize, at: usize) {
        self.mark_range(array, at, 1);
    }

    /// Marks values `at..at + len` of `array` written (within one row).
    #[inline]
    pub(crate) fn mark_range(&mut self, array: usize, at: usize, len: usize) {
        let row = self.row[array].max(1);
        let x = (at % row) as u32;
        if let Some(s) = self.spans[array].get_mut(at / row) {
            let end = x + len as u32;
            debug_assert!(end as usize <= row, "a mark within one row");
            *s = if s.0 >= s.1 {
                (x, end)
            } else {
                (s.0.min(x), s.1.max(end))
            };
        }
    }

    /// The span of row `row` of `array` that may hold values: the one written, or the whole
    /// row when nothing was recorded.
    #[inline]
    pub(crate) fn span(&self, array: usize, row: usize) -> std::ops::Range<usize> {
        match self.spans[array].get(row) {
            Some(&(lo, hi)) if lo < hi => lo as usize..hi as usize,
            Some(_) => 0..0,
            None => 0..self.row[array],
        }
    }

    /// Zeroes every value of `arrays` (Λ, then λ along x, y and z, as recorded) that may be
    /// non-zero, so that all of them are zero: the spans recorded as written, or the whole
    /// array where nothing was recorded.
    pub(crate) fn zero_written(&self, arrays: [&mut Vec<f64>; 4]) {
        for (a, values) in arrays.into_iter().enumerate() {
            let row = self.row[a].max(1);
            if self.spans[a].is_empty() {
                values.fill(0.0);
                continue;
            }
            for (r, &(lo, hi)) in self.spans[a].iter().enumerate() {
                if lo >= hi {
                    continue;
                }
                let end = (r * row + hi as usize).min(values.len());
                values[(r * row + lo as usize).min(end)..end].fill(0.0);
            }
        }
    }

    /// None written yet, for arrays of `row[a]` values per row and `rows[a]` rows each
    /// (buffers reused).
    pub(crate) fn reset(&mut self, row: [usize; 4], rows: [usize; 4]) {
        self.row = row;
        for (m, n) in self.spans.iter_mut().zip(rows) {
            m.clear();
            m.resize(n, (0, 0));
        }
    }

    /// Values per row of `array`.
    pub(crate) fn row_len(&self, array: usize) -> usize {
        self.row[array]
    }
}
