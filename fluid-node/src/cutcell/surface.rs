//! The wet surface as the solid sends it (`protocol::wire::WetSurface`), borrowed.

/// A borrowed wet surface: triangles (3-D) or segments (2-D) over a shared vertex array.
///
/// Orientation: normals point out of the solid into the fluid. 3-D: right-hand rule on the vertex
/// order; 2-D: segment `a -> b` has normal `(dy, -dx)`, so closed loops run counter-clockwise
/// around the solid. The geometry is exact for any *closed* oriented surface (several bodies,
/// internal faces carried on both sides); an open surface is reported by
/// [`crate::cutcell::CutDiagnostics::max_uncut_defect`].
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    /// Spatial dimension, 2 or 3 (the grid's).
    pub dim: usize,
    /// Vertex coordinates, in m, flattened, `dim` per vertex.
    pub vertices: &'a [f64],
    /// Connectivity, `dim` vertex indices per element (triangle or segment).
    pub elements: &'a [u32],
    /// The particle each element belongs to (may be empty: particle 0).
    pub element_particle: &'a [u32],
}

impl Surface<'_> {
    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len() / self.dim.max(1)
    }

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        self.vertices.len() / self.dim.max(1)
    }

    /// Particle of element `e` (0 when no particle array is given).
    pub fn particle(&self, e: usize) -> u32 {
        self.element_particle.get(e).copied().unwrap_or(0)
    }

    /// Vertex `v` as a 3-vector (third coordinate 0 in 2-D).
    #[inline]
    pub fn vertex(&self, v: u32) -> [f64; 3] {
        let v = v as usize * self.dim;
        let mut x = [0.0; 3];
        x[..self.dim].copy_from_slice(&self.vertices[v..v + self.dim]);
        x
    }

    /// Vertices of element `e` (2 or 3 used). `None` when an index is out of range or a coordinate
    /// is not finite.
    pub fn element(&self, e: usize) -> Option<[[f64; 3]; 3]> {
        let mut out = [[0.0; 3]; 3];
        for (k, &v) in self.elements[e * self.dim..(e + 1) * self.dim]
            .iter()
            .enumerate()
        {
            if v as usize >= self.n_vertices() {
                return None;
            }
            out[k] = self.vertex(v);
            if out[k].iter().any(|x| !x.is_finite()) {
                return None;
            }
        }
        Some(out)
    }

    /// Asserts the array lengths agree (a bug in the caller otherwise).
    pub(crate) fn check(&self) {
        assert!(
            self.dim == 2 || self.dim == 3,
            "cut-cell surface dimension must be 2 or 3, got {}",
            self.dim
        );
        assert!(
            self.vertices.len().is_multiple_of(self.dim)
                && self.elements.len().is_multiple_of(self.dim),
            "surface arrays must hold {} values per vertex and per element",
            self.dim
        );
        assert!(
            self.element_particle.is_empty() || self.element_particle.len() == self.n_elements(),
            "element_particle must be empty or hold one entry per element ({} != {})",
            self.element_particle.len(),
            self.n_elements()
        );
    }
}
