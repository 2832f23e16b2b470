//! TEMPORARY stand-in until the sub-face prisms land (element prisms split by area).
#![allow(missing_docs)]
use crate::cutcell::{CutGeometry, Surface, SweptVolumes, swept_volumes};
use crate::grid::Grid;

#[derive(Clone, Copy, Debug)]
pub struct SubfaceSweptEntry {
    pub subface: u32,
    pub cell: u32,
    pub volume: f64,
}

#[derive(Default)]
pub struct SubfaceSwept {
    pub entries: Vec<SubfaceSweptEntry>,
    inner: SweptVolumes,
}

impl SubfaceSwept {
    pub fn new() -> Self {
        Self::default()
    }
}

pub fn subface_swept_volumes(
    grid: &Grid,
    before: &Surface,
    after: &Surface,
    g: &CutGeometry,
    out: &mut SubfaceSwept,
) {
    swept_volumes(grid, before, after, &mut out.inner);
    out.entries.clear();
    let ne = after.n_elements();
    let mut area = vec![0.0; ne];
    for s in &g.subfaces {
        area[s.element as usize] += s.area;
    }
    for (i, s) in g.subfaces.iter().enumerate() {
        for e in out.inner.entries.iter().filter(|e| e.element == s.element) {
            out.entries.push(SubfaceSweptEntry {
                subface: i as u32,
                cell: e.cell,
                volume: e.volume * s.area / area[s.element as usize],
            });
        }
    }
}
