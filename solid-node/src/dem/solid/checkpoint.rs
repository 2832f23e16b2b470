//! The checkpoint of a [`Solid`]: its [`State`] as bytes, and the restore that rebuilds the
//! caches from it.

use crate::dem::solid::state::{Solid, State};

/// Why a checkpoint could not be restored.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The bytes are not a checkpoint of a solid (the decoder's message).
    #[error("{0}")]
    Decode(String),
    /// The checkpoint is of a solid of another size.
    #[error(
        "checkpoint of {checkpoint_particles} particles and {checkpoint_links} links, the solid has \
         {particles} and {links}"
    )]
    Size {
        /// Particles in the checkpoint.
        checkpoint_particles: u64,
        /// Links in the checkpoint.
        checkpoint_links: u64,
        /// Particles of the solid.
        particles: usize,
        /// Links of the solid.
        links: usize,
    },
    /// The checkpoint's contact loads do not match the solid's contact (on or off).
    #[error("checkpoint has contact loads for {found} particles, the solid needs {expected}")]
    ContactLoads {
        /// Particles with contact loads in the checkpoint.
        found: usize,
        /// Particles the solid needs them for (0 without contact).
        expected: usize,
    },
}

impl Solid {
    /// The full dynamic state as bytes (`protocol::codec::encode_blob`).
    pub fn to_checkpoint(&self) -> Vec<u8> {
        protocol::codec::encode_blob(&self.state)
    }

    /// Restores a state written by [`Solid::to_checkpoint`] of a solid built from the same scene.
    pub fn restore_checkpoint(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let state: State = protocol::codec::decode_blob(bytes).map_err(CheckpointError::Decode)?;
        if state.n_particles as usize != self.n_particles()
            || state.n_links as usize != self.model.links.len()
        {
            return Err(CheckpointError::Size {
                checkpoint_particles: state.n_particles,
                checkpoint_links: state.n_links,
                particles: self.n_particles(),
                links: self.model.links.len(),
            });
        }
        let n_damping = if self.contact.is_some() {
            self.n_particles()
        } else {
            0
        };
        if state.contact_damping.len() != n_damping {
            return Err(CheckpointError::ContactLoads {
                found: state.contact_damping.len(),
                expected: n_damping,
            });
        }
        self.state = state;
        self.limit = self.stability_limit();
        self.rebuild_wet_topology();
        self.update_forces();
        self.update_wet();
        self.trial_valid = false;
        Ok(())
    }
}
