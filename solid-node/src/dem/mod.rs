//! Pure DEM core (no IO, no clock).
