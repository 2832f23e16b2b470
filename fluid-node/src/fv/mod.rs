//! Pure finite-volume core (no IO, no clock).
