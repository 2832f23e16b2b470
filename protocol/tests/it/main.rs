//! Integration tests of `protocol`, one test binary: the codec, trials sent as their changes,
//! the scene schema and its reference, the run keys, and the iceoryx2 bus between real ends.

#[cfg(feature = "bus")]
mod bus;
mod changed_trials;
mod codec;
mod issue_11_validation;
mod run_keys;
mod scene;
mod scene_contact;
mod scene_face_inertia;
mod scene_links;
mod scene_reference;
mod scenes_dir;
mod solid_substeps;
