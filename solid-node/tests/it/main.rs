//! Integration tests of `solid-node`, one test binary: the discrete element model (`dem_*`)
//! against exact solutions, its contact, fracture and wet surface. `dem_support` holds the
//! helpers the others share.

mod dem_cantilever;
mod dem_contact;
mod dem_determinism;
mod dem_energy;
mod dem_fracture;
mod dem_holds;
mod dem_init;
mod dem_loads;
mod dem_scene;
mod dem_spring;
mod dem_stability;
mod dem_substeps;
mod dem_support;
mod dem_top;
mod dem_walls;
mod dem_wave;
mod dem_wet;
