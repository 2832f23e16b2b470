//! Pure cut-cell geometry (no IO, no clock).
