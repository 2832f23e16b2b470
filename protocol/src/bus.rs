//! The iceoryx2 transport (placeholder until the bus lands).
