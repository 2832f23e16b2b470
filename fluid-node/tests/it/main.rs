//! Integration tests of `fluid-node`, one test binary: the finite-volume solver (`fv_*`), the
//! cut-cell geometry (`cutcell_*`), the embedded solid (`embedded_*`) and the outputs. The
//! `*_support` and `fv_common` modules hold the helpers the others share.

mod cutcell_2d;
mod cutcell_block;
mod cutcell_block_assemble;
mod cutcell_block_chain;
mod cutcell_cmd;
mod cutcell_degenerate;
mod cutcell_geometry;
mod cutcell_subface_swept;
mod cutcell_support;
mod cutcell_swept;
mod embedded_boundary;
mod embedded_crack;
mod embedded_hooks_block;
mod embedded_memory;
mod embedded_memory_ranks;
mod embedded_particles;
mod embedded_piston;
mod embedded_rest;
mod embedded_support;
mod embedded_thin;
mod embedded_threads;
mod embedded_uniform;
mod embedded_wall_hit;
mod embedded_withdrawn;
mod fv_accuracy;
mod fv_blocks;
mod fv_characteristic;
mod fv_common;
mod fv_conservation;
mod fv_mirror;
mod fv_ranks;
mod fv_ranks_crack;
mod fv_ranks_hooks;
mod fv_ranks_init;
mod fv_ranks_refusals;
mod fv_report;
mod fv_riemann;
mod probe_stream;
mod vtk_xml;
