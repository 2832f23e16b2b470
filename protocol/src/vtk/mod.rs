//! VTK XML files for ParaView, built in memory: image data (`.vti`), polydata (`.vtp`) and the
//! time series that names each file's time (`.pvd`). Pure: the nodes write the bytes.
//!
//! Every array is stored in one appended block of raw binary (`encoding="raw"`), little-endian,
//! each array compressed with zlib in blocks of [`BLOCK_SIZE`] bytes and preceded by VTK's
//! compression header (`header_type="UInt64"`: the number of blocks, the block size, the size of
//! the last partial block or 0 when the last block is full, then each block's compressed size),
//! as `vtkXMLWriter` writes with `vtkZLibDataCompressor`. [`read`] decodes such files back (for
//! tests and tools); it reads what [`image_data`] and [`poly_data`] write, not every VTK file.
//!
//! ```
//! use protocol::vtk::{DataArray, ImageData, Values, image_data, read};
//! let image = ImageData {
//!     cells: [2, 1, 1],
//!     origin: [0.0; 3],
//!     spacing: [0.5, 1.0, 1.0],
//!     cell_data: vec![DataArray::scalar("rho", Values::Float64(vec![1.0, 0.125]))],
//! };
//! let bytes = image_data(&image, "two cells");
//! let file = read::parse(&bytes).unwrap();
//! assert_eq!(file.array("CellData", "rho").unwrap().as_f64(), Some(&[1.0, 0.125][..]));
//! ```

pub mod read;
mod write;

pub use write::{
    BLOCK_SIZE, DataArray, ImageData, PolyCells, PolyData, Series, Values, image_data, poly_data,
};

#[cfg(test)]
mod tests;
